"""Readers as iterators, the evaluation bindings, the simulator, python -m slam_mms run, the
quickstart example."""

from __future__ import annotations

import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import slam_mms
from conftest import REPO, run_app


def test_kitti_reader_iterates_scans_and_streams(sim_drive):
    reader = slam_mms.KittiRawReader(sim_drive)
    assert len(reader) == 20 and reader.has_imu_100hz
    scans = list(reader)
    assert [s.index for s in scans] == list(range(20))
    for s in scans[:3]:
        assert s.points.dtype == np.float32 and s.points.shape == (len(s), 3)
        assert s.stamp_end_ns > s.stamp_start_ns
        assert 0.0 <= s.times.min() and s.times.max() <= s.duration_s + 1e-6
    np.testing.assert_array_equal(reader.scan_starts_ns, [s.stamp_start_ns for s in scans])
    assert reader[-1].index == 19
    with pytest.raises(IndexError):
        reader[20]
    st = reader.streams
    assert st.imu.shape == (len(st.imu_stamps_ns), 7) and len(st.imu_stamps_ns) > 100
    assert np.all(np.diff(st.imu_stamps_ns) > 0)
    assert st.gnss.shape == (len(st.gnss_stamps_ns), 6)
    assert 48 < st.gnss[0, 1] < 50  # latitude of the default origin (Karlsruhe)
    assert st.initial_state is not None and len(st.imu_source) == len(st.imu_stamps_ns)
    np.testing.assert_array_equal(reader.T_body_lidar, st.T_body_lidar)


def test_reader_frame_range_and_errors(sim_drive, tmp_path):
    assert len(slam_mms.open_drive(sim_drive, frames="3:7")) == 5
    assert len(slam_mms.open_drive(sim_drive, frames=(0, 0))) == 1
    with pytest.raises(ValueError, match="frames"):
        slam_mms.open_drive(sim_drive, frames="7")
    with pytest.raises((FileNotFoundError, ValueError, slam_mms.Error)):
        slam_mms.KittiRawReader(tmp_path / "no_such_drive")


def test_open_drive_kitti_vertical_correction(sim_drive):
    # Every point raised by the angle (KITTI's HDL-64E defect), ranges kept.
    plain = slam_mms.open_drive(sim_drive, frames="0:0")[0].points.astype(np.float64)
    raised = slam_mms.open_drive(sim_drive, frames="0:0",
                                 kitti_vertical_correction_deg=0.205)[0].points.astype(np.float64)
    np.testing.assert_allclose(np.linalg.norm(raised, axis=1), np.linalg.norm(plain, axis=1),
                               atol=1e-4)
    def elevation(p):
        return np.degrees(np.arctan2(p[:, 2], np.linalg.norm(p[:, :2], axis=1)))
    np.testing.assert_allclose(elevation(raised) - elevation(plain), 0.205, atol=1e-3)
    with pytest.raises((ValueError, slam_mms.Error)):
        slam_mms.open_drive(sim_drive, kitti_vertical_correction_deg=7.0)


def test_kitti_calibration_file_overrides_and_run_drive_calibrates(sim_drive, tmp_path):
    # A calib_imu_to_velo.txt with a LiDAR clock offset (what slam_mms_run
    # --calibrate-extrinsics writes) taken by open_drive over a KITTI drive's own calibration.
    calib = tmp_path / "calib.txt"
    calib.write_text("calib_time: test\nR: 1 0 0 0 1 0 0 0 1\nT: -0.8 0.3 -0.9\n"
                     "lidar_time_offset_s: 0.02\n")
    base = slam_mms.open_drive(sim_drive)
    shifted = slam_mms.open_drive(sim_drive, extrinsics=calib)
    np.testing.assert_allclose(shifted.streams.T_body_lidar[:3, 3], [0.8, -0.3, 0.9])
    assert shifted[0].stamp_start_ns - base[0].stamp_start_ns == 20_000_000
    # run_drive runs the boresight self-calibration first (RunDrive's estimate_extrinsics).
    res = slam_mms.run_drive(sim_drive, mode="gnss_ins", evaluate=False,
                             calibrate_extrinsics=True)
    cal = res.run.extrinsic_calibration
    assert cal is not None and cal["scans_used"] >= 10
    T0 = base.streams.T_body_lidar
    np.testing.assert_allclose(cal["T_body_lidar_initial"], T0, atol=1e-12)
    # The simulator's calibration file is its truth: the estimate stays near it.
    assert np.linalg.norm(cal["T_body_lidar_estimated"][:3, 3] - T0[:3, 3]) < 0.1
    assert set(cal["observable"]) == {"roll", "pitch", "yaw", "x", "y", "z", "time_offset"}
    plain = slam_mms.run_drive(sim_drive, mode="gnss_ins", evaluate=False)
    assert plain.run.extrinsic_calibration is None
    # The keys moved from level2 to drive, and a system-only caller refuses drive keys.
    with pytest.raises(ValueError, match="moved to 'drive.estimate_extrinsics'"):
        slam_mms.apply_config_text("level2:\n  estimate_extrinsics: true\n", slam_mms.Options())
    with pytest.raises(ValueError, match="drive"):
        slam_mms.apply_config_text("drive.estimate_extrinsics: true\n", slam_mms.Options())


def test_eval_metrics_on_known_errors():
    n = 50
    t = 1_000_000_000 + np.arange(n, dtype=np.int64) * 100_000_000
    tum = np.zeros((n, 8))
    tum[:, 0] = t * 1e-9
    tum[:, 1] = np.arange(n) * 1.0  # 1 m per frame east, curving north (not collinear)
    tum[:, 2] = 0.01 * np.arange(n) ** 2
    tum[:, 7] = 1.0
    gt = slam_mms.Trajectory(tum, stamps_ns=t)
    shifted = tum.copy()
    shifted[:, 2] += 0.5  # 0.5 m north everywhere
    est = slam_mms.Trajectory(shifted, stamps_ns=t)
    ate = slam_mms.compute_ate(est, gt)
    assert ate.num_matched == n
    assert ate.ate_rmse_m == pytest.approx(0.5)
    np.testing.assert_allclose(ate.ate_rmse_xyz_m, [0, 0.5, 0], atol=1e-12)
    assert slam_mms.compute_ate(est, gt, slam_mms.Alignment.SE3).ate_rmse_m < 1e-9
    rel = slam_mms.compute_relative_error(est, gt, "short")
    assert rel.num_segments > 0 and rel.t_rel_pct == pytest.approx(0.0, abs=1e-9)
    out = slam_mms.compute_outage_errors(ate, [(1.0, 2.0)], int(t[0]))
    assert out.num_poses == 20 and out.max_pos_err_m == pytest.approx(0.5)
    report = json.loads(slam_mms.report_to_json(
        "d", n, 4.9, "simulator", [(1.0, 2.0)],
        [("full", slam_mms.make_method_report(ate, rel, out, None))]))
    m = report["methods"]["full"]
    assert m["ate_rmse_m"] == pytest.approx(0.5) and m["mme"] is None
    assert report["gnss_outages"] == [[1.0, 2.0]]


def test_map_entropy_sharper_for_a_plane():
    rng = np.random.default_rng(1)
    plane = np.c_[rng.uniform(0, 5, (20000, 2)), rng.normal(0, 0.001, 20000)].astype(np.float32)
    blurred = plane.copy()
    blurred[:, 2] = rng.normal(0, 0.05, 20000)
    e_plane = slam_mms.compute_map_entropy(plane).mean_map_entropy
    e_blur = slam_mms.compute_map_entropy(blurred).mean_map_entropy
    assert e_plane < e_blur


def _python_env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in sys.path if p)
    env["MPLBACKEND"] = "Agg"
    return env


# Files whose bytes depend on the run's timing or on threads: per-scan stage times, scans/s and
# peak RSS, and the covariances of full/lidar_only (their last bits vary from run to run of the
# app itself; compared to 1e-9 relative).
_TIMED = {"report.json", "report.html", "summary.txt", "full_scans.csv", "gnss_ins_scans.csv",
          "lidar_only_scans.csv", "full_cov.csv", "lidar_only_cov.csv", "gnss_ins_cov.csv"}


def test_python_m_slam_mms_run_writes_what_the_app_writes(sim_drive, slam_mms_run, tmp_path):
    args = ["--frames", "0:7", "--mode", "all", "--gnss-outage", "0.3:0.4"]
    out = tmp_path / "py"
    cmd = [sys.executable, "-m", "slam_mms", "run", "--kitti-raw", str(sim_drive), "--out",
           str(out), *args]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=_python_env(), timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    app = run_app(slam_mms_run, sim_drive, tmp_path / "cpp", *args)
    expected = {p.name for p in app.iterdir() if p.is_file()}
    for f in ("full.tum", "full_level1.tum", "lidar_only_level1.tum", "full_scans.csv",
              "map_gnss_ins.las", "ground_truth.tum", "trajectories.png", "position_error.png",
              "map_full_height.png", "map_gnss_ins_height.png", "summary.txt", "report.json"):
        assert f in expected, f
    assert expected <= {p.name for p in out.iterdir() if p.is_file()}
    # Written by the same C++ writers and plot code from the same RunDrive results: the same bytes.
    for f in sorted(expected - _TIMED):
        assert (out / f).read_bytes() == (app / f).read_bytes(), f
    for f in ("full_cov.csv", "lidar_only_cov.csv", "gnss_ins_cov.csv",
              "gnss_ins_smoothed_cov.csv"):
        a = np.loadtxt(out / f, delimiter=",", skiprows=1)
        b = np.loadtxt(app / f, delimiter=",", skiprows=1)
        np.testing.assert_array_equal(a[:, :8], b[:, :8])  # stamp and pose
        np.testing.assert_allclose(a[:, 8:], b[:, 8:], rtol=1e-9, atol=1e-300)
    for f in ("full_scans.csv", "lidar_only_scans.csv"):
        ours = [line.split(",")[:15] for line in (out / f).read_text().splitlines()]
        theirs = [line.split(",")[:15] for line in (app / f).read_text().splitlines()]
        assert ours == theirs, f  # all but the stage times
    ours = json.loads((out / "report.json").read_text())
    theirs = json.loads((app / "report.json").read_text())
    for m in ours["methods"].values():
        assert m.pop("scans_per_s") > 0 and m.pop("peak_rss_mb") > 0
    for m in theirs["methods"].values():
        del m["scans_per_s"], m["peak_rss_mb"]
    # The command lines differ by nature (python -m slam_mms run vs the app).
    ours.pop("command_line", None)
    theirs.pop("command_line", None)
    assert ours == theirs
    assert list(ours["methods"]) == ["full", "gnss_ins", "gnss_ins_smoothed", "lidar_only"]
    assert ours["input"]["ground_truth"] == "simulator" and ours["gnss_outages"] == [[0.3, 0.4]]
    n = 1 + len(ours["methods"])  # the header and one row per method, then the notes
    ours = (out / "summary.txt").read_text().splitlines()
    theirs = (app / "summary.txt").read_text().splitlines()
    assert [r.split()[:7] for r in ours[:n]] == [r.split()[:7] for r in theirs[:n]]
    assert ours[n:] == theirs[n:]


def test_python_m_slam_mms_run_on_a_folder_without_ground_truth(sim_drive, tmp_path):
    if not slam_mms.HAVE_FOLDER_READER:
        pytest.skip("the folder reader is not built")
    folder = tmp_path / "folder"
    slam_mms.write_drive_folder(slam_mms.open_drive(sim_drive, frames="0:4"), folder)
    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "slam_mms", "run", "--folder", str(folder),
                           "--out", str(out), "--mode", "gnss_ins"], capture_output=True,
                          text=True, env=_python_env(), timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    report = json.loads((out / "report.json").read_text())
    assert report["input"]["ground_truth"] == "none" and report["input"]["scans"] == 5
    assert report["methods"]["gnss_ins"]["ate_rmse_m"] is None
    assert not (out / "ground_truth.tum").exists() and not (out / "trajectories.png").exists()
    assert (out / "map_gnss_ins_height.png").stat().st_size > 1000
    assert "against the none ground truth" in (out / "summary.txt").read_text()
    # A bag topic without --rosbag is a usage error (exit 2), as in slam_mms_run.
    proc = subprocess.run([sys.executable, "-m", "slam_mms", "run", "--folder", str(folder),
                           "--out", str(out), "--lidar-topic", "/x"], capture_output=True,
                          text=True, env=_python_env())
    assert proc.returncode == 2 and "--rosbag" in proc.stderr


def test_cli_bad_arguments_exit_2(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "slam_mms", "run", "--out", str(tmp_path),
                           "--gnss-outage", "abc"], capture_output=True, text=True,
                          env=_python_env())
    assert proc.returncode == 2 and "START_S:DURATION_S" in proc.stderr


def test_quickstart_example_runs(tmp_path):
    script = REPO / "examples" / "python" / "quickstart.py"
    proc = subprocess.run([sys.executable, str(script), str(tmp_path), "--duration", "2"],
                          capture_output=True, text=True, env=_python_env(), timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    for png in ("scan0.png", "trajectories.png", "position_error.png", "map.png"):
        assert (tmp_path / png).stat().st_size > 10_000, png
    assert "ATE" in proc.stdout


def test_version_is_the_cmake_project_version():
    text = (REPO / "CMakeLists.txt").read_text()
    assert f"project(slam_mms VERSION {slam_mms.__version__} " in text
