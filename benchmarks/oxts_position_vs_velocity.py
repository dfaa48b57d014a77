#!/usr/bin/env python3
"""How far a KITTI drive's OXTS positions agree with its own velocities over 1 s.

The statistic of eval::CompareIncrements (include/slam_mms/eval/oxts_reference.hpp), applied to
every drive's OXTS records in ../shared/data/kitti_oxts (the tarballs are read as they are):
windows from each record to the first record at least 1 s later, the horizontal position
increment minus the trapezoidal integral of (ve, vn) over the same records, split along and
across the integrated increment, in % of its length; windows under 5 m are skipped. Positions are
taken to a local east/north frame at the drive's first record with the WGS-84 radii of curvature
there (good to 1e-5 over a few km). A drive with stamps that do not increase inside a window, or
a gap over 0.5 s, skips those windows; a drive slower than 5 m/s throughout has none.

    python3 benchmarks/oxts_position_vs_velocity.py [../shared/data/kitti_oxts] [--csv OUT.csv]
        [--lag-scan]

--lag-scan also reads each drive's velocities 0.025 s, 0.05 s ... later or earlier (-0.15..0.15 s)
and reports the lag with the smallest RMS: a latency between the OXTS's velocity and position
outputs shows as a best lag away from 0. It also finds the lag of the recorded horizontal
accelerations (af, al) that fits the positions' second differences best, and of the recorded yaw
rate (wu) that fits the recorded yaw's central differences best.

Prints one line per drive (sorted by RMS) and the median by the drives' main OXTS position mode
(posmode: 3 SPS, 4 differential, 5 RTK float, 6 RTK integer, 0 none). docs/simulator.md, "The real
reference", quotes its output.
"""
import argparse
import io
import math
import os
import sys
import tarfile

import numpy as np

A = 6378137.0
E2 = 6.69437999014e-3


def stamp_seconds(line):
    date, time = line.strip().split(" ")
    h, m, s = time.split(":")
    return int(h) * 3600 + int(m) * 60 + float(s)


def read_drive(path):
    records, stamps = {}, None
    with tarfile.open(path) as tar:
        for member in tar.getmembers():
            if not member.isfile():
                continue
            name = member.name
            if name.endswith("oxts/timestamps.txt"):
                text = tar.extractfile(member).read().decode()
                stamps = [stamp_seconds(l) for l in text.splitlines() if l.strip()]
            elif "/oxts/data/" in name and name.endswith(".txt"):
                values = tar.extractfile(member).read().decode().split()
                records[int(os.path.basename(name)[:-4])] = [float(v) for v in values]
    if stamps is None or not records:
        return None
    a = np.array([records[k] for k in sorted(records)])
    t = np.array(stamps[: len(a)])
    return t, a[: len(t)]


def east_north(a):
    """The records' positions in a local east/north frame at the first one [m], with the WGS-84
    radii of curvature there."""
    lat0 = math.radians(a[0, 0])
    w = math.sqrt(1.0 - E2 * math.sin(lat0) ** 2)
    m_radius = A * (1.0 - E2) / w**3
    n_radius = A / w
    east = np.radians(a[:, 1] - a[0, 1]) * n_radius * math.cos(lat0)
    north = np.radians(a[:, 0] - a[0, 0]) * m_radius
    return np.c_[east, north]


def agreement(t, a, window_s=1.0, min_distance_m=5.0, max_gap_s=0.5, velocity_lag_s=0.0):
    p = east_north(a)
    v = np.c_[a[:, 7], a[:, 6]]  # ve, vn
    if velocity_lag_s != 0.0:
        # The velocity recorded at t taken as the one at t - lag (read it lag later).
        v = np.c_[np.interp(t + velocity_lag_s, t, v[:, 0]), np.interp(t + velocity_lag_s, t, v[:, 1])]
    along, cross, dist = [], [], []
    j = 0
    for i in range(len(t)):
        j = max(j, i + 1)
        while j < len(t) and t[j] - t[i] < window_s:
            j += 1
        if j >= len(t):
            break
        dt = np.diff(t[i : j + 1])
        if np.any(dt <= 0) or np.any(dt > max_gap_s):
            continue
        d_ref = np.sum(0.5 * (v[i:j] + v[i + 1 : j + 1]) * dt[:, None], axis=0)
        length = np.linalg.norm(d_ref)
        if length < min_distance_m:
            continue
        u = d_ref / length
        diff = (p[j] - p[i]) - d_ref
        along.append(100.0 * (u @ diff) / length)
        cross.append(100.0 * (u[0] * diff[1] - u[1] * diff[0]) / length)
        dist.append(length)
    if not dist:
        return None
    along, cross = np.array(along), np.array(cross)
    return {
        "windows": len(dist),
        "rms": float(np.sqrt(np.mean(along**2 + cross**2))),
        "along_mean": float(along.mean()),
        "along_std": float(along.std()),
        "cross_mean": float(cross.mean()),
        "cross_std": float(cross.std()),
        "pos_accuracy_median": float(np.median(a[:, 23])),
        "posmode": int(np.bincount(np.clip(a[:, 27].astype(int), 0, None)).argmax()),
    }


def acceleration_lag(t, a, lags):
    """The lag of the recorded horizontal accelerations (af, al: level frame, rotated by the yaw
    to east/north) that fits the positions' second differences best (RMS over records whose two
    neighbours are 0.09-0.12 s away)."""
    p = east_north(a)
    yaw, af, al = a[:, 5], a[:, 14], a[:, 15]
    acc = np.c_[af * np.cos(yaw) - al * np.sin(yaw), af * np.sin(yaw) + al * np.cos(yaw)]
    dt = np.diff(t)
    good = (dt > 0.09) & (dt < 0.12)
    i = np.where(np.r_[False, good[:-1] & good[1:], False])[0]
    if len(i) < 20:
        return None
    h1, h2 = t[i] - t[i - 1], t[i + 1] - t[i]
    a_pos = 2.0 * ((p[i + 1] - p[i]) / h2[:, None] - (p[i] - p[i - 1]) / h1[:, None]) / (h1 + h2)[:, None]
    rms = []
    for lag in lags:
        a_rec = np.c_[np.interp(t[i] + lag, t, acc[:, 0]), np.interp(t[i] + lag, t, acc[:, 1])]
        rms.append(np.sqrt(np.mean(np.sum((a_rec - a_pos) ** 2, axis=1))))
    return lags[int(np.argmin(rms))]


def rate_lag(t, a, lags):
    """The lag of the recorded yaw rate (wu, about the up axis) that fits the central differences
    of the recorded yaw best (records whose two neighbours are 0.18-0.24 s apart)."""
    yaw = np.unwrap(a[:, 5])
    wu = a[:, 22]
    i = np.arange(1, len(t) - 1)
    span = t[i + 1] - t[i - 1]
    i = i[(span > 0.18) & (span < 0.24)]
    if len(i) < 20:
        return None
    d_yaw = (yaw[i + 1] - yaw[i - 1]) / (t[i + 1] - t[i - 1])
    rms = [np.sqrt(np.mean((np.interp(t[i] + lag, t, wu) - d_yaw) ** 2)) for lag in lags]
    return lags[int(np.argmin(rms))]


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folder", nargs="?",
                        default=os.path.join(here, "..", "..", "shared", "data", "kitti_oxts"))
    parser.add_argument("--csv", help="write the per-drive rows as CSV")
    parser.add_argument("--lag-scan", action="store_true",
                        help="also find per drive the velocity lag (-0.15..0.15 s, 25 ms steps) "
                             "that minimises the RMS")
    args = parser.parse_args()
    tars = sorted(f for f in os.listdir(args.folder) if f.endswith("_sync.tar.gz"))
    if not tars:
        sys.exit(f"{args.folder}: no <drive>_sync.tar.gz")
    rows, skipped = [], 0
    for name in tars:
        drive = read_drive(os.path.join(args.folder, name))
        r = agreement(*drive) if drive else None
        if r is None:
            skipped += 1
            continue
        r["drive"] = name[: -len("_sync.tar.gz")]
        if args.lag_scan:
            lags = [0.025 * k for k in range(-6, 7)]
            scan = [agreement(*drive, velocity_lag_s=lag)["rms"] for lag in lags]
            r["best_lag_s"] = lags[int(np.argmin(scan))]
            r["rms_at_best_lag"] = float(min(scan))
            r["acceleration_lag_s"] = acceleration_lag(*drive, lags)
            r["yaw_rate_lag_s"] = rate_lag(*drive, lags)
        rows.append(r)
    rows.sort(key=lambda r: r["rms"])
    for r in rows:
        fmt = lambda v: "-" if v is None else "%+.3f s" % v
        lag = ("  best lag %+.3f s: RMS %.2f %%, accelerations %s, yaw rate %s" %
               (r["best_lag_s"], r["rms_at_best_lag"], fmt(r["acceleration_lag_s"]),
                fmt(r["yaw_rate_lag_s"]))
               if args.lag_scan else "")
        print("%s windows %5d  RMS %6.2f %%  along %+.2f +- %.2f  across %+.2f +- %.2f  "
              "pos_accuracy %.2f m  posmode %d%s" % (r["drive"], r["windows"], r["rms"], r["along_mean"],
                                                     r["along_std"], r["cross_mean"], r["cross_std"],
                                                     r["pos_accuracy_median"], r["posmode"], lag))
    rms = np.array([r["rms"] for r in rows])
    print("\n%d drives with a window (%d without one: standing, or under 5 m/s); RMS median "
          "%.2f %%, 10th/90th percentile %.2f / %.2f %%" %
          (len(rows), skipped, np.median(rms), np.percentile(rms, 10), np.percentile(rms, 90)))
    for mode in sorted({r["posmode"] for r in rows}):
        sel = [r for r in rows if r["posmode"] == mode]
        print("posmode %d: %3d drives, RMS median %.2f %%, across-track std median %.2f %%, "
              "|across mean| median %.2f %%" %
              (mode, len(sel), np.median([r["rms"] for r in sel]),
               np.median([r["cross_std"] for r in sel]),
               np.median([abs(r["cross_mean"]) for r in sel])))
        if args.lag_scan:
            acc = [r["acceleration_lag_s"] for r in sel if r["acceleration_lag_s"] is not None]
            rate = [r["yaw_rate_lag_s"] for r in sel if r["yaw_rate_lag_s"] is not None]
            print("           best velocity lag median %+.3f s, RMS there median %.2f %%; "
                  "best acceleration lag median %+.3f s (%d drives), yaw rate %+.3f s (%d)" %
                  (np.median([r["best_lag_s"] for r in sel]),
                   np.median([r["rms_at_best_lag"] for r in sel]), np.median(acc), len(acc),
                   np.median(rate), len(rate)))
    if args.csv:
        with open(args.csv, "w") as f:
            keys = ["drive", "windows", "rms", "along_mean", "along_std", "cross_mean",
                    "cross_std", "pos_accuracy_median", "posmode"]
            if args.lag_scan:
                keys += ["best_lag_s", "rms_at_best_lag", "acceleration_lag_s", "yaw_rate_lag_s"]
            f.write(",".join(keys) + "\n")
            for r in rows:
                f.write(",".join(str(r[k]) for k in keys) + "\n")


if __name__ == "__main__":
    main()
