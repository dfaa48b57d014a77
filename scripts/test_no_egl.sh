#!/usr/bin/env bash
# The build variant without the EGL renderer (SLAM_MMS_WITH_EGL=OFF; issue #19): the library, the
# SDK consumer and the unit tests of the modules the renderer choice reaches (surfel, registration,
# pipeline), in their own build folder. CI runs it after scripts/test.sh.
#   scripts/test_no_egl.sh                  # BUILD_DIR=build-no-egl, JOBS=2
#   BUILD_DIR=build-x scripts/test_no_egl.sh -R Factory   # extra arguments go to ctest
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build-no-egl}
JOBS=${JOBS:-2}

scripts/install_deps.sh
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DSLAM_MMS_WITH_EGL=OFF \
  -DSLAM_MMS_BUILD_TESTS=ON -DSLAM_MMS_BUILD_EXAMPLES=OFF -DSLAM_MMS_BUILD_BENCHMARKS=OFF \
  -DSLAM_MMS_BUILD_PYTHON=OFF ${CMAKE_ARGS:-}
if grep -q "^SLAM_MMS_WITH_EGL:BOOL=ON" "$BUILD_DIR/CMakeCache.txt"; then
  echo "test_no_egl: $BUILD_DIR was configured with EGL" >&2
  exit 1
fi
# Every library module built in this configuration (each slam_mms_add_module of the top
# CMakeLists.txt whose target exists: no render_egl here, rosbag where found), the surfel,
# registration and pipeline unit tests; the consumer builds against the installed tree in its
# ctest.
help=$(cmake --build "$BUILD_DIR" --target help)
targets=()
for m in $(grep -oE "slam_mms_add_module\(\s*\w+" CMakeLists.txt | sed -E 's/.*\(\s*//'); do
  if grep -q "slam_mms_$m\$" <<<"$help"; then
    targets+=("slam_mms_$m")
  fi
done
tests=$(cd tests && ls surfel/*_test.cpp registration/*_test.cpp pipeline/*_test.cpp |
        sed -E 's#/#_#; s#\.cpp$##')
cmake --build "$BUILD_DIR" -j"$JOBS" --target "${targets[@]}" $tests
cd "$BUILD_DIR"
ctest -j"$JOBS" --output-on-failure --timeout 900 -L "surfel|registration|pipeline|consumer|layering" "$@"
