#!/usr/bin/env bash
# Installs the Debian packages slam_mms needs, builds it (Release, -j2) and runs the main job,
# slam_mms_run, printing progress and writing trajectories, maps, report.json and plots.
#   scripts/demo.sh                          # simulate the demo drive (~60 s: one block, four turns, a
#                                            # revisit of its first street) with a 30 s GNSS outage
#                                            # (15..45 s), map it with every method
#   scripts/demo.sh --kitti-raw DRIVE_DIR    # a real KITTI raw drive (e.g. ../shared/data/kitti_raw/...)
#   scripts/demo.sh --folder DIR | --rosbag FILE.bag --extrinsics FILE.yaml
#   scripts/demo.sh --out DIR ...            # output folder (default: out/demo); other options pass on
#                                            # (--keep-sim keeps the simulated drive, ~1.4 GB)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-2}

out="out/demo"
args=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --out) out="$2"; shift 2 ;;
    --out=*) out="${1#--out=}"; shift ;;
    *) args+=("$1"); shift ;;
  esac
done
has_mode=0 has_input=0 has_outage=0
for a in "${args[@]+"${args[@]}"}"; do
  case "$a" in
    --mode | --mode=*) has_mode=1 ;;
    --kitti-raw | --kitti-raw=* | --folder | --folder=* | --rosbag | --rosbag=*) has_input=1 ;;
    --gnss-outage | --gnss-outage=*) has_outage=1 ;;
  esac
done
if [[ $has_mode -eq 0 ]]; then args+=(--mode all); fi
# The simulated demo drive shows what the system is for: mapping through a GNSS outage.
if [[ $has_input -eq 0 && $has_outage -eq 0 ]]; then args+=(--gnss-outage 15:30); fi

scripts/install_deps.sh
# The same configuration as scripts/test.sh (tests, apps and benchmarks on), so the two scripts can
# share build/ in either order; only the app is built here.
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DSLAM_MMS_BUILD_TESTS=ON \
  -DSLAM_MMS_BUILD_EXAMPLES=ON -DSLAM_MMS_BUILD_BENCHMARKS=ON ${CMAKE_ARGS:-}
cmake --build "$BUILD_DIR" -j"$JOBS" --target slam_mms_run
mkdir -p "$out"
"$BUILD_DIR/examples/slam_mms_run" --out "$out" "${args[@]}"
echo "[demo] outputs in $out ($(du -sh "$out" | cut -f1)); open $out/report.html first:"
ls "$out"
