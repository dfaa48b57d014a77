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


def test_python_m_slam_mms_run_writes_what_the_app_writes(sim_drive, slam_mms_run, tmp_path):
    out = tmp_path / "py"
    cmd = [sys.executable, "-m", "slam_mms", "run", "--kitti-raw", str(sim_drive), "--out",
           str(out), "--frames", "0:9", "--mode", "gnss_ins"]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=_python_env(), timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    app = run_app(slam_mms_run, sim_drive, tmp_path / "cpp", "--frames", "0:9", "--mode",
                  "gnss_ins")
    # Both written by the C++ TUM writer from the same RunDrive trajectory: byte-identical.
    assert (out / "gnss_ins.tum").read_bytes() == (app / "gnss_ins.tum").read_bytes()
    assert (out / "ground_truth.tum").read_bytes() == (app / "ground_truth.tum").read_bytes()
    for f in ("gnss_ins.kitti", "gnss_ins_cov.csv", "map_gnss_ins.ply", "map_gnss_ins.las"):
        assert (out / f).stat().st_size > 0, f
    ours = json.loads((out / "report.json").read_text())
    theirs = json.loads((app / "report.json").read_text())
    assert set(ours) == set(theirs) and set(ours["methods"]) == {"gnss_ins"}
    assert ours["methods"]["gnss_ins"]["ate_rmse_m"] == pytest.approx(
        theirs["methods"]["gnss_ins"]["ate_rmse_m"], rel=1e-12)


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
