#!/usr/bin/env python3
"""Markdown tables from the outputs of scripts/experiments/paper_experiments.sh.

  summarize.py table1 DIR   DIR/seqXX/run/report.json -> Table 1 (+ Fig. 10 map entropy)
  summarize.py table2 DIR   DIR/outage_L/{report.json,before_after.json} -> Table 2
  summarize.py kitti DIR    DIR/*/report.json -> the real-frame runs
"""
import json
import os
import sys

METHODS = ["full", "gnss_ins", "lidar_only"]


def fmt(v, d=3):
    return "-" if v is None else f"{v:.{d}f}"


def load(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def methods_table(rows):
    """rows: [(label, report)] -> ATE / rotation / relative error / MME / speed per method."""
    out = ["| run | method | ATE [m] | rot RMSE [deg] | t_rel [%] | r_rel [deg/100 m] | "
           "max err in outage [m] | MME | GT map MME | scans/s | peak RSS [MB] |",
           "|---|---|---|---|---|---|---|---|---|---|---|"]
    for label, rep in rows:
        if rep is None:
            out.append(f"| {label} | (no report) | | | | | | | | | |")
            continue
        gt_mme = rep.get("ground_truth_map", {}).get("mme")
        for m in METHODS:
            r = rep["methods"].get(m)
            if r is None:
                continue
            out.append(
                f"| {label} | {m} | {fmt(r['ate_rmse_m'])} | {fmt(r['rot_rmse_deg'])} | "
                f"{fmt(r['t_rel_pct'])} | {fmt(r['r_rel_deg_per_100m'])} | "
                f"{fmt(r['max_pos_err_in_outage_m'])} | {fmt(r['mme'])} | {fmt(gt_mme)} | "
                f"{fmt(r['scans_per_s'], 1)} | {fmt(r['peak_rss_mb'], 0)} |")
    return out


def ratio_lines(rows):
    out = []
    for label, rep in rows:
        if rep is None:
            continue
        m = rep["methods"]
        if "full" in m and "lidar_only" in m and m["full"]["ate_rmse_m"] > 0:
            out.append(f"- {label}: lidar_only ATE / full ATE = "
                       f"{m['lidar_only']['ate_rmse_m'] / m['full']['ate_rmse_m']:.1f}x; "
                       f"full ATE <= gnss_ins ATE: "
                       f"{m['full']['ate_rmse_m'] <= m.get('gnss_ins', {}).get('ate_rmse_m', 1e9)}; "
                       f"full MME < gnss_ins MME: "
                       f"{m['full']['mme'] < m.get('gnss_ins', {}).get('mme', 1e9)}")
    return out


def table1(d):
    rows = []
    for seq in sorted(os.listdir(d)):
        rep = load(os.path.join(d, seq, "run", "report.json"))
        if rep is not None:
            label = f"{seq} ({rep['input']['scans']} scans, {rep['input']['duration_s']:.0f} s)"
        else:
            label = seq
        rows.append((label, rep))
    return "\n".join(["## Table 1 analogue (and Fig. 10: MME per method and of the ground-truth map)",
                      ""] + methods_table(rows) + [""] + ratio_lines(rows)) + "\n"


def table2(d):
    out = ["## Table 2 analogue: sequence-07 motion, GNSS outages, full mode", "",
           "| outage [s] | max pos err, level 1 only [m] | max pos err, after level 2 [m] | "
           "max rot err, level 1 [deg] | max rot err, after level 2 [deg] | "
           "RMS pos err after level 2 [m] |",
           "|---|---|---|---|---|---|"]
    dirs = [x for x in os.listdir(d) if x.startswith("outage_")]
    for x in sorted(dirs, key=lambda s: int(s.split("_")[1])):
        ba = load(os.path.join(d, x, "before_after.json"))
        L = x.split("_")[1]
        if ba is None:
            out.append(f"| {L} | (missing) | | | | |")
            continue
        t = ba["trajectories"]
        l1, l2 = t.get("level1", {}), t.get("level2", {})
        out.append(f"| {L} | {fmt(l1.get('max_pos_err_in_outage_m'))} | "
                   f"{fmt(l2.get('max_pos_err_in_outage_m'))} | "
                   f"{fmt(l1.get('max_rot_err_in_outage_deg'))} | "
                   f"{fmt(l2.get('max_rot_err_in_outage_deg'))} | "
                   f"{fmt(l2.get('rms_pos_err_in_outage_m'))} |")
    return "\n".join(out) + "\n"


def velocity_table(rows):
    """The same runs against the OXTS velocities integrated (report.json vs_oxts_velocity)."""
    out = ["| run | method | ATE [m] | rot RMSE [deg] | t_rel [%] | r_rel [deg/100 m] | "
           "max err in outage [m] |", "|---|---|---|---|---|---|---|"]
    for label, rep in rows:
        for m in ["full", "gnss_ins", "gnss_ins_smoothed", "lidar_only"]:
            r = (rep or {}).get("methods", {}).get(m, {}).get("vs_oxts_velocity")
            if r is None:
                continue
            out.append(f"| {label} | {m} | {fmt(r['ate_rmse_m'])} | {fmt(r['rot_rmse_deg'])} | "
                       f"{fmt(r['t_rel_pct'])} | {fmt(r['r_rel_deg_per_100m'])} | "
                       f"{fmt(r['max_pos_err_in_outage_m'])} |")
    return out


def kitti(d):
    rows = [(x, load(os.path.join(d, x, "report.json"))) for x in sorted(os.listdir(d))]
    return "\n".join(["## Real KITTI frames (OXTS as ground truth)", ""] + methods_table(rows) +
                      [""] + ratio_lines(rows) +
                      ["", "Against the OXTS velocities integrated from the first record "
                       "(docs/user_guide.md, \"A second reference for OXTS ground truth\"):", ""] +
                      velocity_table(rows)) + "\n"


if __name__ == "__main__":
    if len(sys.argv) != 3 or sys.argv[1] not in ("table1", "table2", "kitti"):
        print(__doc__, file=sys.stderr)
        sys.exit(2)
    print({"table1": table1, "table2": table2, "kitti": kitti}[sys.argv[1]](sys.argv[2]), end="")
