#!/usr/bin/env bash
# End-to-end test of slam_mms_merge (issue 24; registered in tests/CMakeLists.txt):
#   slam_mms_merge_test.sh SLAM_MMS_MERGE SLAM_MMS_RUN SLAM_MMS_SIM
# One short simulated drive, run twice by slam_mms_run --drive-result with different GNSS outages
# (two drives of one street with their own outage drift), merged: the overlaps are found and
# accepted, the offset between the drives where they overlap shrinks to <= 3 cm, the merged map is
# sharper than the union of the two maps, every drive's ATE and outage error are reported against
# the simulator's ground truth, each accepted overlap's registration error against the truth is
# written and small; the outputs exist; a folder without a drive result, an unwritable --out and an unknown --log-level fail with a message naming them.
set -uo pipefail
merge=$1
run=$2
sim=$3
tmp=$(mktemp -d "${TMPDIR:-/tmp}/slam_mms_merge_test.XXXXXX")
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }

"$sim" --scenario demo --seed 5 --duration 24 --out "$tmp/sim" --no-scene-cloud >"$tmp/sim.log" 2>&1 ||
  { cat "$tmp/sim.log"; fail "slam_mms_sim"; }
drive=$(ls -d "$tmp"/sim/*/*_sync | head -n1)
[[ -d $drive ]] || fail "no simulated drive in $tmp/sim"
for spec in "a 3:12" "b 12:10"; do
  set -- $spec
  timeout 300 "$run" --kitti-raw "$drive" --mode full --drive-result --gnss-outage "$2" \
    --out "$tmp/$1" >"$tmp/$1.log" 2>&1 || { tail -20 "$tmp/$1.log"; fail "slam_mms_run $1"; }
  [[ -s $tmp/$1/drive_result/drive_result.json ]] || fail "no drive result in $tmp/$1"
  grep -q "drive result:" "$tmp/$1.log" || fail "slam_mms_run did not report the drive result"
done

timeout 300 "$merge" --drive "$tmp/a" --drive "$tmp/b" --out "$tmp/m" >"$tmp/m.log" 2>&1 ||
  { cat "$tmp/m.log"; fail "slam_mms_merge"; }
cat "$tmp/m.log"
for f in report.json georef.json overlaps.csv a.tum b.tum a_before.tum map/index.json; do
  [[ -s $tmp/m/merged/$f ]] || fail "no merged/$f"
done
python3 - "$tmp/m/merged/report.json" <<'PY' || fail "merged report"
import json, sys
r = json.load(open(sys.argv[1]))
o = r["overlaps"]
assert o["accepted"] >= 2, o
off = r["overlap_offset_m"]
assert off["after"] <= 0.03 and off["after"] < off["before"], off
# ATE and outage errors are measured and reported (not asserted: issue 24's "no drive worse"
# target is not met on every drive yet, docs/merge.md).
for d in r["drives"]:
    assert d["ground_truth"] == "simulator", d
    for k in ("ate_before_m", "ate_after_m", "max_outage_err_before_m", "max_outage_err_after_m"):
        assert isinstance(d[k], float) and d[k] >= 0.0, (k, d)
e = r["map_entropy"]
assert e["merged"] < e["union_before"], e
print("merged report ok:", off, e)
PY
# overlaps.csv: each accepted registration with its error against the true relative pose (both
# drives have ground truth): present, and small for a registration the adjustment accepted.
python3 - "$tmp/m/merged/overlaps.csv" <<'PY' || fail "overlaps.csv"
import csv, math, sys
rows = list(csv.DictReader(open(sys.argv[1])))
acc = [r for r in rows if r["accepted"] == "1"]
assert acc, "no accepted overlap"
for r in acc:
    e = [float(r[k]) for k in ("truth_err_e_m", "truth_err_n_m", "truth_err_u_m")]
    assert all(math.isfinite(float(r[k])) for k in ("x_m", "y_m", "z_m", "rx_deg", "ry_deg", "rz_deg")), r
    assert math.hypot(*e) < 0.15 and float(r["truth_err_deg"]) < 0.5, r
    assert float(r["truth_chi2"]) >= 0.0, r
print("overlaps.csv ok:", len(acc), "accepted, truth error max %.3f m" %
      max(math.hypot(float(r["truth_err_e_m"]), float(r["truth_err_n_m"]), float(r["truth_err_u_m"])) for r in acc))
PY

# A folder without a drive result; an unwritable --out.
"$merge" --drive "$tmp/a" --drive "$tmp/sim" --out "$tmp/m2" >"$tmp/bad.log" 2>&1
[[ $? -eq 1 ]] || fail "a folder without a drive result must exit 1"
grep -q "drive_result.json" "$tmp/bad.log" || fail "the error must name drive_result.json"
touch "$tmp/file"
"$merge" --drive "$tmp/a" --drive "$tmp/b" --out "$tmp/file/x" >"$tmp/unw.log" 2>&1
[[ $? -eq 1 ]] || fail "an unwritable --out must exit 1"
grep -q "\-\-out" "$tmp/unw.log" || fail "the error must name --out"
"$merge" --drive "$tmp/a" --drive "$tmp/b" --out "$tmp/m3" --log-level chatty >"$tmp/lvl.log" 2>&1
[[ $? -eq 2 ]] || fail "--log-level chatty: expected exit status 2"
grep -q -- "--log-level chatty: expected debug, info, warning or error" "$tmp/lvl.log" ||
  fail "--log-level message: $(cat "$tmp/lvl.log")"
echo "PASS"
