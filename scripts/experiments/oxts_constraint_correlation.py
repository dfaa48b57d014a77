#!/usr/bin/env python3
"""How long the vehicle constraint's errors last in KITTI's OXTS records (docs/sweep.md, "Session 30").

For each drive's records above --min-speed (10 Hz), the IMU's velocity in its own frame
(vl leftward; vz = vf sin(pitch) + vu cos(pitch) upward, KITTI's pitch positive nose down) after
the constraint's own model is removed by least squares (lateral: d w_z + a vf + b, the lever arm
and a heading offset; vertical: a vf + b, a pitch offset), and the residual's autocorrelation over
the contiguous stretches above the speed: its standard deviation, the lag at which the
autocorrelation falls below 1/e (the correlation time of a first-order Gauss-Markov error) and
the integral time 2 tau_int = sum of the autocorrelation over lags (-L, L), which is what a
white-noise constraint at 10 Hz under-states its variance by (x 2 tau_int * 10 Hz).

  scripts/experiments/oxts_constraint_correlation.py [--data ../shared/data] [--min-speed 3]
"""
import argparse
import os

import numpy as np

from oxts_records import drive_files, records

RATE_HZ = 10.0
MAX_LAG = 100  # 10 s


def autocorrelation(r, segments):
    """Pooled autocorrelation of r over contiguous segments (lists of index arrays)."""
    num = np.zeros(MAX_LAG + 1)
    den = np.zeros(MAX_LAG + 1)
    for s in segments:
        x = r[s]
        for k in range(min(MAX_LAG + 1, len(x))):
            num[k] += np.dot(x[: len(x) - k], x[k:])
            den[k] += len(x) - k
    c = num / np.maximum(den, 1)
    return c / c[0]


def correlation_times(rho):
    below = np.nonzero(rho < np.exp(-1.0))[0]
    tau_e = below[0] / RATE_HZ if len(below) else np.inf
    # Integral time up to the first zero crossing (the tail is noise).
    zero = np.nonzero(rho <= 0.0)[0]
    end = zero[0] if len(zero) else len(rho)
    tau_int = (rho[0] / 2 + rho[1:end].sum()) / RATE_HZ
    return tau_e, tau_int


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", default=os.environ.get("SLAM_MMS_SHARED_DATA", "../shared/data"))
    ap.add_argument("--min-speed", type=float, default=3.0, help="[m/s]")
    ap.add_argument("--min-samples", type=int, default=200, help="records above the speed")
    args = ap.parse_args()
    files = drive_files(args.data)
    rows = []
    for f in files:
        a = records(f)
        if len(a) < args.min_samples:
            continue
        pitch, vf, vl, vu, wz = a[:, 4], a[:, 8], a[:, 9], a[:, 10], a[:, 19]
        sel = np.abs(vf) > args.min_speed
        if sel.sum() < args.min_samples:
            continue
        idx = np.nonzero(sel)[0]
        segments = [s for s in np.split(idx, np.nonzero(np.diff(idx) > 1)[0] + 1) if len(s) >= 30]
        if not segments:
            continue
        vz = vf * np.sin(pitch) + vu * np.cos(pitch)
        one = np.ones_like(vf)
        out = [os.path.basename(f)[:26]]
        for y, cols in ((vl, [wz, vf, one]), (vz, [vf, one])):
            x = np.c_[tuple(cols)]
            c = np.linalg.lstsq(x[sel], y[sel], rcond=None)[0]
            r = y - x @ c
            rho = autocorrelation(r, segments)
            out += [np.std(r[sel]), *correlation_times(rho)]
        rows.append(out)
        print("%s lateral std %.3f m/s tau_1/e %.1f s tau_int %.2f s | vertical std %.3f tau_1/e %.1f"
              " tau_int %.2f" % tuple(out))
    v = np.array([r[1:] for r in rows], float)
    print("%d drives; median (p10, p90):" % len(v))
    for i, name in enumerate(["lateral std [m/s]", "lateral tau_1/e [s]", "lateral tau_int [s]",
                              "vertical std [m/s]", "vertical tau_1/e [s]",
                              "vertical tau_int [s]"]):
        q = np.percentile(v[:, i][np.isfinite(v[:, i])], [50, 10, 90])
        print("  %-22s %.3f (%.3f, %.3f)" % (name, q[0], q[1], q[2]))
    eq = np.sqrt(2 * np.median(v[:, 5]) * RATE_HZ)
    print("a white 10 Hz constraint on the vertical under-states its sigma by x%.1f (median)" % eq)


if __name__ == "__main__":
    main()
