"""The plain-folder and ROS bag readers from Python: a simulated drive written with
write_drive_folder / write_rosbag (the C++ WriteDriveFolder / WriteRosbag) and run through
run_drive gives the KITTI raw drive's trajectory (tests/pipeline/drive_input_equivalence_test.cpp
says why these tolerances: the folder's initial_state.csv holds the attitude in degrees, 1e-9 m;
a bag has no scan end time, 1 mm); lidar_only on a folder; "none" ground truth."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

import slam_mms

pytestmark = pytest.mark.skipif(not slam_mms.HAVE_OPEN_DRIVE or not slam_mms.HAVE_FOLDER_READER,
                                reason="the folder reader / OpenDrive are not built")


def _max_differences(a, b):
    """Largest position [m] and rotation [rad] difference of two DriveResults, same stamps."""
    np.testing.assert_array_equal(a.stamps_ns, b.stamps_ns)
    dp = np.linalg.norm(a.trajectory[:, 1:4] - b.trajectory[:, 1:4], axis=1).max()
    qa, qb = a.trajectory[:, 4:8], b.trajectory[:, 4:8]
    sign = np.where(np.sum(qa * qb, axis=1) < 0, -1.0, 1.0)[:, None]
    chord = np.linalg.norm(qa - sign * qb, axis=1)  # accurate for small angles (arccos is not)
    return dp, (4.0 * np.arcsin(np.minimum(chord / 2.0, 1.0))).max()


@pytest.fixture(scope="module")
def kitti_full(sim_drive):
    return slam_mms.run_drive(sim_drive, mode="full", frames="0:9", ground_truth_map=False)


@pytest.fixture(scope="module")
def sim_folder(sim_drive, tmp_path_factory):
    folder = tmp_path_factory.mktemp("folder") / "drive"
    slam_mms.write_drive_folder(slam_mms.open_drive(sim_drive, frames="0:9"), folder,
                                scan_format="pcd_binary")
    return folder


def test_folder_gives_the_kitti_raw_trajectory(kitti_full, sim_folder):
    reader = slam_mms.open_drive(sim_folder)
    assert isinstance(reader, slam_mms.FolderDriveReader) and len(reader) == 10
    r = slam_mms.run_drive(sim_folder, mode="full")
    assert r.run.complete and len(r.trajectory) == len(kitti_full.trajectory) == 10
    dp, dr = _max_differences(r, kitti_full)
    assert dp <= 1e-9 and dr <= 1e-9, (dp, dr)
    assert r.origin == kitti_full.origin
    # write_drive_folder copies no ground_truth/: the report says so, metrics are null.
    assert r.report["input"]["ground_truth"] == "none" and r.ground_truth is None
    assert r.report["methods"]["full"]["ate_rmse_m"] is None
    assert r.report["methods"]["full"]["mme"] is not None


def test_folder_formats_and_bad_arguments(sim_drive, tmp_path):
    reader = slam_mms.open_drive(sim_drive, frames="0:2")
    slam_mms.write_drive_folder(reader, tmp_path / "ply", scan_format="ply_ascii",
                                gnss_format="nmea", write_point_time=True, nmea_time_decimals=9)
    back = slam_mms.FolderDriveReader(tmp_path / "ply")
    assert len(back) == 3
    np.testing.assert_array_equal(back[1].points, reader[1].points)
    np.testing.assert_array_equal(back.scan_starts_ns, reader.scan_starts_ns)
    with pytest.raises(ValueError, match="scan_format"):
        slam_mms.write_drive_folder(reader, tmp_path / "x", scan_format="las")
    with pytest.raises(ValueError, match="gnss_format"):
        slam_mms.write_drive_folder(reader, tmp_path / "x", gnss_format="rinex")
    with pytest.raises(ValueError):  # not empty, overwrite=False
        slam_mms.write_drive_folder(reader, tmp_path / "ply")


def test_lidar_only_on_a_folder_equals_kitti_raw(sim_drive, sim_folder, slam_mms_run, tmp_path):
    k = slam_mms.run_drive(sim_drive, mode="lidar_only", frames="0:9", ground_truth_map=False)
    f = slam_mms.run_drive(sim_folder, mode="lidar_only")
    assert k.run.complete and len(k.trajectory) == 10
    dp, dr = _max_differences(f, k)
    assert dp <= 1e-9 and dr <= 1e-9, (dp, dr)
    # lidar_only: level 1 alone, so its level-1 poses are its trajectory.
    np.testing.assert_array_equal(k.run.level1_trajectory.tum, k.trajectory)
    assert len(k.map_points) > 0
    assert set(k.report["methods"]) == {"lidar_only"}
    assert k.report["input"]["ground_truth"] == "simulator"
    assert k.report["methods"]["lidar_only"]["ate_rmse_m"] > 0
    # The app's --folder run writes the same lidar_only trajectory, byte for byte.
    out = tmp_path / "cpp"
    proc = subprocess.run([str(slam_mms_run), "--folder", str(sim_folder), "--out", str(out),
                           "--mode", "lidar_only"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    f.run.level1_trajectory.write_tum(tmp_path / "level1.tum")
    assert (tmp_path / "level1.tum").read_bytes() == (out / "lidar_only_level1.tum").read_bytes()
    f.write_tum(tmp_path / "lidar_only.tum")
    assert (tmp_path / "lidar_only.tum").read_bytes() == (out / "lidar_only.tum").read_bytes()


@pytest.mark.skipif(not slam_mms.HAVE_ROSBAG_READER, reason="the rosbag module is not built")
def test_rosbag_gives_the_kitti_raw_trajectory(sim_drive, kitti_full, tmp_path):
    reader = slam_mms.open_drive(sim_drive, frames="0:9")
    bag = tmp_path / "drive.bag"
    slam_mms.write_rosbag(reader, bag)
    topics = {name for name, _, _ in slam_mms.RosbagDriveReader.list_topics(bag)}
    assert {"/velodyne_points", "/imu/data", "/gps/fix"} <= topics
    # A bag holds no calibration: the extrinsics.yaml of a folder, passed as extrinsics=.
    yaml = tmp_path / "extrinsics.yaml"
    slam_mms.write_extrinsics_yaml(yaml, reader.streams.T_body_lidar,
                                   reader.streams.t_body_antenna_m,
                                   reader.streams.imu_frame_is_vehicle_frame)
    r = slam_mms.run_drive(bag, mode="full", extrinsics=yaml)
    assert isinstance(r.reader, slam_mms.RosbagDriveReader)
    assert r.reader.streams.imu_frame_is_vehicle_frame  # stated by the file, as KITTI raw states it
    assert r.run.complete and len(r.trajectory) == 10
    dp, dr = _max_differences(r, kitti_full)
    assert dp <= 1e-3 and dr <= 1e-4, (dp, dr)
    assert r.report["input"]["ground_truth"] == "none"
    with pytest.raises(ValueError, match="lidar_topic|topic"):
        slam_mms.run_drive(bag, lidar_topic="/nope")
