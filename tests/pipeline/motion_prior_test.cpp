// MotionPrior (src/pipeline/motion_prior.hpp): level 1's prediction and de-skew motion on their
// own.

#include "pipeline/motion_prior.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace slam_mms::internal {
namespace {

const Eigen::Vector3d kG(0.0, 0.0, -9.80665);

Timestamp T(double s) { return Timestamp::FromSeconds(200.0 + s); }

Eigen::Isometry3d Pose(double x, double y, double yaw) {
  return Eigen::Translation3d(x, y, 0.0) * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
}

Scan ScanAt(double t) {
  Scan s;
  s.index = 7;
  s.stamp_start = T(t);
  s.stamp_end = T(t + 0.1);
  return s;
}

// IMU of a body moving at constant velocity without turning: it measures the reaction to gravity.
std::vector<ImuSample> StillImu(double from, double to) {
  std::vector<ImuSample> out;
  for (double t = from; t <= to + 1e-9; t += 0.005) {
    ImuSample s;
    s.stamp = T(t);
    s.accel_mps2 = -kG;
    out.push_back(s);
  }
  return out;
}

PreviousScan Prev(double t, const Eigen::Isometry3d& T_submap, const Eigen::Vector3d& v) {
  PreviousScan p;
  p.stamp = T(t);
  p.T_submap = T_submap;
  p.v_submap = v;
  return p;
}

bool Near(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b, double tol) {
  return (a.matrix() - b.matrix()).cwiseAbs().maxCoeff() < tol;
}

TEST(MotionPriorTest, ASubmapReferenceIsPredictedAtThePreviousPoseWithoutAFactor) {
  const MotionPrior prior(ImuPreintegration::Options(), true);
  ScanMotionInput m;
  m.type = MotionFactorType::kOdometry;
  const PreviousScan prev = Prev(0.9, Pose(1, 2, 0.3), Eigen::Vector3d(1, 0, 0));
  const Prediction p =
      prior.Predict(ScanAt(1.0), m, /*is_reference=*/true, prev, Eigen::Isometry3d::Identity(), kG);
  EXPECT_EQ(p.factor, MotionFactorType::kNone);
  EXPECT_TRUE(Near(p.T_submap, prev.T_submap, 0.0 + 1e-15));
  EXPECT_EQ(p.v_submap, prev.v_submap);
}

TEST(MotionPriorTest, OdometryFollowsThePosRelativeMotionWhereThePreviousScanHadAPosPose) {
  const MotionPrior prior(ImuPreintegration::Options(), true);
  PreviousScan prev = Prev(0.9, Pose(1, 2, 0.3), Eigen::Vector3d::Zero());
  prev.has_pos = true;
  prev.pos_start = Pose(100, 50, 0.1);
  ScanMotionInput m;
  m.type = MotionFactorType::kOdometry;
  m.T_world_body_pos_start = Pose(101, 50, 0.15);  // 1 m along x and 0.05 rad in the world
  m.v_world_pos << 10, 0, 0;
  const Eigen::Isometry3d T_world_submap = Pose(0, 0, 0.5);
  const Prediction p = prior.Predict(ScanAt(1.0), m, false, prev, T_world_submap, kG);
  ASSERT_EQ(p.factor, MotionFactorType::kOdometry);
  EXPECT_TRUE(
      Near(p.T_submap, prev.T_submap * prev.pos_start.inverse() * m.T_world_body_pos_start, 1e-12));
  EXPECT_TRUE(p.v_submap.isApprox(T_world_submap.linear().transpose() * m.v_world_pos));
  // Without a POS pose at the previous scan: preintegration with IMU states and samples, else
  // constant velocity.
  prev.has_pos = false;
  m.imu = StillImu(0.8, 1.2);
  EXPECT_EQ(prior.Predict(ScanAt(1.0), m, false, prev, T_world_submap, kG).factor,
            MotionFactorType::kPreintegration);
  const MotionPrior lidar_states(ImuPreintegration::Options(), false);
  EXPECT_EQ(lidar_states.Predict(ScanAt(1.0), m, false, prev, T_world_submap, kG).factor,
            MotionFactorType::kConstantVelocity);
}

TEST(MotionPriorTest, PreintegrationPredictsFromThePreviousStateAndFallsBackWithoutImu) {
  const MotionPrior prior(ImuPreintegration::Options(), true);
  const PreviousScan prev = Prev(0.9, Pose(1, 2, 0.3), Eigen::Vector3d(2, 1, 0));
  ScanMotionInput m;
  m.type = MotionFactorType::kPreintegration;
  m.imu = StillImu(0.8, 1.2);
  const Prediction p =
      prior.Predict(ScanAt(1.0), m, false, prev, Eigen::Isometry3d::Identity(), kG);
  ASSERT_EQ(p.factor, MotionFactorType::kPreintegration);
  ASSERT_TRUE(p.pre.has_value());
  EXPECT_NEAR(p.pre->delta_t_s(), 0.1, 1e-9);
  // Constant velocity, no rotation: 0.1 s at (2, 1, 0) m/s.
  EXPECT_LT((p.T_submap.translation() - (prev.T_submap.translation() + 0.1 * prev.v_submap)).norm(),
            1e-6);
  EXPECT_TRUE(p.T_submap.linear().isApprox(prev.T_submap.linear(), 1e-9));
  EXPECT_LT((p.v_submap - prev.v_submap).norm(), 1e-6);
  // The IMU does not reach the scan: constant velocity (from no recorded poses: the previous pose).
  m.imu = StillImu(0.0, 0.2);  // ends 0.7 s before the window: beyond max_sample_dt_s
  const Prediction cv =
      prior.Predict(ScanAt(1.0), m, false, prev, Eigen::Isometry3d::Identity(), kG);
  EXPECT_EQ(cv.factor, MotionFactorType::kConstantVelocity);
  EXPECT_FALSE(cv.pre.has_value());
  EXPECT_TRUE(Near(cv.T_submap, prev.T_submap, 1e-15));
}

TEST(MotionPriorTest, ConstantVelocityPredictsTheLastIntervalAndDeskewsWithTheLastThree) {
  MotionPrior prior(ImuPreintegration::Options(), false);
  EXPECT_FALSE(prior.ConstantVelocityMotion(0.1, 1).has_value());
  // Six scans at 10 Hz. The first ones move at 5 m/s; the last interval at 8 m/s, turning.
  const double x[] = {0.0, 0.5, 1.0, 1.5, 2.0, 2.8};
  const double yaw[] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.02};
  for (int k = 0; k < 6; ++k) prior.Record(T(0.1 * k), Pose(x[k], 0, yaw[k]));
  ASSERT_TRUE(prior.ConstantVelocityMotion(0.1, 1).has_value());
  // The prediction of the next scan: the last interval once more.
  const PreviousScan prev = Prev(0.5, Pose(2.8, 0, 0.02), Eigen::Vector3d::Zero());
  const Prediction p =
      prior.Predict(ScanAt(0.6), ScanMotionInput(), false, prev, Eigen::Isometry3d::Identity(), kG);
  EXPECT_EQ(p.factor, MotionFactorType::kConstantVelocity);
  const Eigen::Isometry3d last = Pose(2.0, 0, 0).inverse() * Pose(2.8, 0, 0.02);
  EXPECT_TRUE(Near(p.T_submap, prev.T_submap * last, 1e-7));  // stamps rounded to ns
  // The de-skew: the mean motion of the last three intervals (1.8 m in 0.3 s) over the scan's
  // 0.1 s, not the last interval's, and only the last four poses are kept (the first two move
  // at the same speed, so keeping them would not show; ask for 100 intervals).
  const Eigen::Isometry3d d = prior.DeskewMotion(ScanAt(0.6), ScanMotionInput(), prev.T_submap,
                                                 Eigen::Vector3d::Zero(), kG, Vector6d::Zero());
  const Eigen::Isometry3d three =
      se3::Exp(se3::Log(Pose(1.0, 0, 0).inverse() * Pose(2.8, 0, 0.02)) / 3.0);
  EXPECT_TRUE(Near(d, three, 1e-7));
  EXPECT_TRUE(Near(*prior.ConstantVelocityMotion(0.1, 100), three, 1e-7));
  // A new submap frame moves every kept pose alike: the relative motion is the same.
  prior.Reframe(Pose(-30, 4, 1.0));
  EXPECT_TRUE(Near(*prior.ConstantVelocityMotion(0.1, 3), three, 1e-7));
}

// Seeded with a velocity before the first scan: the first scan is de-skewed and the second
// predicted at it, and the seeds leave as real poses come (kDeskewVelocityIntervals + 1 kept).
TEST(MotionPriorTest, SeedVelocityDeskewsAndPredictsTheFirstScans) {
  MotionPrior prior(ImuPreintegration::Options(), false);
  const Eigen::Vector3d v(6.0, 0.5, 0.0);
  prior.SeedVelocity(T(0.0), v, 0.1);
  Eigen::Isometry3d over_scan = Eigen::Isometry3d::Identity();
  over_scan.translation() = 0.1 * v;
  const Eigen::Isometry3d d0 =
      prior.DeskewMotion(ScanAt(0.0), ScanMotionInput(), Eigen::Isometry3d::Identity(),
                         Eigen::Vector3d::Zero(), kG, Vector6d::Zero());
  EXPECT_TRUE(Near(d0, over_scan, 1e-7));
  prior.Record(T(0.0), Eigen::Isometry3d::Identity());
  const PreviousScan prev = Prev(0.0, Eigen::Isometry3d::Identity(), Eigen::Vector3d::Zero());
  const Prediction p =
      prior.Predict(ScanAt(0.1), ScanMotionInput(), false, prev, Eigen::Isometry3d::Identity(), kG);
  EXPECT_TRUE(Near(p.T_submap, over_scan, 1e-7));
  // Three real poses standing still push the seeds out: no motion left.
  for (int k = 1; k <= 3; ++k) prior.Record(T(0.1 * k), Eigen::Isometry3d::Identity());
  EXPECT_TRUE(Near(*prior.ConstantVelocityMotion(0.1, 100), Eigen::Isometry3d::Identity(), 1e-12));
}

TEST(MotionPriorTest, DeskewMotionByTheMotionSource) {
  const MotionPrior prior(ImuPreintegration::Options(), true);
  ScanMotionInput odo;
  odo.type = MotionFactorType::kOdometry;
  odo.T_world_body_pos_start = Pose(10, 0, 0.1);
  odo.T_world_body_pos_end = Pose(11, 0.2, 0.12);
  EXPECT_TRUE(Near(prior.DeskewMotion(ScanAt(1.0), odo, Eigen::Isometry3d::Identity(),
                                      Eigen::Vector3d::Zero(), kG, Vector6d::Zero()),
                   odo.T_world_body_pos_start.inverse() * odo.T_world_body_pos_end, 1e-12));
  ScanMotionInput pre;
  pre.type = MotionFactorType::kPreintegration;
  pre.imu = StillImu(0.9, 1.2);
  const Eigen::Isometry3d d = prior.DeskewMotion(ScanAt(1.0), pre, Pose(0, 0, 0.4),
                                                 Eigen::Vector3d(3, 0, 0), kG, Vector6d::Zero());
  // 0.1 s at 3 m/s along the submap's x, seen in the body (yawed 0.4 rad) frame.
  const Eigen::Vector3d t_body = Pose(0, 0, 0.4).linear().transpose() * Eigen::Vector3d(0.3, 0, 0);
  EXPECT_LT((d.translation() - t_body).norm(), 1e-6);
  EXPECT_TRUE(d.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-9));
  // No IMU and no recorded poses: no motion.
  ScanMotionInput none;
  none.type = MotionFactorType::kPreintegration;
  EXPECT_TRUE(Near(prior.DeskewMotion(ScanAt(1.0), none, Eigen::Isometry3d::Identity(),
                                      Eigen::Vector3d::Zero(), kG, Vector6d::Zero()),
                   Eigen::Isometry3d::Identity(), 0.0 + 1e-15));
}

}  // namespace
}  // namespace slam_mms::internal
