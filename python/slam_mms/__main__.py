"""``python -m slam_mms run ...``: the Python twin of ``slam_mms_run`` (same flags, same outputs).

    python -m slam_mms run --kitti-raw DRIVE_DIR --out DIR
                           [--mode full|gnss_ins|gnss_ins_smoothed|lidar_only|all]
                           [--pos forward|smoothed]
                           [--frames A:B] [--gnss-outage START_S:DURATION_S ...] [--config FILE]
    python -m slam_mms run --folder DIR --out DIR [...]
    python -m slam_mms run --rosbag FILE.bag --out DIR [--lidar-topic T] [--imu-topic T]
                           [--gnss-topic T] [--extrinsics FILE.yaml] [...]
    python -m slam_mms run --out DIR          # simulates the default drive into DIR/sim first
    python -m slam_mms run --config-keys
    python -m slam_mms version

Writes in DIR what slam_mms_run writes: <method>.tum, <method>.kitti, <method>_cov.csv per method;
<method>_scans.csv and <method>_level1.tum for full and lidar_only; map_<method>.ply/.pcd/.las for
every method but lidar_only (.las: or map_<method>_tiles/ with --las-tile-size); <method>_wgs84.csv
and <method>_utm.csv (<method>_epsg<code>.csv with --crs); georef.json; ground_truth.tum; report.json; summary.txt; trajectories.png,
position_error.png and map_<method>_height.png (drawn by the app's C++ plot code). Every file
comes from the C++ writers, so the trajectories, maps, ground truth and plots are byte-identical
to the app's on the same input (report.json and summary.txt differ in scans/s and RSS only).
Exit status: 0 done; 1 input or processing error (outputs computed so far are written); 2 bad
command line or config file.
"""

from __future__ import annotations

import argparse
import json
import logging
import math
import os
import pathlib
import sys
from typing import List, Optional

from . import _C, __version__
from ._drive import (DriveResult, _options_for_reader, _parse_frames, _run_reader, open_drive,
                     simulate_drive)

_ALL = ["full", "gnss_ins", "gnss_ins_smoothed", "lidar_only"]  # slam_mms_run's --mode all
_LEVELS = {"debug": _C.LogLevel.DEBUG, "info": _C.LogLevel.INFO,
           "warning": _C.LogLevel.WARNING, "error": _C.LogLevel.ERROR}
_log = logging.getLogger("slam_mms")


class _UsageError(Exception):
    """A bad command line or config file: exit status 2."""


def _outage(text: str):
    try:
        start, duration = (float(v) for v in text.split(":"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"--gnss-outage {text!r}: expected START_S:DURATION_S")
    if not (math.isfinite(start) and math.isfinite(duration)) or start < 0 or duration <= 0:
        raise argparse.ArgumentTypeError(
            f"--gnss-outage {text!r}: expected START_S >= 0 and DURATION_S > 0")
    return start, duration


def _modes(text: str) -> List[str]:
    if text == "all":
        return list(_ALL)
    try:
        return [_C.mapping_mode_name(_C.parse_mapping_mode(text))]
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--mode {text}: expected full, gnss_ins, gnss_ins_smoothed, lidar_only or all"
        ) from None


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python -m slam_mms", description=__doc__.split("\n\n")[0])
    sub = p.add_subparsers(dest="command", required=True)
    r = sub.add_parser("run", help="map a drive (as slam_mms_run)")
    src = r.add_mutually_exclusive_group()
    src.add_argument("--kitti-raw", type=pathlib.Path, help="KITTI raw drive folder")
    src.add_argument("--folder", type=pathlib.Path, help="plain drive folder (docs/drive_folder.md)")
    src.add_argument("--rosbag", type=pathlib.Path, help="ROS 1 bag (docs/rosbag.md)")
    r.add_argument("--lidar-topic", default="", help="bag topic of the PointCloud2 scans")
    r.add_argument("--imu-topic", default="", help="bag topic of the Imu samples")
    r.add_argument("--gnss-topic", default="", help="bag topic of the NavSatFix fixes")
    r.add_argument("--extrinsics", type=pathlib.Path,
                   help="extrinsics.yaml (for a bag, or to override a folder's)")
    r.add_argument("--out", type=pathlib.Path, help="output folder (created)")
    r.add_argument("--mode", type=_modes, default=list(_ALL),
                   help="full | gnss_ins | gnss_ins_smoothed | lidar_only | all (default all = "
                        "the four in turn)")
    r.add_argument("--pos", choices=["forward", "smoothed"], default="forward",
                   help="the POS `full` runs on (as slam_mms_run --pos; default forward)")
    r.add_argument("--frames", help="A:B inclusive (A: = from A to the end)")
    r.add_argument("--gnss-outage", type=_outage, nargs="+", action="extend", default=[],
                   metavar="START_S:DURATION_S")
    r.add_argument("--crs", default="",
                   help="output CRS of the LAS maps and projected CSVs (EPSG:nnnn; default WGS 84 / "
                        "UTM zone of the world origin)")
    r.add_argument("--las-tile-size", type=float, default=0.0, metavar="M",
                   help="LAS maps in square tiles of M metres (default 0 = one file)")
    r.add_argument("--config", type=pathlib.Path, help="YAML file of option overrides (slam_mms_run --config)")
    r.add_argument("--sim-duration", type=float, default=30.0,
                   help="seconds of the default drive to simulate (0 = all)")
    r.add_argument("--sim-seed", type=int, default=1)
    r.add_argument("--log-level", choices=list(_LEVELS), default="warning")
    r.add_argument("--config-keys", action="store_true",
                   help="print every --config key with its default as YAML, then exit")
    sub.add_parser("version", help="print the version")
    return p


def _try(what: str, f, *args) -> bool:
    """Runs a writer; logs and returns False on failure (as the app's KeepFirst)."""
    try:
        f(*args)
        return True
    except (OSError, ValueError, _C.Error) as e:
        _log.error("%s: %s", what, e)
        return False


def _write_method(result: DriveResult, name: str, out: pathlib.Path, crs: str = "",
                  las_tile_size: float = 0.0, run_origin=None) -> bool:
    """slam_mms_run's WriteMethodFiles and WriteGeoOutputs: returns False when a file could not be
    written."""
    run = result.run
    ok = True
    traj = run.trajectory
    if len(traj):
        ok &= _try(f"{name}.tum", traj.write_tum, os.fspath(out / f"{name}.tum"))
        ok &= _try(f"{name}.kitti", traj.write_kitti, os.fspath(out / f"{name}.kitti"))
        ok &= _try(f"{name}_cov.csv", traj.write_csv, os.fspath(out / f"{name}_cov.csv"))
    else:
        _log.warning("%s: no pose estimated, no trajectory written", name)
    if len(run.results):
        ok &= _try(f"{name}_scans.csv", run.write_scan_results_csv,
                   os.fspath(out / f"{name}_scans.csv"))
        if name not in ("gnss_ins", "gnss_ins_smoothed"):
            ok &= _try(f"{name}_level1.tum", run.level1_trajectory.write_tum,
                       os.fspath(out / f"{name}_level1.tum"))
    if name != "lidar_only":
        if len(result.map_points):
            base = out / f"map_{name}"
            ok &= _try(f"map_{name}.ply", _C.write_map, result.map_points, f"{base}.ply")
            ok &= _try(f"map_{name}.pcd", _C.write_map, result.map_points, f"{base}.pcd")
        else:
            _log.warning("%s: empty map, map files not written", name)
    # WGS-84 / projected CSVs and the LAS map (or its tiles), as slam_mms_run's WriteGeoOutputs.
    ok &= _try(f"{name} geo-referenced files", run.write_geo_outputs, name, os.fspath(out), crs,
               las_tile_size, run_origin)
    return ok


def _write_plots(results: List[DriveResult], gt, gt_kind: str, outages, reference_ns,
                 out: pathlib.Path) -> None:
    """slam_mms_run's WritePlots, through the same C++ plot functions (eval/plots.hpp)."""
    methods = [(r.extra["name"], r.run.trajectory) for r in results if len(r.run.trajectory)]
    if gt is not None and methods and reference_ns is not None:
        # The ground truth over the span of the estimates only (the simulator's covers the lead-in).
        t_min = min(int(t.stamps_ns[0]) for _, t in methods)
        t_max = max(int(t.stamps_ns[-1]) for _, t in methods)
        span = gt.between(t_min, t_max)
        if len(span) < 2:
            span = gt
        _try("trajectories.png", _C.plot_trajectories_top_view, span,
             f"ground truth ({gt_kind})", methods, outages, reference_ns,
             os.fspath(out / "trajectories.png"),
             f"Trajectories from above (ground truth: {gt_kind})")
        series = [(r.extra["name"], r.ate) for r in results if r.ate is not None]
        if series:
            _try("position_error.png", _C.plot_position_errors, series, outages, reference_ns,
                 os.fspath(out / "position_error.png"),
                 f"Position error vs {gt_kind} ground truth (GNSS outages shaded)")
    for r in results:
        name = r.extra["name"]
        if name == "lidar_only" or not len(r.map_points):
            continue
        _try(f"map_{name}_height.png", _C.plot_map_height, r.map_points,
             os.fspath(out / f"map_{name}_height.png"), r.run.trajectory.tum[:, 1:4],
             f"Map of {name} from above, coloured by height")


def _cell(v, fmt: str) -> str:
    if v is None or not math.isfinite(v):
        return "-"
    return fmt % v


def _summary_table(results: List[DriveResult], report: dict) -> str:
    """slam_mms_run's summary.txt (the same columns and formats)."""
    row = "%-17s %9s %9s %9s %12s %14s %8s %8s %9s\n"
    s = row % ("method", "ATE[m]", "rotRMSE", "t_rel[%]", "r_rel[d/100]", "maxErrOut[m]", "MME",
               "scans/s", "RSS[MB]")
    for r in results:
        name = r.extra["name"]
        m = report["methods"][name]
        s += row % (name, _cell(m["ate_rmse_m"], "%.3f"), _cell(m["rot_rmse_deg"], "%.3f"),
                    _cell(m["t_rel_pct"], "%.3f"), _cell(m["r_rel_deg_per_100m"], "%.4f"),
                    _cell(m["max_pos_err_in_outage_m"], "%.3f"), _cell(m["mme"], "%.4f"),
                    _cell(m["scans_per_s"], "%.2f"), _cell(m["peak_rss_mb"], "%.0f"))
    s += f"ground-truth map MME: {_cell(report['ground_truth_map']['mme'], '%.4f')}\n"
    s += (f"ATE and rotation RMSE without alignment, against the "
          f"{report['input']['ground_truth']} ground truth interpolated at each scan's start; "
          f"rotRMSE in deg.\n")
    for r in results:
        label = r.extra.get("relative_label")
        if label:
            segments = r.relative_error.num_segments if r.relative_error is not None else 0
            poses = r.outage_errors.num_poses if r.outage_errors is not None else 0
            points = r.map_entropy.num_valid_points if r.map_entropy is not None else 0
            s += (f"{r.extra['name']}: t_rel/r_rel over segments {label} ({segments} segments); "
                  f"{poses} poses inside GNSS outages; MME over {points} points\n")
    return s


def _run(args) -> int:
    if args.config_keys:
        # The same YAML as slam_mms_run --config-keys: a --config file of the defaults.
        sys.stdout.write(_C.options_to_yaml(_C.Options()))
        return 0
    if args.out is None:
        raise _UsageError("--out DIR is required (see --help)")
    if (args.lidar_topic or args.imu_topic or args.gnss_topic) and args.rosbag is None:
        raise _UsageError("--lidar-topic/--imu-topic/--gnss-topic go with --rosbag")
    try:
        _parse_frames(args.frames)
    except ValueError as e:
        raise _UsageError(f"--frames {args.frames}: {e}") from None
    try:
        _C.check_geo_output_options(args.crs, args.las_tile_size)
    except ValueError as e:
        raise _UsageError(str(e)) from None
    out: pathlib.Path = args.out
    options = _C.Options()
    # As slam_mms_run: finished submaps' clouds spill into --out (memory stays flat).
    options.localizer.spill_dir = os.fspath(out)
    if args.config is not None:
        try:
            _C.apply_config_file(os.fspath(args.config), options)
        except (ValueError, FileNotFoundError, _C.Error) as e:
            raise _UsageError(str(e)) from None
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise _UsageError(f"--out {out}: {e}") from None

    path = args.kitti_raw or args.folder or args.rosbag
    kind = "folder" if args.folder else "rosbag" if args.rosbag else "kitti_raw"
    if path is None:
        print(f"[sim] simulating the default drive ({args.sim_duration} s, seed {args.sim_seed})"
              f" into {out / 'sim'}", flush=True)
        path = simulate_drive(out / "sim", duration_s=args.sim_duration, seed=args.sim_seed)
    path = pathlib.Path(path)
    reader = open_drive(path, frames=args.frames, kind=kind, lidar_topic=args.lidar_topic,
                        imu_topic=args.imu_topic, gnss_topic=args.gnss_topic,
                        extrinsics=args.extrinsics or "")
    if len(reader) == 0:
        raise IndexError(f"{reader.describe()}: no scan in the frame range")
    outages = list(args.gnss_outage)
    _options_for_reader(options, reader, outages)
    try:
        options.validate()
    except ValueError as e:
        raise _UsageError(str(e)) from None
    duration_s = (reader.scan_end_ns(len(reader) - 1) - reader.scan_start_ns(0)) * 1e-9
    streams = reader.streams
    print(f"[input] {reader.describe()}: {len(reader)} scans, {duration_s:.1f} s, "
          f"IMU {len(streams.imu)} samples, GNSS {len(streams.gnss)} fixes", flush=True)

    results: List[DriveResult] = []
    status = 0
    gt = None
    gt_map_mme = None
    run_origin = None  # the origin of georef.json: the first method's that has one
    for i, name in enumerate(args.mode):
        print(f"[{name}] running ...", flush=True)
        # The simulator's scene map entropy once (it does not depend on the method).
        result = _run_reader(reader, path, name, options, outages, evaluate=True,
                             ground_truth_map=(i == 0), check=False, pos=args.pos)
        result.extra["name"] = name
        results.append(result)
        if run_origin is None and result.origin is not None:
            run_origin = result.origin
            if not _try("georef.json", _C.write_georef_json, run_origin, os.fspath(out), args.crs):
                status = 1
        written = _write_method(result, name, out, args.crs, args.las_tile_size, run_origin)
        if i == 0:
            gt_map_mme = result.extra.get("ground_truth_map_mme")
        if gt is None and result.ground_truth is not None:
            gt = result.ground_truth
            # The ground truth in the run's world frame, for slam_mms_eval.
            _try("ground_truth.tum", gt.write_tum, os.fspath(out / "ground_truth.tum"))
        print(f"[{name}] {result.run.scans_processed} scans in {result.run.wall_s:.1f} s",
              flush=True)
        if not result.run.ok:
            print(f"python -m slam_mms: error: {result.run.status_message}", file=sys.stderr)
            status = 1
        elif not written:
            status = 1
        if status:
            break  # stop the run; evaluate and report what exists

    gt_kind = "none"
    for r in results:
        if r.ground_truth is not None:
            gt_kind = r.extra["ground_truth_kind"]
            break
    reference_ns = next((r.extra["outage_reference_ns"] for r in results
                         if r.run.first_scan_start_ns is not None), reader.scan_start_ns(0))
    text = _C.report_to_json(
        str(path), max(r.run.scans_processed for r in results), duration_s, gt_kind, outages,
        [(r.extra["name"], r.extra["method_report"]) for r in results], gt_map_mme)
    if not _try("report.json", (out / "report.json").write_text, text):
        status = 1
    report = json.loads(text)
    _write_plots(results, gt, gt_kind, outages, reference_ns, out)
    table = _summary_table(results, report)
    _try("summary.txt", (out / "summary.txt").write_text, table)
    print("\n" + table, end="")
    print(f"outputs in {out}", flush=True)
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
    try:
        return _run(args)
    except _UsageError as e:
        print(f"python -m slam_mms: error: {e}", file=sys.stderr)
        return 2
    except (ValueError, FileNotFoundError, IndexError, _C.Error) as e:
        print(f"python -m slam_mms: error: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
