#!/bin/bash
# slam_mms_sim_realism end to end on the real KITTI frames (exit 77 = skipped without them):
# the report is written, every statistic is there, and the ICP-only odometry is sane on both
# drives (t_rel under 5 % on 10-50 m segments: an oscillating de-skew loop gave 10 %).
set -u
APP=$1
SRC=$2
DRIVE="$SRC/../shared/data/kitti_raw/2011_09_26/2011_09_26_drive_0013_sync"
if [ ! -d "$DRIVE" ]; then
  echo "skipped: $DRIVE not found (the test needs ../shared/data)"
  exit 77
fi
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
"$APP" --real "$DRIVE" --out "$OUT" --no-lidar-only --scan-stride 5 --threads 2 > "$OUT/log" 2>&1 ||
  { cat "$OUT/log"; echo "FAIL: exit status $?"; exit 1; }
for f in report.json report.md scan_statistics.png scans.png real_icp_only.tum sim_icp_only.tum; do
  [ -s "$OUT/$f" ] || { echo "FAIL: $f missing"; exit 1; }
done
python3 - "$OUT/report.json" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
assert len(r["scan_statistics"]) == 12, r["scan_statistics"]
assert r["real"]["scans"] == 50 and r["sim"]["scans"] == 50, (r["real"], r["sim"])
icp = r["odometry"]["icp_only"]
for k in ("real", "sim"):
    t = icp[k]["t_rel_pct"]
    assert 0.0 < t < 5.0, (k, t)
# Like for like against each drive's own OXTS, recorded and velocity-integrated positions.
for ref in ("against_oxts", "against_oxts_velocity"):
    for k in ("real", "sim"):
        t = r["odometry"][ref]["icp_only"][k]["t_rel_pct"]
        assert 0.0 < t < 5.0, (ref, k, t)
# The real drive's OXTS is its ground truth: the same numbers against its recorded positions.
assert r["odometry"]["against_oxts"]["icp_only"]["real"] == icp["real"], r["odometry"]["against_oxts"]
inc = r["increments_vs_oxts_velocity"]
for k in ("real", "sim"):
    for track in ("OXTS positions", "ICP-only"):
        a = inc[k][track]
        assert a["windows"] > 0 and 8.0 < a["mean_distance_m"] < 15.0, (k, track, a)
a = {k: inc[k]["OXTS positions"] for k in ("real", "sim")}
e = r["ground_truth_map_entropy"]
assert e["real"] < 0 and e["sim"] < 0, e
print("ok: icp t_rel real %.3f sim %.3f; OXTS position vs velocity RMS real %.2f %% sim %.2f %%" %
      (icp["real"]["t_rel_pct"], icp["sim"]["t_rel_pct"], a["real"]["rms_pct"], a["sim"]["rms_pct"]))
PY
