#!/usr/bin/env bash
# The GPU measurements of issue 20 on a machine with an NVIDIA (or other EGL-capable) GPU, from an
# existing Release build: the EGL renderer's tests (same images as the CPU renderer), the render
# micro-benchmarks (CPU vs EGL) and the end-to-end benchmark on a simulated drive with each
# renderer and thread count, old-style alternated (each configuration REPEAT times, interleaved).
#
#   benchmarks/gpu_bench.sh [BUILD_DIR] [OUT_DIR]
#   env: DURATION_S (30), REPEAT (2), THREADS ("2 $(nproc)"), MODES ("full lidar_only"),
#        SIM_DIR (OUT_DIR/sim, reused when it holds the same drive)
#
# Writes OUT_DIR/e2e_<mode>_<renderer>_t<threads>_<rep>.json, OUT_DIR/bm_render.json and
# OUT_DIR/summary.md (a table of medians). Needs no data folder (the drive is simulated).
set -uo pipefail
BUILD=${1:-build}
OUT=${2:-gpu_bench_out}
DURATION_S=${DURATION_S:-30}
REPEAT=${REPEAT:-2}
THREADS=${THREADS:-"2 $(nproc)"}
MODES=${MODES:-"full lidar_only"}
SIM_DIR=${SIM_DIR:-$OUT/sim}
mkdir -p "$OUT" "$SIM_DIR"
E2E=$BUILD/benchmarks/slam_mms_bench_e2e
[[ -x $E2E ]] || E2E=$BUILD/slam_mms_bench_e2e
BM=$BUILD/benchmarks/slam_mms_benchmarks
EGL_TEST=$BUILD/tests/render_egl_egl_surfel_renderer_test

echo "== machine"
nproc
command -v nvidia-smi >/dev/null &&
  nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm --format=csv

echo "== EGL renderer tests"
if [[ -x $EGL_TEST ]]; then
  "$EGL_TEST" 2>&1 | tail -n 15
else
  echo "no $EGL_TEST"
fi

echo "== render micro-benchmarks"
if [[ -x $BM ]]; then
  "$BM" --benchmark_filter='BM_Render(Cpu|Egl)' --benchmark_repetitions=3 \
    --benchmark_report_aggregates_only=true --benchmark_out="$OUT/bm_render.json" \
    --benchmark_out_format=json 2>&1 | grep -E 'median|skip|error|Error' || true
fi

echo "== simulated drive (${DURATION_S} s)"
"$E2E" --duration-s "$DURATION_S" --sim-dir "$SIM_DIR" --mode gnss_ins --rss-samples 2 \
  >"$OUT/sim.log" 2>&1
grep -E '^\[sim\]' "$OUT/sim.log"

echo "== end to end"
for rep in $(seq 1 "$REPEAT"); do
  for mode in $MODES; do
    for t in $THREADS; do
      for r in cpu egl; do
        json=$OUT/e2e_${mode}_${r}_t${t}_${rep}.json
        "$E2E" --duration-s "$DURATION_S" --sim-dir "$SIM_DIR" --mode "$mode" --renderer "$r" \
          --threads "$t" --out "$json" >"${json%.json}.log" 2>&1 || echo "FAILED: $json"
        python3 - "$json" <<'EOF' || true
import json, sys
j = json.load(open(sys.argv[1]))
st = j["stages_ms"]
print(f'{j["mode"]:10s} {j["renderer"]:28s} t{j["threads"]:<3d} '
      f'{j["scans_per_s_without_reading"]:7.2f} scans/s  render {st["render"]["median"]:6.2f} '
      f'integrate {st["integrate"]["median"]:6.2f} level-1 {st["level-1 total"]["median"]:6.2f} ms')
EOF
      done
    done
  done
done

python3 - "$OUT" "$DURATION_S" <<'EOF'
import glob, json, os, statistics, sys
out, duration = sys.argv[1], float(sys.argv[2])
rows = {}
for f in sorted(glob.glob(os.path.join(out, "e2e_*.json"))):
    j = json.load(open(f))
    key = (j["mode"], j["renderer"], j["threads"])
    rows.setdefault(key, []).append(j)
lines = ["| mode | renderer | threads | runs | scans/s (w/o reading) | x real time | render ms | "
         "integrate ms | register ms | deskew ms | level-1 ms |",
         "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
for (mode, renderer, threads), js in sorted(rows.items()):
    med = lambda f: statistics.median(f(j) for j in js)
    sps = med(lambda j: j["scans_per_s_without_reading"])
    real = sps / (js[0]["scans_processed"] / js[0]["drive_s"])
    stage = lambda s: med(lambda j: j["stages_ms"][s]["median"])
    lines.append(f"| {mode} | {renderer} | {threads} | {len(js)} | {sps:.2f} | {real:.2f} | "
                 f"{stage('render'):.2f} | {stage('integrate'):.2f} | {stage('register'):.2f} | "
                 f"{stage('deskew'):.2f} | {stage('level-1 total'):.2f} |")
open(os.path.join(out, "summary.md"), "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
EOF
