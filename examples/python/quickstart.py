#!/usr/bin/env python3
"""slam_mms from Python, notebook style: simulate a short drive, map it, look at the result.

    python3 examples/python/quickstart.py [OUT_DIR] [--duration S]

Each "cell" below is a step you would run in a notebook. Plots are written as PNGs into OUT_DIR
(matplotlib with the Agg backend, so no display is needed). CI runs this file as a test.
"""

import argparse
import pathlib
import tempfile

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import slam_mms  # noqa: E402

parser = argparse.ArgumentParser()
parser.add_argument("out", nargs="?", type=pathlib.Path)
parser.add_argument("--duration", type=float, default=3.0)
args = parser.parse_args()
out = args.out or pathlib.Path(tempfile.mkdtemp(prefix="slam_mms_quickstart_"))
out.mkdir(parents=True, exist_ok=True)
print("slam_mms", slam_mms.__version__, "->", out)

# %% 1. A simulated drive in KITTI raw layout, with true ground truth.
drive = slam_mms.simulate_drive(out / "sim", duration_s=args.duration, write_scene_cloud=False)
reader = slam_mms.open_drive(drive)
print(reader, "| IMU", reader.streams.imu.shape, "| GNSS", reader.streams.gnss.shape)

# %% 2. One scan: points (N x 3 float32, lidar frame) and per-point times.
scan = reader[0]
fig, ax = plt.subplots(figsize=(6, 6))
ax.scatter(scan.points[:, 0], scan.points[:, 1], s=0.1, c=scan.times, cmap="viridis")
ax.set_aspect("equal")
ax.set_xlim(-40, 40)
ax.set_ylim(-40, 40)
ax.set_title(f"scan 0: {len(scan)} points, colour = time in scan [s]")
fig.savefig(out / "scan0.png", dpi=80)

# %% 3. The SLAM-integrated system and the GNSS/INS baseline, with a GNSS outage.
outage = [(1.0, 1.5)]
full = slam_mms.run_drive(drive, mode="full", gnss_outages=outage, ground_truth_map=False)
gnss_ins = slam_mms.run_drive(drive, mode="gnss_ins", gnss_outages=outage, ground_truth_map=False)
for name, r in (("full", full), ("gnss_ins", gnss_ins)):
    m = r.report["methods"][name]
    print(f"{name:9s} ATE {m['ate_rmse_m']:.3f} m  rot {m['rot_rmse_deg']:.3f} deg  "
          f"MME {m['mme']:.3f}  {m['scans_per_s']:.1f} scans/s")

# %% 4. Trajectories against the ground truth (all in the run's local ENU frame).
gt = full.ground_truth.tum
fig, ax = plt.subplots(figsize=(6, 5))
ax.plot(gt[:, 1], gt[:, 2], "k-", lw=3, alpha=0.3, label="ground truth")
ax.plot(full.trajectory[:, 1], full.trajectory[:, 2], ".-", label="full")
ax.plot(gnss_ins.trajectory[:, 1], gnss_ins.trajectory[:, 2], ".-", label="gnss_ins")
ax.set_aspect("equal")
ax.legend()
ax.set_xlabel("east [m]")
ax.set_ylabel("north [m]")
fig.savefig(out / "trajectories.png", dpi=80)

# %% 5. Position error over time and the pose uncertainty the system reports.
fig, ax = plt.subplots(figsize=(7, 3.5))
t0 = full.stamps_ns[0]
for name, r in (("full", full), ("gnss_ins", gnss_ins)):
    ax.plot((r.ate.stamps_ns - t0) * 1e-9, r.ate.position_error_norm_m, label=f"{name} error")
sigma = np.sqrt(np.trace(full.covariances[:, 3:, 3:], axis1=1, axis2=2))
ax.plot((full.stamps_ns - t0) * 1e-9, sigma, "--", label="full 1-sigma (trace)")
for s, d in outage:
    ax.axvspan(s, s + d, color="grey", alpha=0.2)
ax.set_xlabel("time since first scan [s]")
ax.set_ylabel("[m]")
ax.legend()
fig.savefig(out / "position_error.png", dpi=80)

# %% 6. The map: a bird's-eye view coloured by height.
pts = full.map_points
fig, ax = plt.subplots(figsize=(6, 6))
ax.scatter(pts[::5, 0], pts[::5, 1], s=0.05, c=pts[::5, 2], cmap="terrain")
ax.set_aspect("equal")
ax.set_title(f"map: {len(pts)} points (every 5th shown)")
fig.savefig(out / "map.png", dpi=80)
slam_mms.write_map(pts, out / "map_full.ply")

print("plots:", ", ".join(sorted(p.name for p in out.glob("*.png"))))
