// CalibrateExtrinsics on simulated drives whose true extrinsic is known: started from a wrong
// calibration (rotation, lever arm and LiDAR clock offset), it recovers the truth where the drive
// observes it and flags what a straight drive cannot give.
#include "slam_mms/drive/extrinsic_calibrator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/drive/drive_runner.hpp"
#include "slam_mms/drive/open_drive.hpp"
#include "slam_mms/io/trajectory_io.hpp"
#include "slam_mms/sim/drive_simulator.hpp"
#include "slam_mms/sim/imu_simulator.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct Case {
  std::unique_ptr<DriveReader> reader;
  OfflinePos pos;
};

// `stated_noise`: the POS from the IMU's stated noise and attitude sigma (the drive's
// imu_noise.yaml), whose attitude sigma is that IMU's; otherwise the filter's defaults, an IMU of
// unknown grade, whose attitude sigma (0.25 deg of roll and pitch on these drives) holds any
// boresight correction smaller than three times it (ExtrinsicCalibrationOptions::min_significance).
Case Open(const std::filesystem::path& drive_dir, bool stated_noise = false) {
  Case c;
  StatusOr<std::unique_ptr<DriveReader>> r = OpenDrive(drive_dir, DriveSourceOptions{});
  EXPECT_TRUE(r.ok()) << r.status().ToString();
  if (!r.ok()) return c;
  c.reader = std::move(r).value();
  MappingSystem::Options mo;
  // SLAM_MMS_CAL_LAND: scripts/experiments/land_vehicle_pos.yaml's POS (stated noise and more).
  const bool land = std::getenv("SLAM_MMS_CAL_LAND") != nullptr;
  if (stated_noise || land) {
    mo.use_stated_imu_noise = true;
    mo.ins.use_stated_attitude_sigma = true;
  }
  if (land) {
    mo.vehicle_nhc_sigma_mps = 0.05;
    mo.ins.nhc_lateral_correlation_time_s = 2.6;
    mo.ins.nhc_vertical_correlation_time_s = 0.84;
  }
  StatusOr<OfflinePos> pos = ComputeOfflinePos(*c.reader, mo);
  EXPECT_TRUE(pos.ok()) << pos.status().ToString();
  if (pos.ok()) c.pos = std::move(pos).value();
  return c;
}

void Print(const ExtrinsicCalibration& r, const Eigen::Isometry3d& truth, double true_offset) {
  const Eigen::Vector3d rot_err =
      RollPitchYaw(r.T_body_lidar_estimated.linear() * truth.linear().transpose()) / kDeg;
  const Eigen::Vector3d t_err = r.T_body_lidar_estimated.translation() - truth.translation();
  std::printf(
      "scans %d (pos-skipped %d), residuals %zu, rounds %d, converged %d, wall %.2f s, "
      "heading change %.1f deg\n",
      r.scans_used, r.scans_skipped_pos, r.residuals, r.rounds, r.converged, r.wall_s,
      r.total_heading_change_rad / kDeg);
  std::printf(
      "rms %.4f -> %.4f m; travel reference [%.4f %.4f] deg from %d scans, floor [%.4f %.4f %.4f] "
      "deg\n",
      r.rms_initial_m, r.rms_final_m, r.travel_correction_rad(1) / kDeg,
      r.travel_correction_rad(2) / kDeg, r.travel_samples, r.pos_attitude_sigma_rad(0) / kDeg,
      r.pos_attitude_sigma_rad(1) / kDeg, r.pos_attitude_sigma_rad(2) / kDeg);
  std::printf("error vs truth: rpy [%.4f %.4f %.4f] deg, xyz [%.4f %.4f %.4f] m, time %.5f s\n",
              rot_err(0), rot_err(1), rot_err(2), t_err(0), t_err(1), t_err(2),
              r.time_offset_s - true_offset);
  std::printf(
      "attitude reference sigma [%.4f %.4f %.4f] deg, significance [%.1f %.1f %.1f %.1f %.1f "
      "%.1f %.1f]\n",
      r.pos_attitude_sigma_rad(0) / kDeg, r.pos_attitude_sigma_rad(1) / kDeg,
      r.pos_attitude_sigma_rad(2) / kDeg, r.significance(0), r.significance(1), r.significance(2),
      r.significance(3), r.significance(4), r.significance(5), r.significance(6));
  std::printf("POS correction: %d knots, rate rms [%.4f %.4f %.4f] m/s, max %.3f m\n",
              r.pos_drift_knots, r.pos_drift_rate_rms_mps(0), r.pos_drift_rate_rms_mps(1),
              r.pos_drift_rate_rms_mps(2), r.pos_drift_max_m);
  for (int i = 0; i < 7; ++i) {
    const double s = i < 3 ? 1.0 / kDeg : 1.0;
    std::printf("  %-11s observable %d formal %.5f jackknife %.5f systematic %.5f\n",
                ExtrinsicParameterName(i), r.observable[i], r.formal_sigma(i) * s,
                r.jackknife_sigma(i) * s, r.systematic_sigma(i) * s);
  }
}

// A simulated drive whose calibration file is wrong by `rpy_deg` / `xyz_m` and whose LiDAR clock
// lags by `offset_s`, with a navigation-grade IMU under open sky (a calibration drive).
struct PerturbedDrive {
  explicit PerturbedDrive(const std::string& name) : dir(name) {}
  testing::ScopedTempDir dir;
  Eigen::Isometry3d T_body_lidar_true;
};

std::unique_ptr<PerturbedDrive> Simulate(const std::string& name, const std::string& scenario,
                                         double duration_s, const Eigen::Vector3d& rpy_deg,
                                         const Eigen::Vector3d& xyz_m, double offset_s,
                                         std::filesystem::path* drive_dir) {
  auto d = std::make_unique<PerturbedDrive>(name);
  sim::DriveSimulator::Options o;
  o.scenario = scenario;
  o.duration_s = duration_s;
  o.write_scene_cloud = false;
  o.imu = sim::ImuSimulator::Options::ForGrade(sim::ImuGrade::kNavigation);
  o.gnss.urban_canyon_scale = 0.0;
  o.calib_error_rpy_deg = rpy_deg;
  o.calib_error_xyz_m = xyz_m;
  o.lidar_time_offset_s = offset_s;
  StatusOr<sim::DriveSimulator> simulator = sim::DriveSimulator::Create(o);
  EXPECT_TRUE(simulator.ok()) << simulator.status().ToString();
  if (!simulator.ok()) return nullptr;
  StatusOr<sim::DriveSimulator::Summary> summary = simulator->Run(d->dir.path);
  EXPECT_TRUE(summary.ok()) << summary.status().ToString();
  if (!summary.ok()) return nullptr;
  d->T_body_lidar_true = o.T_lidar_body.inverse();
  *drive_dir = summary->drive_dir;
  return d;
}

TEST(ExtrinsicCalibratorTest, RecoversAPerturbedExtrinsicAndClockOffsetOnADriveWithTurns) {
  std::filesystem::path drive_dir;
  const auto drive = Simulate("cal_turns", "demo", 30.0, Eigen::Vector3d(0.4, -0.3, 1.0),
                              Eigen::Vector3d(0.08, -0.06, 0.05), 0.02, &drive_dir);
  ASSERT_TRUE(drive);
  Case c = Open(drive_dir);
  ASSERT_TRUE(c.reader);
  const Eigen::Isometry3d truth = drive->T_body_lidar_true;
  const Eigen::Isometry3d initial = c.reader->streams().T_body_lidar;  // the wrong file
  ASSERT_GT(Eigen::AngleAxisd(initial.linear() * truth.linear().transpose()).angle(), 0.9 * kDeg);
  // The simulated IMU is aligned with the vehicle and nothing slips: the travel direction is the
  // body x axis.
  ExtrinsicCalibrationOptions o;
  o.attitude_reference = ExtrinsicCalibrationOptions::AttitudeReference::kTravelDirection;
  StatusOr<ExtrinsicCalibration> r = CalibrateExtrinsics(*c.reader, c.pos.states, initial, 0.0, o);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  Print(*r, truth, 0.02);
  EXPECT_EQ(r->attitude_reference, "travel_direction");
  const Eigen::Vector3d rot_err =
      RollPitchYaw(r->T_body_lidar_estimated.linear() * truth.linear().transpose());
  const Eigen::Vector3d t_err = r->T_body_lidar_estimated.translation() - truth.translation();
  EXPECT_GT(r->total_heading_change_rad, 90.0 * kDeg);
  // The target, 0.03 deg per axis. The map observes only boresight + POS attitude error (they
  // commute on level roads); the yaw is referred to the travel direction, as the POS's heading is
  // 0.05-0.15 deg off on this drive.
  EXPECT_NE(r->travel_samples, 0);
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT(std::abs(rot_err(i)), 0.03 * kDeg) << ExtrinsicParameterName(i);
  }
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(r->observable[i]) << ExtrinsicParameterName(i);
    EXPECT_LT(std::abs(rot_err(i)), 3.0 * r->sigma_rpy_rad(i)) << ExtrinsicParameterName(i);
  }
  // Horizontal lever arm within 2 cm with turns; the vertical one needs roll/pitch motion.
  EXPECT_TRUE(r->observable[3]);
  EXPECT_TRUE(r->observable[4]);
  EXPECT_LT(std::abs(t_err(0)), 0.02);
  EXPECT_LT(std::abs(t_err(1)), 0.02);
  if (!r->observable[5]) {
    EXPECT_EQ(r->T_body_lidar_estimated.translation()(2), initial.translation()(2));
    EXPECT_EQ(r->sigma_xyz_m(2), 0.0);
  }
  EXPECT_TRUE(r->observable[6]);
  EXPECT_LT(std::abs(r->time_offset_s - 0.02), 0.002);
  EXPECT_LT(r->rms_final_m, 0.6 * r->rms_initial_m);
}

TEST(ExtrinsicCalibratorTest, StraightDriveHoldsTheLeverArmAndRollAtTheirInitialValues) {
  // The default drive's first 10 s: straight ahead, no turn.
  std::filesystem::path drive_dir;
  const auto drive = Simulate("cal_straight", "default", 10.0, Eigen::Vector3d(0.3, 0.2, 0.5),
                              Eigen::Vector3d(0.06, 0.05, 0.0), 0.0, &drive_dir);
  ASSERT_TRUE(drive);
  Case c = Open(drive_dir, /*stated_noise=*/true);
  ASSERT_TRUE(c.reader);
  const Eigen::Isometry3d initial = c.reader->streams().T_body_lidar;
  ExtrinsicCalibrationOptions o;
  o.attitude_reference = ExtrinsicCalibrationOptions::AttitudeReference::kTravelDirection;
  StatusOr<ExtrinsicCalibration> r = CalibrateExtrinsics(*c.reader, c.pos.states, initial, 0.0, o);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  Print(*r, drive->T_body_lidar_true, 0.0);
  EXPECT_LT(r->total_heading_change_rad, 2.0 * kDeg);
  // Without a turn the lever arm moves the whole map rigidly, and a roll error rotates it about
  // the road's own axis: neither is observable, and neither is invented.
  for (int i : {0, 3, 4, 5}) {
    EXPECT_FALSE(r->observable[i]) << ExtrinsicParameterName(i);
  }
  EXPECT_EQ(r->T_body_lidar_estimated.translation(), initial.translation());
  EXPECT_EQ(r->correction_xyz_m, Eigen::Vector3d::Zero());
  EXPECT_EQ(r->sigma_xyz_m, Eigen::Vector3d::Zero());
  EXPECT_NEAR(r->correction_rpy_rad(0), 0.0, 1e-12);
  // Pitch is observable straight ahead (the ground seen at different ranges): the 0.2 deg error
  // is corrected.
  EXPECT_TRUE(r->observable[1]);
  const Eigen::Vector3d rot_err = RollPitchYaw(r->T_body_lidar_estimated.linear() *
                                               drive->T_body_lidar_true.linear().transpose());
  EXPECT_LT(std::abs(rot_err(1)), 0.05 * kDeg);
  // Yaw too: a yaw error shifts each scan sideways by the distance driven since the last one,
  // which the facades along the road see.
  EXPECT_TRUE(r->observable[2]);
  EXPECT_LT(std::abs(rot_err(2)), 0.03 * kDeg);
}

// The failure class of the simulated sweep's float and outage drives (docs/calibration.md, "The
// POS's drift"): a POS whose position wanders tilts the scans' path, and a boresight estimated
// without the POS's drift took the tilt. Here the file is right and the POS is the smoothed one
// with a vertical drift of 5 cm/s added (1 m over the 20 s) and a position sigma of 0.4 m.
TEST(ExtrinsicCalibratorTest, ARightFileStaysRightOnAPosThatDrifts) {
  std::filesystem::path drive_dir;
  const auto drive = Simulate("cal_drift", "demo", 20.0, Eigen::Vector3d::Zero(),
                              Eigen::Vector3d::Zero(), 0.0, &drive_dir);
  ASSERT_TRUE(drive);
  Case c = Open(drive_dir);
  ASSERT_TRUE(c.reader);
  const Eigen::Isometry3d truth = drive->T_body_lidar_true;
  ASSERT_TRUE(c.reader->streams().T_body_lidar.isApprox(truth, 1e-6));  // the file, as text
  constexpr double kDriftMps = 0.05;
  std::vector<InsState> drifting = c.pos.states;
  for (InsState& st : drifting) {
    st.T_world_body.translation().z() += kDriftMps * st.stamp.SecondsSince(drifting.front().stamp);
    // and says so, as a float-fix POS does (0.39 m on the sweep's float drive 0022).
    st.cov_T_world_body.block<3, 3>(3, 3) = Eigen::Matrix3d::Identity() * 0.4 * 0.4;
  }
  const auto rotation_error = [&](const ExtrinsicCalibration& r) {
    return Eigen::Vector3d(
        RollPitchYaw(r.T_body_lidar_estimated.linear() * truth.linear().transpose()) / kDeg);
  };
  ExtrinsicCalibrationOptions o;
  // Without the POS's drift in the model the boresight takes the path's tilt: the test can fail.
  o.estimate_pos_drift = false;
  StatusOr<ExtrinsicCalibration> blind = CalibrateExtrinsics(*c.reader, drifting, truth, 0.0, o);
  ASSERT_TRUE(blind.ok()) << blind.status().ToString();
  Print(*blind, truth, 0.0);
  EXPECT_GT(rotation_error(*blind).head<2>().cwiseAbs().maxCoeff(), 0.1);
  // With it, the drift is found and the file kept within 0.03 deg, 1 cm, 1 ms.
  for (const std::vector<InsState>* pos : {&c.pos.states, &drifting}) {
    o.estimate_pos_drift = true;
    StatusOr<ExtrinsicCalibration> r = CalibrateExtrinsics(*c.reader, *pos, truth, 0.0, o);
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    Print(*r, truth, 0.0);
    const Eigen::Vector3d rot_err = rotation_error(*r);
    for (int i = 0; i < 3; ++i) EXPECT_LT(std::abs(rot_err(i)), 0.03) << ExtrinsicParameterName(i);
    EXPECT_LT((r->T_body_lidar_estimated.translation() - truth.translation()).norm(), 0.01);
    EXPECT_LT(std::abs(r->time_offset_s), 0.001);
    EXPECT_GT(r->pos_drift_knots, 10);
    if (pos == &drifting) {
      EXPECT_NEAR(r->pos_drift_rate_rms_mps.z(), kDriftMps, 0.01);
    }
    // What is held is exactly the file's; what is applied is significant.
    for (int i = 0; i < 7; ++i) {
      if (r->applied[i]) {
        EXPECT_GE(r->significance(i), o.min_significance) << ExtrinsicParameterName(i);
      }
    }
  }
}

TEST(ExtrinsicCalibratorTest, OptionsAndInputsAreChecked) {
  ExtrinsicCalibrationOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.final_gate_m = 0.0;
  const Status s = o.Validate();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("final_gate_m"), std::string::npos) << s.ToString();
  o = ExtrinsicCalibrationOptions{};
  o.jackknife_blocks = 1;
  EXPECT_NE(o.Validate().message().find("jackknife_blocks"), std::string::npos);
  // The report's roll, pitch, yaw convention (core's RollPitchYaw) reads back.
  const Eigen::Matrix3d R = FromRollPitchYaw(0.1, -0.2, 2.5);
  const Eigen::Vector3d rpy = RollPitchYaw(R);
  EXPECT_NEAR((FromRollPitchYaw(rpy(0), rpy(1), rpy(2)) - R).norm(), 0.0, 1e-12);
  EXPECT_NEAR((rpy - Eigen::Vector3d(0.1, -0.2, 2.5)).norm(), 0.0, 1e-12);
}

// RunDrive with DriveRunOptions::estimate_extrinsics is the two steps by hand: the calibration
// (CalibrateDriveExtrinsics), then the run over the reader with the estimate; its errors carry the
// step that failed.
TEST(ExtrinsicCalibratorTest, RunDriveCalibratesFirstWhenAsked) {
  std::filesystem::path drive_dir;
  const auto drive = Simulate("cal_rundrive", "demo", 20.0, Eigen::Vector3d(0.0, 0.0, 1.0),
                              Eigen::Vector3d(0.05, 0.0, 0.0), 0.02, &drive_dir);
  ASSERT_TRUE(drive);
  Case c = Open(drive_dir);
  ASSERT_TRUE(c.reader);
  MappingSystem::Options mo;
  mo.mode = MappingMode::kGnssIns;
  mo.T_body_lidar = c.reader->streams().T_body_lidar;
  DriveRunOptions ro;
  ro.estimate_extrinsics = true;
  const DriveRun run = RunDrive(*c.reader, mo, {}, ro);
  ASSERT_TRUE(run.status.ok()) << run.status.ToString();
  ASSERT_TRUE(run.complete);
  ASSERT_TRUE(run.extrinsic_calibration.has_value());
  const ExtrinsicCalibration& cal = *run.extrinsic_calibration;
  Print(cal, drive->T_body_lidar_true, 0.02);
  // The wrong 1 deg of yaw and 20 ms of clock are found (loose: a 20 s drive). 20 s: through the
  // demo's first turn; on its straight first 12 s a clock offset looks like a drift of the POS
  // along the path (a shift of v x 20 ms that follows the speed) and is held.
  const Eigen::Vector3d rot_err = RollPitchYaw(cal.T_body_lidar_estimated.linear() *
                                               drive->T_body_lidar_true.linear().transpose());
  EXPECT_LT(std::abs(rot_err(2)), 0.2 * kDeg);
  EXPECT_LT(std::abs(cal.time_offset_s - 0.02), 0.01);

  StatusOr<ExtrinsicCalibration> by_hand =
      CalibrateDriveExtrinsics(*c.reader, mo, ro.extrinsic_calibration);
  ASSERT_TRUE(by_hand.ok()) << by_hand.status().ToString();
  EXPECT_EQ(by_hand->T_body_lidar_estimated.matrix(), cal.T_body_lidar_estimated.matrix());
  EXPECT_EQ(by_hand->time_offset_s, cal.time_offset_s);
  DriveExtrinsics e;
  e.T_body_lidar = by_hand->T_body_lidar_estimated;
  e.lidar_time_offset_s = by_hand->time_offset_s;
  const std::unique_ptr<DriveReader> calibrated = OverrideExtrinsics(*c.reader, e);
  MappingSystem::Options mo2 = mo;
  mo2.T_body_lidar = e.T_body_lidar;
  const DriveRun two_steps = RunDrive(*calibrated, mo2);
  ASSERT_TRUE(two_steps.status.ok());
  EXPECT_FALSE(two_steps.extrinsic_calibration.has_value());
  ASSERT_EQ(two_steps.trajectory.size(), run.trajectory.size());
  for (size_t i = 0; i < run.trajectory.size(); ++i) {
    ASSERT_EQ(run.trajectory[i].stamp, two_steps.trajectory[i].stamp) << i;
    ASSERT_EQ(run.trajectory[i].T_world_body.matrix(),
              two_steps.trajectory[i].T_world_body.matrix())
        << i;
  }
  // Bad calibration options: nothing runs, the field is named.
  ro.extrinsic_calibration.max_scans = 5;
  const DriveRun bad = RunDrive(*c.reader, mo, {}, ro);
  EXPECT_EQ(bad.status.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(bad.status.message().find("max_scans"), std::string::npos) << bad.status.ToString();
  EXPECT_EQ(bad.scans_processed, 0u);
}

// A measurement, not a check (docs/calibration.md): SLAM_MMS_CAL_DRIVE=<simulated KITTI raw drive>
// perturbs its true calibration (0.4, -0.3, 1.0 deg; 8, -6, 5 cm; -20 ms; x SLAM_MMS_CAL_SCALE),
// calibrates (SLAM_MMS_CAL_TRAVEL=1: the travel-direction reference; SLAM_MMS_CAL_GTPOS=1: the
// true poses as the POS) and prints the errors against the truth and the POS's own errors.
TEST(ExtrinsicCalibratorTest, ExploreDrive) {
  const char* dir = std::getenv("SLAM_MMS_CAL_DRIVE");
  if (dir == nullptr) GTEST_SKIP() << "set SLAM_MMS_CAL_DRIVE to explore a drive";
  Case c = Open(dir);
  ASSERT_TRUE(c.reader);
  const Eigen::Isometry3d truth = c.reader->streams().T_body_lidar;
  // The POS's own attitude error against the simulator's truth (what the boresight absorbs).
  StatusOr<Trajectory> gt =
      ReadTrajectoryTum(std::filesystem::path(dir) / "ground_truth" / "poses_100hz.tum");
  ASSERT_TRUE(gt.ok()) << gt.status().ToString();
  // In world axes (an INS's tilt and heading error) and in body axes (what the boresight absorbs).
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sq = Eigen::Vector3d::Zero();
  Eigen::Vector3d sum_b = Eigen::Vector3d::Zero(), sq_b = Eigen::Vector3d::Zero();
  int n = 0;
  for (size_t i = 0; i < c.pos.states.size(); i += 10) {
    const StatusOr<Eigen::Isometry3d> T = gt->Interpolate(c.pos.states[i].stamp);
    if (!T.ok()) continue;
    const Eigen::Matrix3d& R = c.pos.states[i].T_world_body.linear();
    const Eigen::Vector3d e = RollPitchYaw(R * T->linear().transpose()) / kDeg;
    const Eigen::Vector3d eb = RollPitchYaw(T->linear().transpose() * R) / kDeg;
    sum += e;
    sq += e.cwiseAbs2();
    sum_b += eb;
    sq_b += eb.cwiseAbs2();
    ++n;
  }
  ASSERT_GT(n, 0);
  const auto print = [n](const char* what, const Eigen::Vector3d& s, const Eigen::Vector3d& q) {
    const Eigen::Vector3d m = s / n;
    const Eigen::Vector3d sd = (q / n - m.cwiseAbs2()).cwiseMax(0.0).cwiseSqrt();
    std::printf("POS attitude error (%s) mean [%.3f %.3f %.3f] deg sd [%.3f %.3f %.3f]\n", what,
                m(0), m(1), m(2), sd(0), sd(1), sd(2));
  };
  {
    std::vector<double> sig;
    for (const InsState& st : c.pos.states)
      sig.push_back(std::sqrt(st.cov_T_world_body.block<3, 3>(3, 3).diagonal().maxCoeff()));
    std::sort(sig.begin(), sig.end());
    std::printf("POS position sigma (largest axis) median %.3f m, 90th %.3f m\n",
                sig[sig.size() / 2], sig[sig.size() * 9 / 10]);
  }
  print("world axes", sum, sq);
  print("body axes", sum_b, sq_b);
  {
    // The POS's position error and its change over 2 s (a velocity error tilts the scans' path).
    std::vector<std::pair<double, Eigen::Vector3d>> err;
    for (const InsState& st : c.pos.states) {
      const StatusOr<Eigen::Isometry3d> T = gt->Interpolate(st.stamp);
      if (!T.ok()) continue;
      err.emplace_back(st.stamp.SecondsSince(c.pos.states.front().stamp),
                       st.T_world_body.translation() - T->translation());
    }
    Eigen::Vector3d rms = Eigen::Vector3d::Zero(), rate = Eigen::Vector3d::Zero();
    int nr = 0;
    size_t j = 0;
    for (size_t i = 0; i < err.size(); i += 10) {
      rms += err[i].second.cwiseAbs2();
      while (j < err.size() && err[j].first < err[i].first + 2.0) ++j;
      if (j == err.size()) break;
      rate += ((err[j].second - err[i].second) / (err[j].first - err[i].first)).cwiseAbs2();
      ++nr;
    }
    if (nr > 0) {
      rms = (rms / nr).cwiseSqrt();
      rate = (rate / nr).cwiseSqrt();
      std::printf(
          "POS position error rms [%.3f %.3f %.3f] m, its 2 s rate rms [%.4f %.4f %.4f] m/s\n",
          rms(0), rms(1), rms(2), rate(0), rate(1), rate(2));
    }
  }
  if (std::getenv("SLAM_MMS_CAL_GTPOS")) {
    c.pos.states.clear();
    for (const auto& p : gt->poses()) {
      InsState s;
      s.stamp = p.stamp;
      s.T_world_body = p.T_world_body;
      s.cov_T_world_body = Matrix6d::Identity() * 1e-6;
      c.pos.states.push_back(s);
    }
  }
  const double scale =
      std::getenv("SLAM_MMS_CAL_SCALE") ? std::atof(std::getenv("SLAM_MMS_CAL_SCALE")) : 1.0;
  Eigen::Isometry3d initial = truth;
  initial.linear() = FromRollPitchYaw(scale * 0.4 * kDeg, scale * -0.3 * kDeg, scale * 1.0 * kDeg) *
                     truth.linear();
  initial.translation() += scale * Eigen::Vector3d(0.08, -0.06, 0.05);
  ExtrinsicCalibrationOptions o;
  if (std::getenv("SLAM_MMS_CAL_NODRIFT")) o.estimate_pos_drift = false;
  if (std::getenv("SLAM_MMS_CAL_DRIFT_TAU"))
    o.pos_error_correlation_s = std::atof(std::getenv("SLAM_MMS_CAL_DRIFT_TAU"));
  if (std::getenv("SLAM_MMS_CAL_TRAVEL"))
    o.attitude_reference = ExtrinsicCalibrationOptions::AttitudeReference::kTravelDirection;
  StatusOr<ExtrinsicCalibration> r =
      CalibrateExtrinsics(*c.reader, c.pos.states, initial, -0.02 * scale, o);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  Print(*r, truth, 0.0);
}

}  // namespace
}  // namespace slam_mms
