#!/usr/bin/env bash
# The paper's experiments (Li et al. 2020, §6), one command each; see docs/results.md.
#
#   scripts/experiments/paper_experiments.sh table1 [--duration S] [--sequences "00 01 ..."]
#                                                [--out DIR]
#       Table 1 analogue: full vs gnss_ins vs lidar_only on simulated drives along the real motion
#       of KITTI odometry sequences 00-10 (03 is not in the data), each cut to S seconds (default
#       40), with the simulator's scene map for the ground-truth map entropy (Fig. 10 analogue).
#   scripts/experiments/paper_experiments.sh table2 [--duration S] [--outage-start S]
#                                                [--lengths "5 10 ..."] [--out DIR]
#       Table 2 analogue: sequence-07 motion with GNSS outages of 5..60 s, in full mode; the
#       largest error inside each outage before (level 1 only) and after level-2 refinement.
#   scripts/experiments/paper_experiments.sh kitti [--out DIR]
#       The real KITTI frames in ../shared/data (OXTS as ground truth), without and with an
#       injected 3 s outage.
#   Every experiment also takes --config FILE (passed to every slam_mms_run) and --sim-dir DIR
#   (simulated drives are read from / written to DIR instead of the experiment's own folder, so
#   that two configurations run on the same drives).
#
# Needs a build (BUILD_DIR, default build) with the apps, python3, and ../shared/data (read only;
# it is CC BY-NC-SA: never copy it into the repository). Results: DIR/<experiment>/..., and a
# Markdown table DIR/<experiment>.md.
set -euo pipefail
cd "$(dirname "$0")/../.."
ROOT=$(pwd)
BUILD_DIR=${BUILD_DIR:-build}
DATA=${SLAM_MMS_DATA:-$ROOT/../shared/data}
EXP=${1:-}
shift || true
OUT=experiments_out
CONFIG=()
SIM_DIR=""
DURATION=""
OUTAGE_START=20
LENGTHS="5 10 15 20 25 30 40 50 60"
SEQUENCES="00 01 02 04 05 06 07 08 09 10"
while [ $# -gt 0 ]; do
  case "$1" in
    --out) OUT=$2; shift 2 ;;
    --duration) DURATION=$2; shift 2 ;;
    --outage-start) OUTAGE_START=$2; shift 2 ;;
    --lengths) LENGTHS=$2; shift 2 ;;
    --sequences) SEQUENCES=$2; shift 2 ;;
    --config) CONFIG=(--config "$2"); shift 2 ;;
    --sim-dir) SIM_DIR=$2; shift 2 ;;
    *) echo "unknown argument: $1" >&2; exit 2 ;;
  esac
done
SIM=$BUILD_DIR/examples/slam_mms_sim
RUN=$BUILD_DIR/examples/slam_mms_run
EVAL=$BUILD_DIR/examples/slam_mms_eval
for b in "$SIM" "$RUN" "$EVAL"; do
  [ -x "$b" ] || { echo "missing $b: build first (scripts/test.sh or cmake --build $BUILD_DIR)" >&2; exit 1; }
done
[ -d "$DATA/kitti_oxts" ] || { echo "no $DATA/kitti_oxts: the experiments need ../shared/data" >&2; exit 1; }
mkdir -p "$OUT"
SUMMARIZE="python3 $ROOT/scripts/experiments/summarize.py"

declare -A SEQ_DRIVE=([00]=2011_10_03_drive_0027 [01]=2011_10_03_drive_0042 [02]=2011_10_03_drive_0034
  [04]=2011_09_30_drive_0016 [05]=2011_09_30_drive_0018 [06]=2011_09_30_drive_0020
  [07]=2011_09_30_drive_0027 [08]=2011_09_30_drive_0028 [09]=2011_09_30_drive_0033
  [10]=2011_09_30_drive_0034)

simulate() {  # seq duration out_dir [extra args]
  local seq=$1 duration=$2 dir=$3
  shift 3
  if [ ! -d "$dir" ]; then
    echo "== simulating sequence $seq motion (${SEQ_DRIVE[$seq]}), $duration s -> $dir" >&2
    "$SIM" --oxts "$DATA/kitti_oxts/${SEQ_DRIVE[$seq]}_sync.tar.gz" --seed 1 --duration "$duration" \
      --out "$dir" "$@" >&2
  fi
  ls -d "$dir"/*/*_sync | head -1
}

case "$EXP" in
  table1)
    D=${DURATION:-40}
    for seq in $SEQUENCES; do
      drive=$(simulate "$seq" "$D" "${SIM_DIR:-$OUT/table1}/seq$seq/sim")
      echo "== sequence $seq: slam_mms_run --mode all"
      "$RUN" --kitti-raw "$drive" --out "$OUT/table1/seq$seq/run" --mode all "${CONFIG[@]}" || true
    done
    $SUMMARIZE table1 "$OUT/table1" > "$OUT/table1.md"
    cat "$OUT/table1.md"
    ;;
  table2)
    D=${DURATION:-100}
    drive=$(simulate 07 "$D" "${SIM_DIR:-$OUT/table2}/sim" --no-scene-cloud)
    for L in $LENGTHS; do
      dir="$OUT/table2/outage_$L"
      echo "== sequence 07, GNSS outage ${OUTAGE_START}:$L"
      "$RUN" --kitti-raw "$drive" --out "$dir" --mode full --gnss-outage "$OUTAGE_START:$L" \
        "${CONFIG[@]}" || true
      "$EVAL" --gt "$dir/ground_truth.tum" --est "level1=$dir/full_level1.tum" \
        --est "level2=$dir/full.tum" --outage "$OUTAGE_START:$L" --segments short \
        --json "$dir/before_after.json" > "$dir/before_after.txt" || true
    done
    $SUMMARIZE table2 "$OUT/table2" > "$OUT/table2.md"
    cat "$OUT/table2.md"
    ;;
  kitti)
    drive="$DATA/kitti_raw/2011_09_26/2011_09_26_drive_0013_sync"
    [ -d "$drive" ] || { echo "no $drive" >&2; exit 1; }
    "$RUN" --kitti-raw "$drive" --out "$OUT/kitti/no_outage" --mode all "${CONFIG[@]}" || true
    "$RUN" --kitti-raw "$drive" --out "$OUT/kitti/outage_1_3" --mode all --gnss-outage 1:3 \
      "${CONFIG[@]}" || true
    $SUMMARIZE kitti "$OUT/kitti" > "$OUT/kitti.md"
    cat "$OUT/kitti.md"
    ;;
  *)
    sed -n 2,20p "$0"
    exit 2
    ;;
esac
