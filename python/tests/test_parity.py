"""The same drive through Python (run_drive -> C++ RunDrive) and through slam_mms_run gives
identical trajectories, compared bit for bit with the TUM files the app writes."""

from __future__ import annotations

import json

import numpy as np
import pytest

import slam_mms
from conftest import read_tum_exact, run_app


def _assert_same(result, tum_file):
    stamps, values = read_tum_exact(tum_file)
    assert len(stamps) == len(result.stamps_ns) > 0
    np.testing.assert_array_equal(result.stamps_ns, stamps)
    # Bitwise: the app writes %.17g (lossless) and the binding computes the TUM row as its writer.
    assert np.array_equal(result.trajectory[:, 1:], values), (
        f"max |diff| = {np.abs(result.trajectory[:, 1:] - values).max()}")
    np.testing.assert_allclose(result.trajectory[:, 0], stamps * 1e-9, rtol=0, atol=1e-6)


def test_real_frames_full_mode_equal_slam_mms_run(kitti_0013, slam_mms_run, tmp_path):
    out = run_app(slam_mms_run, kitti_0013, tmp_path / "cpp", "--frames", "0:19", "--mode", "full")
    result = slam_mms.run_drive(kitti_0013, mode="full", frames="0:19")
    assert result.run.complete and result.run.scans_processed == 20
    _assert_same(result, out / "full.tum")
    # The report is computed as the app computes it (same ground truth, same metrics).
    app_report = json.loads((out / "report.json").read_text())
    ours = result.report["methods"]["full"]
    theirs = app_report["methods"]["full"]
    for key in ("ate_rmse_m", "rot_rmse_deg", "t_rel_pct", "mme"):
        assert ours[key] == pytest.approx(theirs[key], rel=1e-12), key
    # The second reference (the OXTS velocities integrated), also as the app computes it.
    assert theirs["vs_oxts_velocity"] is not None
    for key, value in theirs["vs_oxts_velocity"].items():
        if value is None:
            assert ours["vs_oxts_velocity"][key] is None, key
        else:
            assert ours["vs_oxts_velocity"][key] == pytest.approx(value, rel=1e-12), key
    assert result.report["input"] == app_report["input"]


@pytest.mark.parametrize("mode", ["full", "gnss_ins"])
def test_simulated_drive_equal_slam_mms_run(sim_drive, slam_mms_run, tmp_path, mode):
    out = run_app(slam_mms_run, sim_drive, tmp_path / "cpp", "--mode", mode,
                  "--gnss-outage", "0.5:1.0")
    result = slam_mms.run_drive(sim_drive, mode=mode, gnss_outages=[(0.5, 1.0)],
                                ground_truth_map=False)
    _assert_same(result, out / f"{mode}.tum")
    assert result.report["input"]["ground_truth"] == "simulator"
    assert result.report["gnss_outages"] == [[0.5, 1.0]]


def test_manual_feed_equals_run_drive(sim_drive):
    """MappingSystem fed from a reader in RunDrive's order gives RunDrive's trajectory."""
    reader = slam_mms.KittiRawReader(sim_drive)
    options = slam_mms.Options()
    options.T_body_lidar = reader.T_body_lidar
    streams = reader.streams
    assert streams.imu_noise is not None  # the simulator states its IMU (imu_noise.yaml)
    assert streams.imu_frame_is_vehicle_frame  # KITTI raw: the OXTS frame is the car's
    stated = options.copy()  # what apply_input_models does where the models are switched on
    stated.use_stated_imu_noise = True  # the default (docs/ins.md)
    stated.vehicle_nhc_sigma_mps = 0.05  # the default
    stated = slam_mms.apply_input_models(stated, streams)
    assert stated.ins.gyro_noise_density == streams.imu_noise.gyro_noise_density
    assert stated.ins.nhc_sigma_mps == 0.05
    options = slam_mms.apply_input_models(options, streams)  # as run_drive does (the defaults)
    system = slam_mms.MappingSystem(options)
    system.initialize_pos(streams.initial_state, streams.initial_attitude_sigma_rpy_rad)
    imu, gnss = streams.imu_samples, streams.gnss_fixes
    i = g = 0
    for k in range(len(reader)):
        end = reader.scan_end_ns(k)
        while True:  # IMU, then GNSS, then the scan at equal stamps
            t_i = imu[i].stamp_ns if i < len(imu) else None
            t_g = gnss[g].stamp_ns if g < len(gnss) else None
            if t_i is not None and t_i <= end and (t_g is None or t_i <= t_g):
                system.add_imu(imu[i])
                i += 1
            elif t_g is not None and t_g <= end:
                system.add_gnss(gnss[g])
                g += 1
            else:
                break
        scan = reader[k]
        # Through the numpy path (float32 N x 3 + times + intensities), not the Scan object.
        system.add_scan(scan.points, scan.stamp_start_ns, scan.stamp_end_ns, times=scan.times,
                        intensities=scan.intensities, index=scan.index)
    for sample in imu[i:]:
        system.add_imu(sample)
    for fix in gnss[g:]:
        system.add_gnss(fix)
    system.finish()
    tum, cov = system.final_trajectory()
    expected = slam_mms.run_drive(sim_drive, evaluate=False)
    np.testing.assert_array_equal(system.final_stamps_ns(), expected.stamps_ns)
    assert np.array_equal(tum, expected.trajectory)
    assert cov.shape == (len(tum), 6, 6) and np.isfinite(cov).all()
    assert np.array_equal(system.final_map(), expected.map_points)
    assert len(system.results) == len(tum)
    assert system.origin == expected.origin
