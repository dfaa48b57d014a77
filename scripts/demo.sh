#!/usr/bin/env bash
# Installs the Debian packages slam_mms needs, builds it (Release, -j2) and runs the main job,
# slam_mms_run, printing progress and writing trajectories, maps, report.json and plots.
#   scripts/demo.sh                          # simulate the embedded default drive, map it (all methods)
#   scripts/demo.sh --kitti-raw DRIVE_DIR    # a real KITTI raw drive (e.g. ../shared/data/kitti_raw/...)
#   scripts/demo.sh --out DIR ...            # output folder (default: out/demo); other options pass on
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-2}

out="out/demo"
args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    *) args+=("$1"); shift ;;
  esac
done
has_mode=0
for a in "${args[@]+"${args[@]}"}"; do [[ "$a" == "--mode" ]] && has_mode=1; done
if [[ $has_mode -eq 0 ]]; then args+=(--mode all); fi

scripts/install_deps.sh
# The same configuration as scripts/test.sh (tests, apps and benchmarks on), so the two scripts can
# share build/ in either order; only the app is built here.
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DSLAM_MMS_BUILD_TESTS=ON \
  -DSLAM_MMS_BUILD_EXAMPLES=ON -DSLAM_MMS_BUILD_BENCHMARKS=ON ${CMAKE_ARGS:-}
cmake --build "$BUILD_DIR" -j"$JOBS" --target slam_mms_run
mkdir -p "$out"
"$BUILD_DIR/examples/slam_mms_run" --out "$out" "${args[@]}"
echo "[demo] outputs in $out:"
ls "$out"
