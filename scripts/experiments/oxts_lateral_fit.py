#!/usr/bin/env python3
"""How KITTI's OXTS moves sideways (docs/sweep.md, "Session 29").

For each drive's OXTS records above 3 m/s, least-squares fits of the leftward velocity vl:
  lever:      vl = d w_z + a vf + b
  lever+vw:   vl = d w_z + k vf w_z + a vf + b
  lever+v2w:  vl = d w_z + s vf^2 w_z + a vf + b
(w_z: yaw rate; a vf: a heading offset; b: a bias) and prints the coefficients, the residual
standard deviations and their medians over the drives with yaw rates above --min-yaw-rate.

  scripts/experiments/oxts_lateral_fit.py [--data ../shared/data] [--min-yaw-rate 0.3]
"""
import argparse
import os

import numpy as np

from oxts_records import drive_files, records


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default=os.environ.get("SLAM_MMS_SHARED_DATA", "../shared/data"))
    ap.add_argument("--min-yaw-rate", type=float, default=0.3, help="[rad/s]")
    args = ap.parse_args()
    files = drive_files(args.data)
    summary = []
    for f in files:
        a = records(f)
        if len(a) < 50:
            continue
        vf, vl, wz = a[:, 8], a[:, 9], a[:, 19]
        sel = np.abs(vf) > 3.0
        if sel.sum() < 50 or np.max(np.abs(wz[sel])) < args.min_yaw_rate:
            continue
        one = np.ones_like(vf)
        fits = {}
        for name, cols in (("lever", [wz, vf, one]), ("lever+vw", [wz, vf * wz, vf, one]),
                           ("lever+v2w", [wz, vf * vf * wz, vf, one])):
            x = np.c_[tuple(cols)][sel]
            c = np.linalg.lstsq(x, vl[sel], rcond=None)[0]
            fits[name] = (c, np.std(vl[sel] - x @ c))
        row = [fits["lever"][0][0], fits["lever+vw"][0][0], fits["lever+vw"][0][1],
               fits["lever+v2w"][0][1], fits["lever"][1], fits["lever+vw"][1],
               fits["lever+v2w"][1], np.std(vl[sel])]
        summary.append(row)
        print("%s lever %.2f m | lever %.2f m + %.3f s vw | v2w %.4f | resid %.3f %.3f %.3f of %.3f m/s"
              % ((os.path.basename(f)[:26],) + tuple(row)))
    if summary:
        med = np.median(np.array(summary), axis=0)
        print("median over %d drives: lever %.2f m | lever %.2f m + %.3f s vw | v2w %.4f s^2/m | "
              "resid %.3f %.3f %.3f of %.3f m/s" % ((len(summary),) + tuple(med)))


if __name__ == "__main__":
    main()
