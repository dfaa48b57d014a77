#!/usr/bin/env bash
# Installs the slam_mms Python package into a virtual environment, offline:
#   scripts/install_python.sh [VENV]          # default VENV: .venv
# 1. Debian packages (scripts/install_deps.sh: toolchain, libraries, pybind11-dev, python3-numpy,
#    python3-pytest, python3-venv, python3-matplotlib, ...);
# 2. builds the extension module (CMake target _slam_mms in $BUILD_DIR, default build/, Release);
# 3. creates VENV with --system-site-packages (Debian's numpy/matplotlib/pytest are used) from
#    /usr/bin/python3, the interpreter the Debian packages are for;
# 4. pip install --no-build-isolation --no-deps ./python (no network: the built module is copied);
# 5. checks: VENV/bin/python -c "import slam_mms; print(slam_mms.__version__)".
set -euo pipefail
cd "$(dirname "$0")/.."
VENV=$(realpath -m "${1:-.venv}")
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-2}
PYTHON=${PYTHON:-/usr/bin/python3}

scripts/install_deps.sh
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DSLAM_MMS_BUILD_PYTHON=ON \
      -DPython_EXECUTABLE="$PYTHON" ${CMAKE_ARGS:-}
cmake --build "$BUILD_DIR" -j"$JOBS" --target _slam_mms
MODULE=$(ls "$BUILD_DIR"/python/_slam_mms*.so 2>/dev/null | head -n1 || true)
if [[ -z "$MODULE" ]]; then
  echo "[install_python] $BUILD_DIR/python/_slam_mms*.so was not built (see the CMake output)" >&2
  exit 1
fi

if [[ ! -x "$VENV/bin/python" ]]; then
  "$PYTHON" -m venv --system-site-packages "$VENV"
fi
SLAM_MMS_PYTHON_MODULE="$(realpath "$MODULE")" PIP_NO_INDEX=1 \
  "$VENV/bin/python" -m pip install --no-build-isolation --no-deps --no-index --upgrade ./python
# Checked outside the source tree, so that the installed package (not python/) is imported.
(cd / && "$VENV/bin/python" -c "import slam_mms; print(slam_mms.__version__)")
echo "[install_python] installed into $VENV: source $VENV/bin/activate"
