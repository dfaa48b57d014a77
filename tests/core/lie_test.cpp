#include "slam_mms/core/lie.hpp"

#include <gtest/gtest.h>

#include <random>

namespace slam_mms {
namespace {

class LieTest : public ::testing::Test {
 protected:
  Eigen::Vector3d RandomVec(double scale) {
    std::uniform_real_distribution<double> u(-scale, scale);
    return {u(rng_), u(rng_), u(rng_)};
  }
  Vector6d RandomXi(double rot_scale, double trans_scale) {
    Vector6d xi;
    xi << RandomVec(rot_scale), RandomVec(trans_scale);
    return xi;
  }
  std::mt19937 rng_{42};
};

TEST_F(LieTest, So3ExpLogRoundTripIncludingSmallAndNearPi) {
  for (double scale : {1e-12, 1e-6, 0.1, 1.0, 1.8}) {
    for (int i = 0; i < 50; ++i) {
      const Eigen::Vector3d w = RandomVec(scale);
      const Eigen::Vector3d back = so3::Log(so3::Exp(w));
      EXPECT_LT((back - w).norm(), 1e-9 * std::max(1.0, w.norm())) << w.transpose();
    }
  }
  const Eigen::Vector3d near_pi = Eigen::Vector3d(0.0, 0.0, M_PI - 1e-7);
  EXPECT_NEAR(so3::Log(so3::Exp(near_pi)).norm(), near_pi.norm(), 1e-6);
}

TEST_F(LieTest, So3HatVeeAndOrthonormality) {
  const Eigen::Vector3d a = RandomVec(2.0), b = RandomVec(2.0);
  EXPECT_LT((so3::Hat(a) * b - a.cross(b)).norm(), 1e-12);
  EXPECT_LT((so3::Vee(so3::Hat(a)) - a).norm(), 1e-15);
  const Eigen::Matrix3d R = so3::Exp(a);
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
}

TEST_F(LieTest, So3RightJacobianMatchesNumericDifferentiation) {
  for (double scale : {1e-9, 0.3, 2.0}) {
    const Eigen::Vector3d w = RandomVec(scale);
    Eigen::Matrix3d J_num;
    const double h = 1e-6;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d d = Eigen::Vector3d::Unit(k) * h;
      J_num.col(k) = so3::Log(Eigen::Matrix3d(so3::Exp(w).transpose() * so3::Exp(w + d))) / h;
    }
    EXPECT_LT((J_num - so3::RightJacobian(w)).norm(), 1e-5) << "scale " << scale;
    EXPECT_LT(
        (so3::RightJacobian(w) * so3::RightJacobianInverse(w) - Eigen::Matrix3d::Identity()).norm(),
        1e-9);
    EXPECT_LT(
        (so3::LeftJacobian(w) * so3::LeftJacobianInverse(w) - Eigen::Matrix3d::Identity()).norm(),
        1e-9);
  }
}

TEST_F(LieTest, Se3ExpLogRoundTrip) {
  for (double scale : {1e-10, 0.1, 1.0, 2.5}) {
    for (int i = 0; i < 50; ++i) {
      // Rotation norm kept below pi (sqrt(3) * 1.7 < pi), where Log is the inverse of Exp.
      const Vector6d xi = RandomXi(std::min(scale, 1.7), 10.0 * scale);
      const Vector6d back = se3::Log(se3::Exp(xi));
      EXPECT_LT((back - xi).norm(), 1e-8 * std::max(1.0, xi.norm()));
    }
  }
}

TEST_F(LieTest, Se3RightJacobianMatchesNumericDifferentiation) {
  for (double scale : {1e-9, 0.2, 1.5}) {
    const Vector6d xi = RandomXi(scale, 3.0);
    Matrix6d J_num;
    const double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      const Vector6d d = Vector6d::Unit(k) * h;
      J_num.col(k) = se3::Log(se3::Exp(xi).inverse() * se3::Exp(xi + d)) / h;
    }
    EXPECT_LT((J_num - se3::RightJacobian(xi)).norm(), 1e-5) << "scale " << scale;
    EXPECT_LT(
        (se3::RightJacobian(xi) * se3::RightJacobianInverse(xi) - Matrix6d::Identity()).norm(),
        1e-9);
  }
}

TEST_F(LieTest, Se3AdjointIdentity) {
  const Eigen::Isometry3d T = se3::Exp(RandomXi(1.0, 5.0));
  const Vector6d xi = RandomXi(0.5, 2.0);
  const Eigen::Isometry3d lhs = se3::Exp(se3::Adjoint(T) * xi);
  const Eigen::Isometry3d rhs = T * se3::Exp(xi) * T.inverse();
  EXPECT_LT((lhs.matrix() - rhs.matrix()).norm(), 1e-10);
}

TEST_F(LieTest, InterpolatePoseEndpointsAndMidpoint) {
  const Eigen::Isometry3d A = se3::Exp(RandomXi(1.0, 5.0));
  const Eigen::Isometry3d B = se3::Exp(RandomXi(1.0, 5.0));
  EXPECT_LT((InterpolatePose(A, B, 0.0).matrix() - A.matrix()).norm(), 1e-10);
  EXPECT_LT((InterpolatePose(A, B, 1.0).matrix() - B.matrix()).norm(), 1e-10);
  const Eigen::Isometry3d M = InterpolatePose(A, B, 0.5);
  const double angle_am = RotationAngle(A.linear().transpose() * M.linear());
  const double angle_mb = RotationAngle(M.linear().transpose() * B.linear());
  EXPECT_NEAR(angle_am, angle_mb, 1e-9);
  EXPECT_LT((M.translation() - 0.5 * (A.translation() + B.translation())).norm(), 1e-12);
}

TEST_F(LieTest, RollPitchYawRoundTrip) {
  for (int i = 0; i < 50; ++i) {
    const Eigen::Vector3d rpy(RandomVec(3.0).x(), RandomVec(1.5).y(), RandomVec(3.0).z());
    const Eigen::Vector3d back = RollPitchYaw(FromRollPitchYaw(rpy.x(), rpy.y(), rpy.z()));
    EXPECT_LT((back - rpy).norm(), 1e-9);
  }
}

}  // namespace
}  // namespace slam_mms

#include "slam_mms/core/trajectory.hpp"

namespace slam_mms {
namespace {

TEST(TrajectoryTest, InterpolationOrderingAndRange) {
  Trajectory traj;
  const Timestamp t0 = Timestamp::FromNanoseconds(1'000'000'000);
  ASSERT_TRUE(traj.Add(t0, Eigen::Isometry3d::Identity()).ok());
  Eigen::Isometry3d T1 = MakeIsometry(so3::Exp(Eigen::Vector3d(0, 0, 0.2)), {2.0, 0.0, 0.0});
  ASSERT_TRUE(traj.Add(t0.PlusSeconds(1.0), T1).ok());
  EXPECT_EQ(traj.Add(t0.PlusSeconds(0.5), T1).code(), StatusCode::kInvalidArgument);
  const auto mid = traj.Interpolate(t0.PlusSeconds(0.25));
  ASSERT_TRUE(mid.ok());
  EXPECT_NEAR(mid->translation().x(), 0.5, 1e-12);
  EXPECT_NEAR(RotationAngle(mid->linear()), 0.05, 1e-12);
  EXPECT_EQ(traj.Interpolate(t0.PlusSeconds(1.5)).status().code(), StatusCode::kOutOfRange);
  EXPECT_NEAR(traj.PathLength(), 2.0, 1e-12);
}

}  // namespace
}  // namespace slam_mms
