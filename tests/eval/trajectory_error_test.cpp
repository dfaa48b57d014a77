#include "slam_mms/eval/trajectory_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <random>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/eval/umeyama.hpp"

namespace slam_mms::eval {
namespace {

constexpr double kDeg = M_PI / 180.0;
const Timestamp kT0 = Timestamp::FromNanoseconds(1317042651000000000LL);

// A curved drive: circle of radius 50 m at 10 m/s, heading tangent, some pitch/roll wiggle.
Eigen::Isometry3d CurvePose(double t) {
  const double w = 10.0 / 50.0;
  const double a = w * t;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() =
      Eigen::Vector3d(50.0 * std::sin(a), 50.0 * (1.0 - std::cos(a)), 0.5 * std::sin(0.3 * t));
  T.linear() = FromRollPitchYaw(0.02 * std::sin(t), 0.01 * std::cos(0.5 * t), a);
  return T;
}

Trajectory MakeTrajectory(double t_begin, double t_end, double dt,
                          const std::function<Eigen::Isometry3d(double)>& pose) {
  Trajectory traj;
  const int n = static_cast<int>(std::floor((t_end - t_begin) / dt + 1e-9)) + 1;
  for (int i = 0; i < n; ++i) {
    const double t = t_begin + i * dt;
    EXPECT_TRUE(traj.Add(kT0.PlusSeconds(t), pose(t)).ok());
  }
  return traj;
}

TEST(TrajectoryErrorTest, ConstantOffsetGivesOffsetPerAxis) {
  const Trajectory gt = MakeTrajectory(0.0, 20.0, 0.1, CurvePose);
  const Eigen::Vector3d offset(0.3, -0.4, 1.2);
  const Trajectory est = MakeTrajectory(0.0, 20.0, 0.1, [&](double t) {
    Eigen::Isometry3d T = CurvePose(t);
    T.translation() += offset;
    return T;
  });
  const StatusOr<AteResult> r = ComputeAte(est, gt);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_EQ(r->alignment, Alignment::kNone);
  EXPECT_EQ(r->num_matched, gt.size());
  EXPECT_EQ(r->num_unmatched, 0u);
  EXPECT_NEAR(r->ate_rmse_xyz_m.x(), 0.3, 1e-9);
  EXPECT_NEAR(r->ate_rmse_xyz_m.y(), 0.4, 1e-9);
  EXPECT_NEAR(r->ate_rmse_xyz_m.z(), 1.2, 1e-9);
  EXPECT_NEAR(r->ate_rmse_m, 1.3, 1e-9);
  EXPECT_NEAR(r->ate_max_m, 1.3, 1e-9);
  EXPECT_NEAR(r->ate_median_m, 1.3, 1e-9);
  EXPECT_NEAR(r->rot_rmse_deg, 0.0, 1e-6);

  // SE(3) alignment removes a pure offset.
  AteOptions aligned;
  aligned.alignment = Alignment::kSe3;
  const StatusOr<AteResult> ra = ComputeAte(est, gt, aligned);
  ASSERT_TRUE(ra.ok()) << ra.status().ToString();
  EXPECT_NEAR(ra->ate_rmse_m, 0.0, 1e-9);
  EXPECT_TRUE(ra->T_gt_est.t.isApprox(-offset, 1e-9));
}

TEST(TrajectoryErrorTest, GroundTruthIsInterpolatedAtEstimateStamps) {
  // Ground truth at 10 Hz; estimate exactly on the true motion but stamped 0.037 s after each
  // ground-truth sample. Linear motion: interpolation is exact, nearest-neighbour would be 0.37 m
  // off.
  auto line = [](double t) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(10.0 * t, 2.0 * t, 0.0);
    T.linear() = FromRollPitchYaw(0.0, 0.0, 0.1 * t);  // slerp of a constant-rate yaw is exact too
    return T;
  };
  const Trajectory gt = MakeTrajectory(0.0, 10.0, 0.1, line);
  const Trajectory est = MakeTrajectory(0.037, 9.95, 0.1, line);
  const StatusOr<AteResult> r = ComputeAte(est, gt);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_EQ(r->num_matched, est.size());
  EXPECT_LT(r->ate_max_m, 1e-6);
  EXPECT_LT(r->rot_max_deg, 1e-6);
}

TEST(TrajectoryErrorTest, KnownYawOffsetGivesRotationRmse) {
  const Trajectory gt = MakeTrajectory(0.0, 10.0, 0.1, CurvePose);
  const Trajectory est = MakeTrajectory(0.0, 10.0, 0.1, [](double t) {
    Eigen::Isometry3d T = CurvePose(t);
    const Eigen::Vector3d rpy = RollPitchYaw(T.linear());
    T.linear() = FromRollPitchYaw(rpy(0), rpy(1), rpy(2) + 2.0 * kDeg);
    return T;
  });
  const StatusOr<AteResult> r = ComputeAte(est, gt);
  ASSERT_TRUE(r.ok());
  EXPECT_NEAR(r->ate_rmse_m, 0.0, 1e-9);
  EXPECT_NEAR(r->rot_rmse_rpy_deg.x(), 0.0, 1e-9);
  EXPECT_NEAR(r->rot_rmse_rpy_deg.y(), 0.0, 1e-9);
  EXPECT_NEAR(r->rot_rmse_rpy_deg.z(), 2.0, 1e-9);
  EXPECT_NEAR(r->rot_mean_rpy_deg.z(), 2.0, 1e-9);  // a constant offset: its mean, signed
  EXPECT_NEAR(r->rot_mean_rpy_deg.x(), 0.0, 1e-9);
  // Small roll/pitch: the total angle is the yaw offset up to second order.
  EXPECT_NEAR(r->rot_rmse_deg, 2.0, 1e-3);
  // A yaw error alternating -1 / +3 deg: mean +1, RMS sqrt(5).
  int k = 0;
  const Trajectory alternating = MakeTrajectory(0.0, 9.9, 0.1, [&k](double t) {  // 100 poses
    Eigen::Isometry3d T = CurvePose(t);
    const Eigen::Vector3d rpy = RollPitchYaw(T.linear());
    T.linear() = FromRollPitchYaw(rpy(0), rpy(1), rpy(2) + ((k++ % 2) == 0 ? -1.0 : 3.0) * kDeg);
    return T;
  });
  const StatusOr<AteResult> a = ComputeAte(alternating, gt);
  ASSERT_TRUE(a.ok());
  ASSERT_EQ(a->num_matched % 2, 0u);
  EXPECT_NEAR(a->rot_mean_rpy_deg.z(), 1.0, 1e-9);
  EXPECT_NEAR(a->rot_rmse_rpy_deg.z(), std::sqrt(5.0), 1e-9);
}

TEST(TrajectoryErrorTest, YawErrorWrapsAcrossPi) {
  // gt yaw +179 deg, est yaw -179 deg: a 2 deg error, not 358.
  Trajectory gt, est;
  for (int i = 0; i < 5; ++i) {
    ASSERT_TRUE(gt.Add(kT0.PlusSeconds(i),
                       MakeIsometry(FromRollPitchYaw(0, 0, 179 * kDeg), Eigen::Vector3d(i, 0, 0)))
                    .ok());
    ASSERT_TRUE(est.Add(kT0.PlusSeconds(i),
                        MakeIsometry(FromRollPitchYaw(0, 0, -179 * kDeg), Eigen::Vector3d(i, 0, 0)))
                    .ok());
  }
  const StatusOr<AteResult> r = ComputeAte(est, gt);
  ASSERT_TRUE(r.ok());
  EXPECT_NEAR(r->rot_rmse_rpy_deg.z(), 2.0, 1e-9);
  EXPECT_NEAR(r->rot_mean_rpy_deg.z(), 2.0, 1e-9);  // wrapped before the mean
  EXPECT_NEAR(r->rot_rmse_deg, 2.0, 1e-9);
}

TEST(TrajectoryErrorTest, PosesOutsideGroundTruthOrInGapsAreSkippedAndCounted) {
  Trajectory gt;
  // 0..5 s at 10 Hz, then a 3 s gap, then 8..10 s.
  for (int i = 0; i <= 50; ++i)
    ASSERT_TRUE(gt.Add(kT0.PlusSeconds(0.1 * i), CurvePose(0.1 * i)).ok());
  for (int i = 80; i <= 100; ++i)
    ASSERT_TRUE(gt.Add(kT0.PlusSeconds(0.1 * i), CurvePose(0.1 * i)).ok());
  const Trajectory est = MakeTrajectory(-1.0, 11.0, 0.5, CurvePose);  // 25 poses
  const StatusOr<MatchedPoses> m = MatchByTimestamp(est, gt);
  ASSERT_TRUE(m.ok()) << m.status().ToString();
  // Inside: 0.0..5.0 (11 poses) and 8.0..10.0 (5 poses); outside span: -1, -0.5, 10.5, 11 (4);
  // in the gap: 5.5 .. 7.5 (5).
  EXPECT_EQ(m->size(), 16u);
  EXPECT_EQ(m->num_unmatched, 9u);

  MatchOptions wide;
  wide.max_ground_truth_gap_s = 5.0;
  const StatusOr<MatchedPoses> m2 = MatchByTimestamp(est, gt, wide);
  ASSERT_TRUE(m2.ok());
  EXPECT_EQ(m2->size(), 21u);
}

TEST(TrajectoryErrorTest, NoOverlapAndBadOptionsFail) {
  const Trajectory gt = MakeTrajectory(0.0, 5.0, 0.1, CurvePose);
  const Trajectory est = MakeTrajectory(10.0, 15.0, 0.1, CurvePose);
  EXPECT_EQ(ComputeAte(est, gt).status().code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(ComputeAte(Trajectory(), gt).status().code(), StatusCode::kInvalidArgument);
  AteOptions bad;
  bad.match.max_ground_truth_gap_s = 0.0;
  const Status s = ComputeAte(gt, gt, bad).status();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("max_ground_truth_gap_s"), std::string::npos);
}

TEST(UmeyamaTest, RecoversKnownSe3AndSim3) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  std::vector<Eigen::Vector3d> src, dst_rigid, dst_sim;
  const Eigen::Matrix3d R = FromRollPitchYaw(0.1, -0.2, 2.5);
  const Eigen::Vector3d t(12.0, -3.0, 0.7);
  const double s = 1.07;
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d p(u(rng), u(rng), 0.1 * u(rng));
    src.push_back(p);
    dst_rigid.push_back(R * p + t);
    dst_sim.push_back(s * (R * p) + t);
  }
  const StatusOr<SimilarityTransform> se3 = UmeyamaAlignment(src, dst_rigid, false);
  ASSERT_TRUE(se3.ok()) << se3.status().ToString();
  EXPECT_TRUE(se3->R.isApprox(R, 1e-10));
  EXPECT_TRUE(se3->t.isApprox(t, 1e-10));
  EXPECT_DOUBLE_EQ(se3->scale, 1.0);

  const StatusOr<SimilarityTransform> sim3 = UmeyamaAlignment(src, dst_sim, true);
  ASSERT_TRUE(sim3.ok());
  EXPECT_TRUE(sim3->R.isApprox(R, 1e-10));
  EXPECT_TRUE(sim3->t.isApprox(t, 1e-10));
  EXPECT_NEAR(sim3->scale, s, 1e-10);
  EXPECT_NEAR((sim3->operator*(src[3]) - dst_sim[3]).norm(), 0.0, 1e-9);

  // Fixing the scale on scaled data leaves a residual: the fit is not exact.
  const StatusOr<SimilarityTransform> se3_on_sim = UmeyamaAlignment(src, dst_sim, false);
  ASSERT_TRUE(se3_on_sim.ok());
  EXPECT_GT((se3_on_sim->operator*(src[0]) - dst_sim[0]).norm(), 1e-3);
}

TEST(UmeyamaTest, RejectsDegenerateInput) {
  std::vector<Eigen::Vector3d> line, moved;
  for (int i = 0; i < 10; ++i) {
    line.emplace_back(i, 2.0 * i, 0.0);
    moved.emplace_back(i + 1.0, 2.0 * i, 0.0);
  }
  EXPECT_EQ(UmeyamaAlignment(line, moved, false).status().code(), StatusCode::kInvalidArgument);
  EXPECT_FALSE(UmeyamaAlignment({line[0], line[1]}, {moved[0], moved[1]}, false).ok());
  moved.pop_back();
  EXPECT_FALSE(UmeyamaAlignment(line, moved, false).ok());
}

TEST(TrajectoryErrorTest, Sim3AlignmentUndoesScaleAndTransform) {
  const Trajectory gt = MakeTrajectory(0.0, 30.0, 0.1, CurvePose);
  const Eigen::Matrix3d R = FromRollPitchYaw(0.0, 0.0, 0.7);
  const Eigen::Vector3d t(100.0, -50.0, 3.0);
  const double s = 0.8;
  const Trajectory est = MakeTrajectory(0.0, 30.0, 0.1, [&](double tt) {
    const Eigen::Isometry3d T = CurvePose(tt);
    return MakeIsometry(R * T.linear(), s * (R * T.translation()) + t);
  });
  AteOptions o;
  o.alignment = Alignment::kSim3;
  const StatusOr<AteResult> r = ComputeAte(est, gt, o);
  ASSERT_TRUE(r.ok());
  EXPECT_NEAR(r->ate_rmse_m, 0.0, 1e-8);
  EXPECT_NEAR(r->rot_rmse_deg, 0.0, 1e-6);
  EXPECT_NEAR(r->T_gt_est.scale, 1.0 / s, 1e-10);
  o.alignment = Alignment::kNone;
  EXPECT_GT(ComputeAte(est, gt, o)->ate_rmse_m, 50.0);
}

// Errors drawn from each pose's covariance give a NEES near its dof (3) with ~95 % inside the
// 95 % interval; the same errors with the covariance claimed 10x smaller (std) are flagged.
TEST(TrajectoryErrorTest, NeesOfConsistentAndOverconfidentCovariances) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n01(0.0, 1.0);
  const Trajectory gt = MakeTrajectory(0.0, 200.0, 0.1, CurvePose);
  Trajectory honest, overconfident, no_cov;
  // Body-frame sigmas: rotation 0.2/0.3/0.5 deg, translation 0.1/0.2/0.4 m (right perturbation).
  Eigen::Matrix<double, 6, 1> sigma;
  sigma << 0.2 * kDeg, 0.3 * kDeg, 0.5 * kDeg, 0.1, 0.2, 0.4;
  const Eigen::Matrix<double, 6, 6> C = sigma.cwiseProduct(sigma).asDiagonal();
  for (int i = 0; i < 2000; ++i) {
    const double t = 0.1 * i;
    Eigen::Matrix<double, 6, 1> d;
    for (int k = 0; k < 6; ++k) d(k) = sigma(k) * n01(rng);
    const Eigen::Isometry3d T_gt = CurvePose(t);
    // T_est = T_gt Exp(-d): the error of the estimate about the truth has the covariance C.
    Eigen::Isometry3d T_est = Eigen::Isometry3d::Identity();
    T_est.linear() = T_gt.linear() * so3::Exp(-d.head<3>());
    T_est.translation() = T_gt.translation() - T_est.linear() * d.tail<3>();
    StampedPose p;
    p.stamp = kT0.PlusSeconds(t);
    p.T_world_body = T_est;
    p.cov_T_world_body = C;
    ASSERT_TRUE(honest.Add(p).ok());
    p.cov_T_world_body = 0.01 * C;
    ASSERT_TRUE(overconfident.Add(p).ok());
    ASSERT_TRUE(no_cov.Add(p.stamp, T_est).ok());
  }
  const StatusOr<NeesResult> h = ComputeNees(honest, gt);
  const StatusOr<NeesResult> o = ComputeNees(overconfident, gt);
  ASSERT_TRUE(h.ok()) << h.status().ToString();
  ASSERT_TRUE(o.ok());
  EXPECT_EQ(h->num_epochs, 2000u);
  EXPECT_NEAR(h->position_mean, 3.0, 0.3);
  EXPECT_NEAR(h->attitude_mean, 3.0, 0.3);
  EXPECT_NEAR(h->position_fraction_inside_95, 0.95, 0.02);
  EXPECT_NEAR(h->attitude_fraction_inside_95, 0.95, 0.02);
  EXPECT_NEAR(o->position_mean, 300.0, 30.0);
  EXPECT_LT(o->position_fraction_inside_95, 0.05);
  EXPECT_EQ(ComputeNees(no_cov, gt).status().code(), StatusCode::kInvalidArgument);
}

// A relative-pose measurement against the truth: the error in the true b frame, rotation first,
// and its chi2 against the stated covariance; NaN where the covariance is not positive definite.
TEST(TrajectoryErrorTest, RelativePoseErrorAgainstTruth) {
  const Eigen::Isometry3d T_world_a = se3::Exp((Vector6d() << 0.1, -0.2, 0.7, 5, 3, 1).finished());
  const Eigen::Isometry3d T_a_b_true =
      se3::Exp((Vector6d() << 0.0, 0.05, 0.3, 20, 1, 0).finished());
  const Eigen::Isometry3d T_world_b = T_world_a * T_a_b_true;
  const Vector6d xi = (Vector6d() << 0.002, 0.0, -0.001, 0.03, -0.02, 0.01).finished();
  const Eigen::Isometry3d T_a_b = T_a_b_true * se3::Exp(xi);
  Matrix6d cov = Matrix6d::Zero();
  cov.diagonal() << 1e-6, 1e-6, 4e-6, 1e-4, 1e-4, 4e-4;
  const RelativePoseError e = RelativePoseErrorAgainstTruth(T_a_b, cov, T_world_a, T_world_b);
  EXPECT_LT((e.error - xi).norm(), 1e-9);
  const double expected = 4.0 + 0.0 + 0.25 + 9.0 + 4.0 + 0.25;
  EXPECT_NEAR(e.chi2, expected, 1e-6);
  Matrix6d bad = cov;
  bad(2, 2) = -1.0;
  EXPECT_TRUE(std::isnan(RelativePoseErrorAgainstTruth(T_a_b, bad, T_world_a, T_world_b).chi2));
}

TEST(TrajectoryErrorTest, WrapAngle) {
  EXPECT_NEAR(WrapAngle(3.0 * M_PI / 2.0), -M_PI / 2.0, 1e-12);
  EXPECT_NEAR(WrapAngle(-3.0 * M_PI / 2.0), M_PI / 2.0, 1e-12);
  EXPECT_NEAR(WrapAngle(M_PI), M_PI, 1e-12);
  EXPECT_NEAR(WrapAngle(-M_PI), M_PI, 1e-12);
  EXPECT_NEAR(WrapAngle(0.25), 0.25, 1e-15);
}

}  // namespace
}  // namespace slam_mms::eval
