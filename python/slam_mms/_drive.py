"""Whole drives: open_drive, run_drive (the C++ RunDrive + slam_mms_run's evaluation) and
simulate_drive."""

from __future__ import annotations

import json
import logging
import os
import pathlib
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Optional, Sequence, Tuple, Union

import numpy as np

from . import _C

PathLike = Union[str, "os.PathLike[str]"]
Frames = Union[None, str, Tuple[int, int], Sequence[int]]

_log = logging.getLogger("slam_mms")


def _parse_frames(frames: Frames) -> Tuple[int, int]:
    """None -> all; "A:B" or (A, B) -> inclusive file/scan numbers (B = -1: to the end)."""
    if frames is None:
        return 0, -1
    if isinstance(frames, str):
        parts = frames.split(":")
        if len(parts) != 2:
            raise ValueError(f"frames = {frames!r}; expected 'A:B' (inclusive)")
        try:
            first, last = int(parts[0]), int(parts[1]) if parts[1] else -1
        except ValueError:
            raise ValueError(f"frames = {frames!r}; expected integers 'A:B'") from None
    else:
        try:
            first, last = (int(v) for v in frames)  # type: ignore[misc]
        except (TypeError, ValueError):
            raise ValueError(f"frames = {frames!r}; expected (first, last)") from None
    if first < 0 or (last != -1 and last < first):
        raise ValueError(f"frames = {frames!r}; need 0 <= first <= last (or last = -1)")
    return first, last


def open_drive(path: PathLike, frames: Frames = None, kind: str = "auto",
               lidar_topic: str = "", imu_topic: str = "", gnss_topic: str = "",
               extrinsics: PathLike = "",
               kitti_vertical_correction_deg: float = 0.0) -> "_C.DriveReader":
    """Opens a drive as a :class:`DriveReader` through the C++ ``OpenDrive``: a KITTI raw drive
    folder, a plain drive folder (with scans.csv) or a ROS 1 bag (``.bag``; where the library was
    built with it). ``frames``: ``"A:B"`` or ``(A, B)``, inclusive (KITTI file numbers, else scan
    numbers). ``kitti_vertical_correction_deg``: KITTI's own recordings only, every point rotated
    up by this angle (0.205, as KISS-ICP; see ``slam_mms_run --kitti-vertical-correction``).
    Errors name the file: FileNotFoundError, ValueError, :class:`slam_mms.Error`."""
    first, last = _parse_frames(frames)
    if _C.HAVE_OPEN_DRIVE:
        return _C._open_drive(os.fspath(path), kind, first, last, lidar_topic, imu_topic,
                              gnss_topic, os.fspath(extrinsics),
                              float(kitti_vertical_correction_deg))
    if kind not in ("auto", "kitti_raw"):
        raise ValueError(f"kind = {kind!r}: this build reads KITTI raw drives only")
    options = _C.KittiRawReaderOptions()
    options.first_frame, options.last_frame = first, last
    if kitti_vertical_correction_deg:
        options.vertical_angle_correction = True
        options.vertical_correction_deg = float(kitti_vertical_correction_deg)
    return _C.KittiRawReader(os.fspath(path), options)


@dataclass
class DriveResult:
    """What :func:`run_drive` returns.

    Attributes:
        trajectory: N x 8 float64 TUM rows ``[t_s x y z qx qy qz qw]`` of ``T_world_body`` at each
            processed scan's start (``t_s`` is rounded to float64; exact stamps in ``stamps_ns``).
        stamps_ns: (N,) int64 exact stamps.
        covariances: N x 6 x 6 pose covariances (rotation first), NaN where none.
        map_points: M x 4 float32 ``[x y z intensity]`` in world (local ENU at ``origin``).
        report: the report.json dict (written by the C++ report writer), or None when
            ``evaluate=False``: ``{"input": {"drive", "scans", "duration_s", "ground_truth"},
            "gnss_outages": [[start_s, duration_s], ...], "methods": {mode: {"ate_rmse_m",
            "ate_rmse_xyz_m", "rot_rmse_deg", "rot_rmse_rpy_deg", "rot_mean_rpy_deg", "t_rel_pct",
            "r_rel_deg_per_100m", "max_pos_err_in_outage_m", "max_rot_err_in_outage_deg", "mme",
            "scans_per_s", "peak_rss_mb"}}, "ground_truth_map": {"mme"}}``; metrics that could
            not be computed (no ground truth, too short for any segment) are None;
            ``input.ground_truth`` is ``"simulator"``, ``"oxts"`` or ``"none"``.
        run: the C++ ``DriveRun`` (results per scan, counts, skipped scans, status, timing).
        origin: WGS-84 origin of world (GeodeticPoint) or None.
        ground_truth: the ground truth in world (Trajectory) when one was found, else None.
        ate, relative_error, outage_errors, map_entropy: the eval results behind the report.
        options: the MappingSystem options used.
        reader: the DriveReader that was run.
    """

    trajectory: np.ndarray
    stamps_ns: np.ndarray
    covariances: np.ndarray
    map_points: np.ndarray
    report: Optional[dict]
    run: Any
    origin: Any
    options: Any
    reader: Any
    ground_truth: Any = None
    ate: Any = None
    relative_error: Any = None
    outage_errors: Any = None
    map_entropy: Any = None
    extra: dict = field(default_factory=dict)

    @property
    def results(self) -> list:
        """Per-scan level-1 results (LocalizationResult)."""
        return self.run.results

    def write_tum(self, path: PathLike) -> None:
        """Writes the trajectory as slam_mms_run does (exact stamps, %.17g numbers)."""
        self.run.trajectory.write_tum(os.fspath(path))


def _mode_of(mode: Union[str, "_C.MappingMode"]) -> "_C.MappingMode":
    if isinstance(mode, _C.MappingMode):
        return mode
    return _C.parse_mapping_mode(str(mode))


def _pos_of(pos: Union[str, "_C.PosWorkflow"]) -> "_C.PosWorkflow":
    if isinstance(pos, _C.PosWorkflow):
        return pos
    if pos == "forward":
        return _C.PosWorkflow.FORWARD
    if pos == "smoothed":
        return _C.PosWorkflow.SMOOTHED
    raise ValueError(f"pos = {pos!r}; must be 'forward' or 'smoothed'")


def _ground_truth_dir(path: pathlib.Path) -> pathlib.Path:
    # slam_mms_run: the drive or folder itself, the folder of a bag.
    return path.parent if path.is_file() else path


# report.json's input.kind of each reader type (as slam_mms_run's, for a drive it did not simulate).
_READER_KINDS = {"KittiRawReader": "kitti_raw", "FolderDriveReader": "folder",
                 "RosbagDriveReader": "rosbag"}


def _split_skipped(entry: str) -> Tuple[str, str]:
    """DriveRun.skipped_scans' "<source>: <reason>" as (source, reason), as slam_mms_run splits it."""
    source, sep, reason = entry.partition(": ")
    if not sep:
        return entry, ""
    if reason.startswith(source + ": "):
        reason = reason[len(source) + 2:]
    return source, reason


def _relative_lengths(ate) -> str:
    """The devkit's 100..800 m ("kitti") where the ground-truth path matched by `ate` is at least
    400 m long, else 10..80 m ("short"), as slam_mms_run chooses."""
    path_m = 0.0
    if ate is not None:
        p = ate.p_gt_world
        path_m = float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum()) if len(p) else 0.0
    return "kitti" if path_m >= 400.0 else "short"


def _evaluate(result: DriveResult, drive: pathlib.Path, gnss_outages, num_threads: int,
              ground_truth_map: bool) -> dict:
    """slam_mms_run's evaluation of one method (examples/apps/slam_mms_run/outputs.cpp,
    EvaluateMethod) through the eval bindings; the JSON is the C++ report writer's."""
    run, reader = result.run, result.reader
    gt = None
    gt_kind = None
    if run.origin is not None:
        try:
            loaded = _C.load_ground_truth(os.fspath(_ground_truth_dir(drive)), reader, run.origin)
            gt, gt_kind = loaded["trajectory"], loaded["kind"]
            result.ground_truth = gt
            result.extra["scene_map"] = loaded["scene_map"]
        except FileNotFoundError as e:
            _log.info("no ground truth: %s", e)
    else:
        _log.warning("%s: world origin unknown, no metrics", _C.mapping_mode_name(run.mode))
    reference_ns = run.first_scan_start_ns
    if reference_ns is None and len(reader):
        reference_ns = reader.scan_start_ns(0)
    nees = None
    if gt is not None and len(run.trajectory) and run.mode in (_C.MappingMode.GNSS_INS,
                                                              _C.MappingMode.GNSS_INS_SMOOTHED):
        # The POS's covariances are absolute (level 1's are relative to their submap).
        try:
            nees = _C.compute_nees(run.trajectory, gt)
        except (ValueError, IndexError, _C.Error) as e:
            _log.warning("NEES: %s", e)
    if gt is not None and len(run.trajectory):
        try:
            result.ate = _C.compute_ate(run.trajectory, gt)
            result.outage_errors = _C.compute_outage_errors(result.ate, list(gnss_outages),
                                                            reference_ns)
        except (ValueError, IndexError, _C.Error) as e:
            _log.warning("ATE: %s", e)
        if len(run.trajectory) >= 2:
            lengths = _relative_lengths(result.ate)
            result.extra["relative_label"] = {"kitti": "kitti_100-800m",
                                              "short": "short_10-80m"}[lengths]
            try:
                result.relative_error = _C.compute_relative_error(run.trajectory, gt, lengths)
            except (ValueError, IndexError, _C.Error) as e:
                _log.warning("relative error: %s", e)
    if len(result.map_points):
        try:
            result.map_entropy = _C.compute_map_entropy(result.map_points,
                                                        num_threads=num_threads)
        except (ValueError, _C.Error) as e:
            _log.warning("map entropy: %s", e)
    method = _C.make_method_report(result.ate, result.relative_error, result.outage_errors,
                                   result.map_entropy, nees)
    if gt_kind == "oxts" and len(run.trajectory):
        # The second reference slam_mms_run reports (run_report.cpp): the OXTS velocities
        # integrated from the first record, sharper over seconds than its positions.
        try:
            vel = _C.load_oxts_ground_truth(reader, run.origin, "velocity")["trajectory"]
            result.extra["oxts_velocity_reference"] = vel
            v_ate = _C.compute_ate(run.trajectory, vel)
            v_out = _C.compute_outage_errors(v_ate, list(gnss_outages), reference_ns)
            v_rel = None
            if len(run.trajectory) >= 2:
                v_rel = _C.compute_relative_error(run.trajectory, vel, _relative_lengths(v_ate))
            method.vs_oxts_velocity = _C.make_reference_metrics(v_ate, v_rel, v_out)
        except (FileNotFoundError, ValueError, IndexError, _C.Error) as e:
            _log.warning("OXTS velocity reference: %s", e)
    method.scans_per_s = run.scans_processed / run.wall_s if run.wall_s > 0 else 0.0
    method.peak_rss_mb = _C.peak_rss_mb()
    gt_map_mme = None
    scene = result.extra.get("scene_map")
    if ground_truth_map and scene and os.fspath(scene):
        try:
            e = _C.compute_map_entropy(_C.read_ply(os.fspath(scene)), num_threads=num_threads)
            gt_map_mme = e.mean_map_entropy
        except (ValueError, FileNotFoundError, _C.Error) as err:
            _log.warning("ground-truth map: %s", err)
    duration_s = 0.0
    if len(reader):
        duration_s = (reader.scan_end_ns(len(reader) - 1) - reader.scan_start_ns(0)) * 1e-9
    text = _C.report_to_json(
        str(drive), run.scans_processed, duration_s, gt_kind or "none",
        [(float(s), float(d)) for s, d in gnss_outages],
        [(_C.mapping_mode_name(run.mode), method)], gt_map_mme,
        kind=_READER_KINDS.get(type(reader).__name__, ""), scans_total=len(reader),
        skipped_scans=[_split_skipped(s) for s in run.skipped_scans], complete=run.complete,
        imu_noise=_imu_noise_used(result.options, reader),
        oxts_inertial_delay_s=_C.oxts_inertial_delay_s(reader))
    result.extra["method_report"] = method
    result.extra["ground_truth_kind"] = gt_kind or "none"
    result.extra["ground_truth_map_mme"] = gt_map_mme
    result.extra["outage_reference_ns"] = reference_ns
    return json.loads(text)


def run_drive(path: PathLike, mode: Union[str, "_C.MappingMode"] = "full",
              frames: Frames = None, gnss_outages: Iterable[Tuple[float, float]] = (),
              options: Optional["_C.Options"] = None, config: Optional[PathLike] = None,
              evaluate: bool = True, ground_truth_map: bool = True,
              progress: Optional[Callable[[int, int], None]] = None, check: bool = True,
              kind: str = "auto", pos: str = "forward", calibrate_extrinsics: bool = False,
              **open_kwargs: Any) -> DriveResult:
    """Runs one mapping method over a whole drive with the C++ ``RunDrive`` (the loop
    ``slam_mms_run`` runs), so the trajectory equals slam_mms_run's on the same input and options.

    Args:
        path: a KITTI raw drive folder (…/2011_09_26_drive_0013_sync), a plain drive folder or a
            ROS 1 bag (see :func:`open_drive`).
        mode: "full", "gnss_ins", "gnss_ins_smoothed" or "lidar_only" (or a
            :class:`MappingMode`); gnss_ins_smoothed is offline: the whole IMU/GNSS stream is
            smoothed (forward EKF + Rauch-Tung-Striebel) before the scans are placed.
        pos: "forward" (default, as slam_mms_run --pos) or "smoothed": the POS `full` runs on.
        calibrate_extrinsics: the boresight self-calibration first (as slam_mms_run
            --calibrate-extrinsics; needs IMU, GNSS and an initial attitude), then the run with
            the estimate; ``result.run.extrinsic_calibration`` holds it.
        frames: ``"A:B"`` / ``(A, B)`` inclusive, as ``slam_mms_run --frames A:B``; None = all.
        gnss_outages: ``[(start_s, duration_s), ...]`` relative to the first scan's start.
        options: :class:`Options` to start from (copied; default: the C++ defaults). As the app
            does, T_body_lidar (and the antenna lever arm where the input has one) comes from the
            reader, then mode and gnss_outages are set.
        config: a slam_mms_run ``--config`` file applied to the options first.
        evaluate: compute the metrics and the report dict (ground truth: the simulator's, else
            the KITTI OXTS poses, carried into world through WGS-84; without one only the map
            entropy and speed are filled).
        ground_truth_map: also the map entropy of the simulator's scene (slower).
        progress: ``progress(fed, total)`` after every scan (GIL held while it runs).
        check: raise the run's fatal error (ValueError for bad options, ...) instead of returning
            the partial result (whose ``run.ok`` is then False).

    Returns:
        :class:`DriveResult`. The GIL is released while the drive is processed; Ctrl-C stops
        after the current scan and raises KeyboardInterrupt.
    """
    drive = pathlib.Path(os.fspath(path))
    reader = open_drive(drive, frames=frames, kind=kind, **open_kwargs)
    if len(reader) == 0:
        raise IndexError(f"{reader.describe()}: no scan in the frame range")
    opts = options.copy() if options is not None else _C.Options()
    if config is not None:
        _C.apply_config_file(os.fspath(config), opts)
    outages = [(float(s), float(d)) for s, d in gnss_outages]
    _options_for_reader(opts, reader, outages)
    return _run_reader(reader, drive, mode, opts, outages, evaluate, ground_truth_map, progress,
                       check, pos, calibrate_extrinsics)


def _options_for_reader(opts: "_C.Options", reader: "_C.DriveReader", outages) -> None:
    """As slam_mms_run: T_body_lidar (and the antenna lever arm where the input has one) from the
    reader, then the outage windows."""
    streams = reader.streams
    opts.T_body_lidar = streams.T_body_lidar
    if streams.t_body_antenna_m is not None:
        opts.ins.gnss.t_body_antenna = streams.t_body_antenna_m
    opts.gnss_outages = list(outages)


def _imu_noise_used(options: "_C.Options", reader) -> str:
    """Where the run's IMU noise model came from, as slam_mms_run reports it ('' = defaults)."""
    streams = reader.streams
    if options.use_stated_imu_noise and streams.imu_noise is not None:
        return streams.imu_noise_source
    return ""


def _run_reader(reader, drive: pathlib.Path, mode, options: "_C.Options", outages,
                evaluate: bool = True, ground_truth_map: bool = True, progress=None,
                check: bool = True, pos: str = "forward",
                calibrate_extrinsics: bool = False) -> DriveResult:
    """One method over an opened reader with `options` (copied; mode set here)."""
    opts = options.copy()
    opts.mode = _mode_of(mode)
    # gnss_ins_smoothed is RunDrive's (offline): MappingSystem itself runs it as gnss_ins.
    check_opts = opts.copy()
    if check_opts.mode == _C.MappingMode.GNSS_INS_SMOOTHED:
        check_opts.mode = _C.MappingMode.GNSS_INS
    check_opts.validate()
    workflow = _pos_of(pos)
    run = _C._run_drive(reader, opts, progress, workflow, bool(calibrate_extrinsics))
    if check:
        run.raise_if_error()
    traj = run.trajectory
    result = DriveResult(trajectory=traj.tum, stamps_ns=traj.stamps_ns,
                         covariances=traj.covariances, map_points=run.map_points, report=None,
                         run=run, origin=run.origin, options=opts, reader=reader)
    if evaluate:
        result.report = _evaluate(result, drive, outages, opts.num_threads, ground_truth_map)
    return result


def simulate_drive(out_dir: PathLike, scenario: str = "default", duration_s: float = 30.0,
                   seed: int = 1, oxts_drive_dir: Optional[PathLike] = None,
                   write_scene_cloud: bool = True, num_threads: int = 2,
                   progress: Optional[Callable[[int, int], None]] = None) -> pathlib.Path:
    """Simulates a KITTI-raw-like drive with true ground truth (the C++ DriveSimulator) under
    ``out_dir`` and returns the drive folder (``out_dir/<date>/<date>_drive_<id>_sync``).

    ``scenario``: "default" (the embedded urban drive, ~190 s) or "long"; ``duration_s``: seconds
    of scans (0 = the whole drive); ``oxts_drive_dir``: a KITTI OXTS drive to follow instead.
    """
    summary = _C._simulate_drive(os.fspath(out_dir), scenario, float(duration_s), int(seed),
                                 None if oxts_drive_dir is None else os.fspath(oxts_drive_dir),
                                 bool(write_scene_cloud), int(num_threads), progress)
    return pathlib.Path(os.fspath(summary["drive_dir"]))
