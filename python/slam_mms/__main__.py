"""``python -m slam_mms run ...``: the Python twin of ``slam_mms_run``.

    python -m slam_mms run --kitti-raw DRIVE_DIR --out DIR [--mode full|gnss_ins|lidar_only|all]
                           [--frames A:B] [--gnss-outage START_S:DURATION_S ...] [--config FILE]
    python -m slam_mms run --out DIR          # simulates the default drive into DIR/sim first
    python -m slam_mms version

Writes what slam_mms_run writes for each method: <method>.tum, <method>.kitti, <method>_cov.csv,
map_<method>.ply/.pcd/.las (full and gnss_ins), ground_truth.tum and report.json (same schema,
by the C++ writer). Exit status 1 on a processing error, 2 on a bad command line or config.
(Plots are not drawn; examples/python/quickstart.py shows matplotlib ones.)
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import pathlib
import sys
from typing import List, Optional

from . import _C, __version__
from ._drive import run_drive, simulate_drive

_MODES = {"full": ["full"], "gnss_ins": ["gnss_ins"], "lidar_only": ["lidar_only"],
          "all": ["full", "gnss_ins", "lidar_only"]}
_LEVELS = {"debug": _C.LogLevel.DEBUG, "info": _C.LogLevel.INFO,
           "warning": _C.LogLevel.WARNING, "error": _C.LogLevel.ERROR}


def _outage(text: str):
    try:
        start, duration = (float(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--gnss-outage {text!r}: expected START_S:DURATION_S")
    return start, duration


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m slam_mms", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="map a drive (as slam_mms_run)")
    src = r.add_mutually_exclusive_group()
    src.add_argument("--kitti-raw", type=pathlib.Path, help="KITTI raw drive folder")
    src.add_argument("--folder", type=pathlib.Path, help="plain drive folder")
    src.add_argument("--rosbag", type=pathlib.Path, help="ROS 1 bag")
    r.add_argument("--out", type=pathlib.Path, required=True)
    r.add_argument("--mode", choices=sorted(_MODES), default="full")
    r.add_argument("--frames", help="A:B inclusive")
    r.add_argument("--gnss-outage", type=_outage, action="append", default=[],
                   metavar="START_S:DURATION_S")
    r.add_argument("--config", type=pathlib.Path)
    r.add_argument("--extrinsics", type=pathlib.Path)
    r.add_argument("--sim-duration", type=float, default=30.0)
    r.add_argument("--sim-seed", type=int, default=1)
    r.add_argument("--log-level", choices=sorted(_LEVELS), default="warning")
    sub.add_parser("version", help="print the version")
    return p


def _write_method(result, name: str, out: pathlib.Path) -> None:
    traj = result.run.trajectory
    traj.write_tum(os.fspath(out / f"{name}.tum"))
    traj.write_kitti(os.fspath(out / f"{name}.kitti"))
    traj.write_csv(os.fspath(out / f"{name}_cov.csv"))
    if name in ("full", "gnss_ins") and len(result.map_points):
        for ext in ("ply", "pcd"):
            _C.write_map(result.map_points, os.fspath(out / f"map_{name}.{ext}"))
        if result.origin is not None:
            _C.write_map(result.map_points, os.fspath(out / f"map_{name}.las"), result.origin)


def _run(args) -> int:
    out: pathlib.Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    options = _C.Options()
    # As slam_mms_run: finished submaps' clouds spill into --out (memory stays flat).
    options.localizer.spill_dir = os.fspath(out)
    if args.config is not None:
        try:
            _C.apply_config_file(os.fspath(args.config), options)
        except (ValueError, FileNotFoundError, _C.Error) as e:
            print(f"python -m slam_mms: error: {e}", file=sys.stderr)
            return 2
    path = args.kitti_raw or args.folder or args.rosbag
    kind = "kitti_raw" if args.kitti_raw else "folder" if args.folder else \
        "rosbag" if args.rosbag else "kitti_raw"
    if path is None:
        print(f"[sim] simulating the default drive ({args.sim_duration} s, seed {args.sim_seed})"
              f" into {out / 'sim'}", flush=True)
        path = simulate_drive(out / "sim", duration_s=args.sim_duration, seed=args.sim_seed)
    report = None
    status = 0
    for name in _MODES[args.mode]:
        print(f"[{name}] running ...", flush=True)
        try:
            result = run_drive(path, mode=name, frames=args.frames,
                               gnss_outages=args.gnss_outage, options=options, check=False,
                               kind=kind, extrinsics=args.extrinsics or "")
        except (ValueError, FileNotFoundError, IndexError, _C.Error) as e:
            print(f"python -m slam_mms: error: {e}", file=sys.stderr)
            return 2 if isinstance(e, ValueError) else 1
        _write_method(result, name, out)
        if result.ground_truth is not None and not (out / "ground_truth.tum").exists():
            result.ground_truth.write_tum(os.fspath(out / "ground_truth.tum"))
        if report is None:
            report = result.report
        else:
            report["methods"].update(result.report["methods"])
        print(f"[{name}] {result.run.scans_processed} scans in {result.run.wall_s:.1f} s", flush=True)
        if not result.run.ok:
            print(f"python -m slam_mms: error: {result.run.status_message}", file=sys.stderr)
            status = 1
            break
    if report is not None:
        (out / "report.json").write_text(json.dumps(report, indent=2) + "\n")
        print(json.dumps(report["methods"], indent=2))
    print(f"outputs in {out}")
    return status


def main(argv: Optional[List[str]] = None) -> int:
    args = _parser().parse_args(argv)
    if args.command == "version":
        print(__version__)
        return 0
    logging.basicConfig(level=logging.WARNING, format="[%(levelname)s] %(message)s")
    level = _LEVELS[args.log_level]
    _C.set_min_log_level(level)
    logging.getLogger("slam_mms").setLevel({0: 10, 1: 20, 2: 30, 3: 40}[int(level)])
    return _run(args)


if __name__ == "__main__":
    sys.exit(main())
