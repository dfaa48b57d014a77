#!/usr/bin/env bash
# Builds the libFuzzer targets of fuzz/ with clang (ASan + UBSan) and runs each for a while, starting
# from the committed corpus fuzz/corpus/<target>/ (copied: new inputs go to the work folder, the
# committed corpus stays small and synthetic).
#   scripts/fuzz.sh                      # every target, 60 s each
#   FUZZ_SECONDS=20 scripts/fuzz.sh      # the short CI run
#   scripts/fuzz.sh oxts calib           # some targets
# Env: BUILD_DIR (build-fuzz), FUZZ_SECONDS (60), FUZZ_WORK (build-fuzz/fuzz-work), JOBS (2).
# A crash stops with exit 1; its input is left in $FUZZ_WORK/<target>/crash-* (reproduce with
# $BUILD_DIR/fuzz/fuzz_<target> <file>). Prints one summary line per target: executions, exec/s,
# coverage, corpus size.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD_DIR=${BUILD_DIR:-build-fuzz}
FUZZ_SECONDS=${FUZZ_SECONDS:-60}
FUZZ_WORK=${FUZZ_WORK:-$BUILD_DIR/fuzz-work}
JOBS=${JOBS:-2}
TARGETS=("$@")
if [[ ${#TARGETS[@]} -eq 0 ]]; then TARGETS=(kitti_scan oxts timestamps calib trajectory pcd csv nmea); fi

SLAM_MMS_WITH_CLANG=1 scripts/install_deps.sh
CC=clang CXX=clang++ cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g" \
  -DSLAM_MMS_BUILD_FUZZERS=ON -DSLAM_MMS_BUILD_TESTS=OFF -DSLAM_MMS_BUILD_EXAMPLES=OFF \
  -DSLAM_MMS_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$BUILD_DIR" -j"$JOBS" --target "${TARGETS[@]/#/fuzz_}"

export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
status=0
for t in "${TARGETS[@]}"; do
  work="$FUZZ_WORK/$t"
  mkdir -p "$work/corpus"
  cp -n fuzz/corpus/"$t"/* "$work/corpus/" 2>/dev/null || true
  log="$work/fuzz.log"
  set +e
  (cd "$work" && "$OLDPWD/$BUILD_DIR/fuzz/fuzz_$t" -max_total_time="$FUZZ_SECONDS" -max_len=4096 \
     -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 corpus >"fuzz.log" 2>&1)
  rc=$?
  set -e
  execs=$(grep -m1 'stat::number_of_executed_units' "$log" | awk '{print $2}')
  cov=$(grep -E '^#[0-9]+' "$log" | tail -1 | grep -oE 'cov: [0-9]+' || true)
  corpus=$(find "$work/corpus" -type f | wc -l)
  echo "[fuzz] $t: rc=$rc execs=${execs:-?} exec/s=$(( ${execs:-0} / FUZZ_SECONDS )) ${cov} corpus=$corpus (${FUZZ_SECONDS} s)"
  if [[ $rc -ne 0 ]]; then
    echo "[fuzz] $t FAILED; last lines of $log:"
    tail -40 "$log"
    status=1
  fi
done
exit $status
