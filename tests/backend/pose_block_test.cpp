#include "backend/pose_block.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <random>

#include "slam_mms/core/lie.hpp"

namespace slam_mms {
namespace {

Eigen::Isometry3d RandomPose(std::mt19937* rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return MakeIsometry(so3::Exp(Eigen::Vector3d(n(*rng), n(*rng), n(*rng))),
                      Eigen::Vector3d(n(*rng), n(*rng), n(*rng)) * 100.0);
}

TEST(PoseBlockTest, RoundTripAndLayout) {
  std::mt19937 rng(5);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Isometry3d T = RandomPose(&rng);
    const PoseBlock b = PoseToBlock(T);
    EXPECT_EQ(b[0], T.translation().x());
    EXPECT_EQ(b[2], T.translation().z());
    // [qx, qy, qz, qw]: Eigen's memory order.
    const Eigen::Map<const Eigen::Quaterniond> q(b.data() + 3);
    EXPECT_LT(RotationAngle(q.toRotationMatrix().transpose() * T.linear()), 1e-12);
    EXPECT_TRUE(PoseFromBlock(b).isApprox(T, 1e-12));
  }
}

TEST(PoseBlockTest, ManifoldInvariants) {
  std::unique_ptr<ceres::Manifold> m(NewPoseManifold());
  ASSERT_EQ(m->AmbientSize(), 7);
  ASSERT_EQ(m->TangentSize(), 6);
  std::mt19937 rng(6);
  std::normal_distribution<double> n(0.0, 0.1);
  for (int i = 0; i < 20; ++i) {
    const PoseBlock x = PoseToBlock(RandomPose(&rng));
    double delta[6], y[7], back[6];
    for (double& d : delta) d = n(rng);
    ASSERT_TRUE(m->Plus(x.data(), delta, y));
    ASSERT_TRUE(m->Minus(y, x.data(), back));
    for (int k = 0; k < 6; ++k) EXPECT_NEAR(back[k], delta[k], 1e-9);
    // Translation is the plain sum (the first three tangent coordinates).
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(y[k], x[k] + delta[k], 1e-12);
  }
}

TEST(PoseBlockTest, QuaternionRightTangentToAmbientInvertsARightPerturbation) {
  // delta_theta(q') ~= J (q' - q) for q' = q * Exp(dtheta), the library's right perturbation.
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 20; ++i) {
    const Eigen::Quaterniond q(so3::Exp(Eigen::Vector3d(n(rng), n(rng), n(rng))));
    const Eigen::Vector3d dtheta = 1e-6 * Eigen::Vector3d(n(rng), n(rng), n(rng));
    const Eigen::Quaterniond q2 = q * so3::ExpQuaternion(dtheta);
    const Eigen::Vector4d dq = q2.coeffs() - q.coeffs();
    EXPECT_LT((QuaternionRightTangentToAmbient(q) * dq - dtheta).norm(), 1e-11);
    // The radial direction (scaling q) does not move the rotation.
    EXPECT_LT((QuaternionRightTangentToAmbient(q) * q.coeffs()).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace slam_mms
