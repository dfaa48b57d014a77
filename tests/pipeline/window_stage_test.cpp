// WindowStage (steps 5-6 of Localizer::ProcessScan) on hand-made predictions and registrations: the
// state ids of a window and across windows, the reference scan, the constant-velocity factor,
// F_Reg pulling the pose and F_Reg rejected by the consistency check (and taken after a streak of
// rejections), F_Odom fixing the relative motion, and the velocity of F_Odom with IMU states (full
// mode).
#include "pipeline/window_stage.hpp"

#include <gtest/gtest.h>

#include "pipeline/noise_model.hpp"

namespace slam_mms::internal {
namespace {

constexpr int64_t kT0Ns = 1'317'000'000'000'000'000;

Localizer::Options Options(MappingMode mode) {
  Localizer::Options o;
  o.mode = mode;
  o.num_threads = 1;
  return o;
}

Eigen::Isometry3d Forward(double x_m) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation().x() = x_m;
  return T;
}

Scan MakeScan(int k) {
  Scan scan;
  scan.index = k;
  scan.stamp_start = Timestamp::FromNanoseconds(kT0Ns + k * 100'000'000);
  scan.stamp_end = scan.stamp_start;
  return scan;
}

/// The previous scan (k - 1) at T_submap_body.
PreviousScan Previous(int k, const Eigen::Isometry3d& T_submap_body) {
  PreviousScan prev;
  prev.stamp = MakeScan(k - 1).stamp_start;
  prev.T_submap = T_submap_body;
  return prev;
}

/// A scan predicted at T_submap_pred by `factor`, registered at *T_submap_reg if given (1 cm,
/// 0.5 mrad sigma).
ScanStep Step(MotionFactorType factor, const Eigen::Isometry3d& T_submap_pred,
              const std::optional<Eigen::Isometry3d>& T_submap_reg = std::nullopt) {
  ScanStep step;
  step.pred.factor = factor;
  step.pred.T_submap = T_submap_pred;
  step.T_submap_reg = T_submap_reg;
  Vector6d var;
  var << Eigen::Vector3d::Constant(0.25e-6), Eigen::Vector3d::Constant(1e-4);
  step.cov_reg = var.asDiagonal();
  return step;
}

double DistM(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.inverse() * b).translation().norm();
}

TEST(WindowStageTest, TheReferenceScanIsTheHeldReferenceState) {
  WindowStage window(Options(MappingMode::kLidarOnly));
  ASSERT_TRUE(window.Start(Eigen::Vector3d::Zero(), Vector6d::Zero()).ok());
  EXPECT_EQ(window.reference_id(), 0);
  EXPECT_EQ(window.previous_id(), 0);
  ScanStep step = Step(MotionFactorType::kNone, Forward(3.0));
  step.is_reference = true;
  LocalizationResult res;
  PreviousScan prev = Previous(0, Eigen::Isometry3d::Identity());
  ASSERT_TRUE(window.AddFactors(MakeScan(0), ScanMotionInput(), prev, &step, &res).ok());
  EXPECT_EQ(step.cur_state, 0);
  EXPECT_EQ(window.graph()->StateIds().size(), 1u);
  ASSERT_TRUE(window.Optimize(MakeScan(0), &step, &prev, &res).ok());
  EXPECT_TRUE(step.T_submap_cur.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_EQ(res.cov_T_world_body, Matrix6d::Identity() * noise::kAnchorPoseVariance);
}

TEST(WindowStageTest, StateIdsIncreaseWithinAndAcrossWindows) {
  WindowStage window(Options(MappingMode::kLidarOnly));
  ASSERT_TRUE(window.Start(Eigen::Vector3d::Zero(), Vector6d::Zero()).ok());
  PreviousScan prev = Previous(1, Eigen::Isometry3d::Identity());
  for (int k = 1; k <= 2; ++k) {
    ScanStep step = Step(MotionFactorType::kConstantVelocity, Forward(0.5 * k));
    LocalizationResult res;
    ASSERT_TRUE(window.AddFactors(MakeScan(k), ScanMotionInput(), prev, &step, &res).ok());
    EXPECT_EQ(step.cur_state, k);
    ASSERT_TRUE(window.Optimize(MakeScan(k), &step, &prev, &res).ok());
    window.Advance(step.cur_state);
    EXPECT_EQ(window.previous_id(), k);
    prev = Previous(k + 1, step.T_submap_cur);
  }
  ASSERT_TRUE(window.Start(Eigen::Vector3d::Zero(), Vector6d::Zero()).ok());
  EXPECT_EQ(window.reference_id(), 3);  // ids are never reused
  EXPECT_EQ(window.previous_id(), 3);
  EXPECT_EQ(window.graph()->StateIds().size(), 1u);
}

TEST(WindowStageTest, ConstantVelocityAloneKeepsThePredictionAndFRegPullsTowardsTheScan) {
  WindowStage window(Options(MappingMode::kLidarOnly));
  ASSERT_TRUE(window.Start(Eigen::Vector3d::Zero(), Vector6d::Zero()).ok());
  PreviousScan prev = Previous(1, Eigen::Isometry3d::Identity());
  // Scan 1: no registration, the constant-velocity factor alone.
  ScanStep step = Step(MotionFactorType::kConstantVelocity, Forward(0.5));
  LocalizationResult res;
  ASSERT_TRUE(window.AddFactors(MakeScan(1), ScanMotionInput(), prev, &step, &res).ok());
  ASSERT_TRUE(window.Optimize(MakeScan(1), &step, &prev, &res).ok());
  EXPECT_LT(DistM(step.T_submap_cur, Forward(0.5)), 1e-6);
  EXPECT_FALSE(res.registration_used);
  window.Advance(step.cur_state);
  // Scan 2: predicted at 1.0 m, registered at 1.03 m (within the gate): the registration wins.
  prev = Previous(2, step.T_submap_cur);
  step = Step(MotionFactorType::kConstantVelocity, Forward(1.0), Forward(1.03));
  res = LocalizationResult();
  ASSERT_TRUE(window.AddFactors(MakeScan(2), ScanMotionInput(), prev, &step, &res).ok());
  EXPECT_TRUE(res.registration_used);
  EXPECT_GT(res.consistency_mahalanobis_sq, 0.0);
  ASSERT_TRUE(window.Optimize(MakeScan(2), &step, &prev, &res).ok());
  EXPECT_LT(DistM(step.T_submap_cur, Forward(1.03)), 2e-3);
  EXPECT_TRUE(res.cov_T_world_body.allFinite());
}

TEST(WindowStageTest, ARegistrationFarFromThePredictionIsRejected) {
  WindowStage window(Options(MappingMode::kLidarOnly));
  ASSERT_TRUE(window.Start(Eigen::Vector3d::Zero(), Vector6d::Zero()).ok());
  PreviousScan prev = Previous(1, Eigen::Isometry3d::Identity());
  ScanStep step = Step(MotionFactorType::kConstantVelocity, Forward(0.5), Forward(5.0));
  LocalizationResult res;
  ASSERT_TRUE(window.AddFactors(MakeScan(1), ScanMotionInput(), prev, &step, &res).ok());
  EXPECT_FALSE(res.registration_used);
  EXPECT_GT(res.consistency_mahalanobis_sq, 22.46);
  ASSERT_TRUE(window.Optimize(MakeScan(1), &step, &prev, &res).ok());
  EXPECT_LT(DistM(step.T_submap_cur, Forward(0.5)), 1e-6);
}

// The gate's lock-out (noise::kRejectedRegistrationsBeforeRecovery): a motion prediction 5 m off
// (a wrong velocity) makes every registration fail the gate; without a way out level 1 follows the
// prediction alone and leaves its map (session 38: 11.6 m in 10 s after a POS re-converged).
// After three rejected in a row, the next registrations that are not flagged degenerate are taken
// as they are, until one passes the gate again; then a new streak starts from zero.
TEST(WindowStageTest, AfterThreeRejectedRegistrationsInARowTheNextAreTaken) {
  WindowStage window(Options(MappingMode::kLidarOnly));
  ASSERT_TRUE(window.Start(Eigen::Vector3d::Zero(), Vector6d::Zero()).ok());
  PreviousScan prev = Previous(1, Eigen::Isometry3d::Identity());
  auto run = [&](int k, const Eigen::Isometry3d& pred, const Eigen::Isometry3d& reg,
                 bool degenerate, LocalizationResult* res, ScanStep* step) {
    *step = Step(MotionFactorType::kConstantVelocity, pred, reg);
    *res = LocalizationResult();
    res->degenerate = degenerate;
    ASSERT_TRUE(window.AddFactors(MakeScan(k), ScanMotionInput(), prev, step, res).ok());
    ASSERT_TRUE(window.Optimize(MakeScan(k), step, &prev, res).ok());
    window.Advance(step->cur_state);
    prev = Previous(k + 1, step->T_submap_cur);
  };
  LocalizationResult res;
  ScanStep step;
  for (int k = 1; k <= 7; ++k) {
    const Eigen::Isometry3d reg = Forward(0.5 * k);
    // Scan 4 is flagged degenerate: not taken, the streak goes on.
    run(k, Forward(0.5 * k + 5.0), reg, /*degenerate=*/k == 4, &res, &step);
    EXPECT_GT(res.consistency_mahalanobis_sq, 22.46) << k;
    if (k <= 4) {
      EXPECT_FALSE(res.registration_used) << k;
      EXPECT_GT(DistM(step.T_submap_cur, reg), 1.0) << k;
    } else {
      EXPECT_TRUE(res.registration_used) << k;
      EXPECT_FALSE(res.registration_downweighted) << k;
      EXPECT_LT(DistM(step.T_submap_cur, reg), 0.05) << k;
    }
  }
  // A registration within the gate ends the recovery: the next far one is rejected again.
  run(8, Forward(4.0), Forward(4.01), false, &res, &step);
  EXPECT_TRUE(res.registration_used);
  EXPECT_LT(res.consistency_mahalanobis_sq, 22.46);
  run(9, Forward(9.5), Forward(4.5), false, &res, &step);
  EXPECT_FALSE(res.registration_used);
}

TEST(WindowStageTest, FOdomFixesThePosRelativeMotion) {
  WindowStage window(Options(MappingMode::kLidarOnly));
  ASSERT_TRUE(window.Start(Eigen::Vector3d::Zero(), Vector6d::Zero()).ok());
  PreviousScan prev = Previous(1, Eigen::Isometry3d::Identity());
  Eigen::Isometry3d pos0 = Eigen::Isometry3d::Identity();
  pos0.translate(Eigen::Vector3d(100.0, -20.0, 3.0));
  pos0.rotate(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()));
  prev.has_pos = true;
  prev.pos_start = pos0;
  ScanMotionInput motion;
  motion.type = MotionFactorType::kOdometry;
  motion.T_world_body_pos_start = pos0 * Forward(0.7);
  motion.T_world_body_pos_end = pos0 * Forward(1.4);
  // The initial value (the prediction) is off; F_Odom alone decides.
  ScanStep step = Step(MotionFactorType::kOdometry, Forward(0.6));
  LocalizationResult res;
  ASSERT_TRUE(window.AddFactors(MakeScan(1), motion, prev, &step, &res).ok());
  ASSERT_TRUE(window.Optimize(MakeScan(1), &step, &prev, &res).ok());
  EXPECT_LT(DistM(step.T_submap_cur, Forward(0.7)), 1e-6);
}

TEST(WindowStageTest, FOdomWithImuStatesTiesTheVelocityToThePos) {
  WindowStage window(Options(MappingMode::kFull));
  ASSERT_TRUE(window.use_imu_states());
  const Eigen::Vector3d v(5.0, 0.0, 0.0);
  ASSERT_TRUE(window.Start(v, Vector6d::Zero()).ok());
  PreviousScan prev = Previous(1, Eigen::Isometry3d::Identity());
  prev.has_pos = true;
  prev.v_submap = Eigen::Vector3d::Zero();  // overwritten by the window's estimate
  ScanMotionInput motion;
  motion.type = MotionFactorType::kOdometry;
  motion.T_world_body_pos_start = Forward(0.5);
  motion.T_world_body_pos_end = Forward(1.0);
  motion.v_world_pos = v;
  ScanStep step = Step(MotionFactorType::kOdometry, Forward(0.5));
  step.pred.v_submap = v;
  LocalizationResult res;
  ASSERT_TRUE(window.AddFactors(MakeScan(1), motion, prev, &step, &res).ok());
  ASSERT_TRUE(window.Optimize(MakeScan(1), &step, &prev, &res).ok());
  EXPECT_LT((prev.v_submap - v).norm(), 1e-3);
  EXPECT_LT(DistM(step.T_submap_cur, Forward(0.5)), 1e-6);
}

}  // namespace
}  // namespace slam_mms::internal
