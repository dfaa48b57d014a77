// DriveSimulator's calibration errors on purpose: a wrong calib_imu_to_velo.txt
// (Options::calib_error_rpy_deg / calib_error_xyz_m) and a LiDAR clock behind the IMU's
// (Options::lidar_time_offset_s), while the scans and the ground truth stay true.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "slam_mms/io/trajectory_io.hpp"
#include "slam_mms/sim/drive_simulator.hpp"
#include "testing/test_data.hpp"

namespace slam_mms::sim {
namespace {

namespace fs = std::filesystem;

using ScopedDir = testing::ScopedTempDir;

// The T_lidar_body of the file, derived here from the definition in DriveSimulator::Options.
Eigen::Isometry3d ExpectedWritten(const Eigen::Isometry3d& T_lidar_body_true, double yaw_deg,
                                  const Eigen::Vector3d& xyz_m) {
  const Eigen::Isometry3d T_body_lidar_true = T_lidar_body_true.inverse();
  Eigen::Isometry3d T_body_lidar_written = Eigen::Isometry3d::Identity();
  T_body_lidar_written.linear() =
      Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ()).toRotationMatrix() *
      T_body_lidar_true.linear();
  T_body_lidar_written.translation() = T_body_lidar_true.translation() + xyz_m;
  return T_body_lidar_written.inverse();
}

Eigen::Matrix4d JsonMatrix(const nlohmann::json& a) {
  EXPECT_EQ(a.size(), 16u);
  Eigen::Matrix4d M = Eigen::Matrix4d::Zero();
  for (int k = 0; k < 16 && k < static_cast<int>(a.size()); ++k) {
    M(k / 4, k % 4) = a[static_cast<size_t>(k)].get<double>();
  }
  return M;
}

TEST(CalibrationErrorTest, WritesTheWrongCalibrationAndDelayedScanStamps) {
  const ScopedDir dir("sim_calib_error");
  DriveSimulator::Options o;
  o.seed = 3;
  o.lead_in_s = 4.0;
  o.duration_s = 0.3;
  o.write_scene_cloud = false;
  o.calib_error_rpy_deg = Eigen::Vector3d(0.0, 0.0, 1.0);
  o.calib_error_xyz_m = Eigen::Vector3d(0.05, 0.0, 0.0);
  o.lidar_time_offset_s = 0.02;
  auto sim = DriveSimulator::Create(o);
  ASSERT_TRUE(sim.ok()) << sim.status().ToString();
  auto s = sim->Run(dir.path);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  ASSERT_EQ(s->num_scans, 3);

  // The file: the error applied about the body axes (10 digits written).
  const Eigen::Isometry3d expected =
      ExpectedWritten(o.T_lidar_body, 1.0, Eigen::Vector3d(0.05, 0.0, 0.0));
  auto written = ReadKittiRigidCalibration(s->date_dir / "calib_imu_to_velo.txt");
  ASSERT_TRUE(written.ok()) << written.status().ToString();
  EXPECT_LT((written->matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((WrittenTLidarBody(o).matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  // Really wrong: about 1 deg and 5 cm off the truth.
  const Eigen::Isometry3d T_err = o.T_lidar_body.inverse() * *written;  // T_body_body'
  EXPECT_NEAR(Eigen::AngleAxisd(T_err.linear()).angle(), M_PI / 180.0, 1e-6);

  // scenario.json keeps the true calibration and adds what was written.
  std::ifstream f(s->drive_dir / "ground_truth" / "scenario.json");
  const nlohmann::json j = nlohmann::json::parse(f);
  EXPECT_EQ(JsonMatrix(j["T_lidar_body"]), o.T_lidar_body.matrix());
  EXPECT_LT((JsonMatrix(j["T_lidar_body_written"]) - expected.matrix()).cwiseAbs().maxCoeff(),
            1e-12);
  EXPECT_EQ(j["lidar_time_offset_s"].get<double>(), 0.02);
  EXPECT_EQ(j["calib_error_rpy_deg"], nlohmann::json::array({0.0, 0.0, 1.0}));
  EXPECT_EQ(j["calib_error_xyz_m"], nlohmann::json::array({0.05, 0.0, 0.0}));

  // The scan stamps written are 20 ms before the true (IMU clock) ones of the ground truth.
  auto reader = KittiRawReader::Open(s->drive_dir);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  auto gt_start = ReadTrajectoryTum(s->drive_dir / "ground_truth" / "scan_start.tum");
  auto gt_trigger = ReadTrajectoryTum(s->drive_dir / "ground_truth" / "scan_trigger.tum");
  auto gt_end = ReadTrajectoryTum(s->drive_dir / "ground_truth" / "scan_end.tum");
  ASSERT_TRUE(gt_start.ok() && gt_trigger.ok() && gt_end.ok());
  ASSERT_EQ(gt_start->size(), reader->NumScans());
  const Timestamp first_true = sim->trajectory().ToTimestamp(sim->first_scan_s());
  EXPECT_EQ((*gt_start)[0].stamp, first_true);
  constexpr int64_t kOffsetNs = 20000000;
  for (size_t i = 0; i < reader->NumScans(); ++i) {
    SCOPED_TRACE("scan " + std::to_string(i));
    auto scan = reader->ReadScan(i);
    ASSERT_TRUE(scan.ok()) << scan.status().ToString();
    EXPECT_EQ(scan->stamp_start.nanoseconds(), (*gt_start)[i].stamp.nanoseconds() - kOffsetNs);
    EXPECT_EQ(scan->stamp_end.nanoseconds(), (*gt_end)[i].stamp.nanoseconds() - kOffsetNs);
    EXPECT_EQ(reader->ScanTrigger(i).nanoseconds(),
              (*gt_trigger)[i].stamp.nanoseconds() - kOffsetNs);
  }
  // The OXTS records stay on the IMU clock: the 100 Hz records are the ground truth's stamps.
  auto gt_poses = ReadTrajectoryTum(s->drive_dir / "ground_truth" / "poses_100hz.tum");
  ASSERT_TRUE(gt_poses.ok());
  ASSERT_FALSE(reader->ImuOxtsRecords().empty());
  for (const auto& rec : reader->ImuOxtsRecords()) {
    bool found = false;
    for (const auto& p : gt_poses->poses()) found = found || p.stamp == rec.stamp;
    ASSERT_TRUE(found) << rec.stamp.ToKittiString() << " is not a ground-truth stamp";
  }
}

TEST(CalibrationErrorTest, AnImuMountedOffTheCarTurnsTheBodyNotTheCarsMotion) {
  DriveSimulator::Options o;
  o.seed = 3;
  o.lead_in_s = 1.0;
  o.duration_s = 0.3;
  o.write_scene_cloud = false;
  auto plain = DriveSimulator::Create(o);
  ASSERT_TRUE(plain.ok()) << plain.status().ToString();
  o.imu_mount_error_rpy_deg = Eigen::Vector3d(0.3, -0.5, 2.0);
  auto mounted = DriveSimulator::Create(o);
  ASSERT_TRUE(mounted.ok()) << mounted.status().ToString();
  const Eigen::Matrix3d R_car_body =
      FromRollPitchYaw(0.3 * M_PI / 180.0, -0.5 * M_PI / 180.0, 2.0 * M_PI / 180.0);
  const ReferenceTrajectory& a = plain->trajectory();
  const ReferenceTrajectory& b = mounted->trajectory();
  int checked = 0;
  for (double t = a.start_s() + 0.5; t < a.end_s() - 0.5; t += 0.5, ++checked) {
    const BodyState car = a.Evaluate(t), body = b.Evaluate(t);
    // The car's motion is kept ...
    EXPECT_LT((body.T_world_body.translation() - car.T_world_body.translation()).norm(), 1e-3) << t;
    EXPECT_LT((body.v_world_mps - car.v_world_mps).norm(), 1e-3) << t;
    // ... the body is turned by the mount against it.
    const Eigen::Matrix3d expected = car.T_world_body.linear() * R_car_body;
    const double off_deg =
        Eigen::AngleAxisd(expected.transpose() * body.T_world_body.linear()).angle() * 180.0 / M_PI;
    EXPECT_LT(off_deg, 0.01) << t;
    // So the body moves sideways where the car does not: by its speed times the mount's yaw.
    const Eigen::Vector3d v_car = car.T_world_body.linear().transpose() * car.v_world_mps;
    const Eigen::Vector3d v_body = body.T_world_body.linear().transpose() * body.v_world_mps;
    if (v_car.norm() > 3.0) {
      EXPECT_NEAR(std::atan2(-v_body.y(), v_body.x()) - std::atan2(-v_car.y(), v_car.x()),
                  2.0 * M_PI / 180.0, 2e-3)
          << t;
    }
  }
  EXPECT_GT(checked, 4);
}

TEST(CalibrationErrorTest, ValidateNamesTheFieldOutOfRange) {
  auto expect_invalid = [](const DriveSimulator::Options& o, const std::string& field) {
    const Status st = o.Validate();
    EXPECT_EQ(st.code(), StatusCode::kInvalidArgument) << field;
    EXPECT_NE(st.message().find("DriveSimulator::Options::" + field), std::string::npos)
        << st.message();
  };
  DriveSimulator::Options o;
  EXPECT_TRUE(o.Validate().ok());
  o.calib_error_rpy_deg = Eigen::Vector3d(0.0, 10.5, 0.0);
  expect_invalid(o, "calib_error_rpy_deg");
  o.calib_error_rpy_deg = Eigen::Vector3d(NAN, 0.0, 0.0);
  expect_invalid(o, "calib_error_rpy_deg");
  o.calib_error_rpy_deg = Eigen::Vector3d(-10.0, 10.0, 5.0);
  EXPECT_TRUE(o.Validate().ok());
  o.calib_error_xyz_m = Eigen::Vector3d(0.0, 0.0, -1.5);
  expect_invalid(o, "calib_error_xyz_m");
  o.calib_error_xyz_m = Eigen::Vector3d(1.0, -1.0, 0.0);
  EXPECT_TRUE(o.Validate().ok());
  o.lidar_time_offset_s = 0.6;
  expect_invalid(o, "lidar_time_offset_s");
  o.lidar_time_offset_s = INFINITY;
  expect_invalid(o, "lidar_time_offset_s");
  o.lidar_time_offset_s = -0.5;
  EXPECT_TRUE(o.Validate().ok());
  o.imu_mount_error_rpy_deg = Eigen::Vector3d(0.0, 0.0, 11.0);
  expect_invalid(o, "imu_mount_error_rpy_deg");
  o.imu_mount_error_rpy_deg = Eigen::Vector3d(0.0, NAN, 0.0);
  expect_invalid(o, "imu_mount_error_rpy_deg");
  o.imu_mount_error_rpy_deg = Eigen::Vector3d(-10.0, 10.0, 3.0);
  EXPECT_TRUE(o.Validate().ok());
}

}  // namespace
}  // namespace slam_mms::sim
