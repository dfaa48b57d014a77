// Jacobians of the backend's cost functions against numeric differentiation (ambient coordinates
// and, through ceres::GradientChecker, the PoseManifold tangent), plus validation of bad inputs.
#include <ceres/gradient_checker.h>
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "backend/backend_test_util.hpp"
#include "backend/pose_block.hpp"
#include "backend/pose_prior_factor.hpp"
#include "backend/relative_pose_factor.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms {
namespace {

using testing_backend::CheckAmbientJacobians;
using testing_backend::RandomPose;

Matrix6d RandomCovariance(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Matrix6d A;
  for (int i = 0; i < 36; ++i) A(i) = n(rng);
  return 0.01 * A * A.transpose() + 1e-3 * Matrix6d::Identity();
}

TEST(RelativePoseFactorTest, AmbientJacobiansMatchNumeric) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Isometry3d T_w_a = RandomPose(rng, 1.0, 10.0);
    const Eigen::Isometry3d T_w_b = RandomPose(rng, 1.0, 10.0);
    // Measurement near the truth, plus some rotations far from it (large residual angle).
    const Eigen::Isometry3d noise = RandomPose(rng, trial < 10 ? 0.05 : 1.0, 0.5);
    const Eigen::Isometry3d T_a_b = T_w_a.inverse() * T_w_b * noise;
    auto f = RelativePoseFactor::Create(T_a_b, RandomCovariance(rng));
    ASSERT_TRUE(f.ok()) << f.status().ToString();
    std::vector<std::vector<double>> blocks(2, std::vector<double>(7));
    PoseToBlock(T_w_a, blocks[0].data());
    PoseToBlock(T_w_b, blocks[1].data());
    CheckAmbientJacobians(**f, blocks, 1e-5);
  }
}

TEST(RelativePoseFactorTest, TangentJacobiansPassCeresGradientChecker) {
  std::mt19937 rng(11);
  std::vector<const ceres::Manifold*> manifolds;
  std::unique_ptr<ceres::Manifold> m0(NewPoseManifold()), m1(NewPoseManifold());
  manifolds = {m0.get(), m1.get()};
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Isometry3d T_w_a = RandomPose(rng, 1.0, 10.0);
    const Eigen::Isometry3d T_w_b = RandomPose(rng, 1.0, 10.0);
    const Eigen::Isometry3d T_a_b = T_w_a.inverse() * T_w_b * RandomPose(rng, 0.1, 0.5);
    auto f = RelativePoseFactor::Create(T_a_b, RandomCovariance(rng));
    ASSERT_TRUE(f.ok());
    ceres::NumericDiffOptions nd;
    ceres::GradientChecker checker(f->get(), &manifolds, nd);
    const PoseBlock a = PoseToBlock(T_w_a), b = PoseToBlock(T_w_b);
    const double* params[] = {a.data(), b.data()};
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(params, 1e-6, &results)) << results.error_log;
  }
}

TEST(RelativePoseFactorTest, ResidualIsZeroAtTheMeasurementAndWhitened) {
  std::mt19937 rng(3);
  const Eigen::Isometry3d T_w_a = RandomPose(rng, 1.0, 5.0);
  const Eigen::Isometry3d T_a_b = RandomPose(rng, 0.5, 5.0);
  Matrix6d cov = Matrix6d::Zero();
  cov.diagonal() << 1e-4, 1e-4, 1e-4, 0.04, 0.04, 0.04;
  auto f = RelativePoseFactor::Create(T_a_b, cov);
  ASSERT_TRUE(f.ok());
  const PoseBlock a = PoseToBlock(T_w_a), b = PoseToBlock(T_w_a * T_a_b);
  const double* params[] = {a.data(), b.data()};
  Vector6d r;
  ASSERT_TRUE((*f)->Evaluate(params, r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-9);
  // A 0.2 m error along the x axis of frame a is one standard deviation.
  Eigen::Isometry3d T_a_b_off = T_a_b;
  T_a_b_off.translation() += T_w_a.linear().transpose() * Eigen::Vector3d::Zero();
  const PoseBlock b_off = PoseToBlock(T_w_a * Eigen::Translation3d(0.2, 0.0, 0.0) * T_a_b);
  const double* params_off[] = {a.data(), b_off.data()};
  ASSERT_TRUE((*f)->Evaluate(params_off, r.data(), nullptr));
  EXPECT_NEAR(r.norm(), 1.0, 1e-9);
}

TEST(PosePriorFactorTest, AmbientJacobiansMatchNumericAndGradientChecker) {
  std::mt19937 rng(5);
  std::unique_ptr<ceres::Manifold> m0(NewPoseManifold());
  std::vector<const ceres::Manifold*> manifolds = {m0.get()};
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Isometry3d T_prior = RandomPose(rng, 1.0, 10.0);
    const Eigen::Isometry3d T = T_prior * RandomPose(rng, trial < 10 ? 0.1 : 1.0, 1.0);
    auto f = PosePriorFactor::Create(T_prior, RandomCovariance(rng));
    ASSERT_TRUE(f.ok());
    std::vector<std::vector<double>> blocks(1, std::vector<double>(7));
    PoseToBlock(T, blocks[0].data());
    CheckAmbientJacobians(**f, blocks, 1e-5);
    ceres::NumericDiffOptions nd;
    ceres::GradientChecker checker(f->get(), &manifolds, nd);
    const double* params[] = {blocks[0].data()};
    ceres::GradientChecker::ProbeResults results;
    EXPECT_TRUE(checker.Probe(params, 1e-6, &results)) << results.error_log;
  }
}

TEST(FactorValidationTest, BadCovariancesAndPosesAreRejected) {
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  Matrix6d cov = Matrix6d::Identity();
  EXPECT_TRUE(RelativePoseFactor::Create(I, cov).ok());
  Matrix6d nan_cov = cov;
  nan_cov(2, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(RelativePoseFactor::Create(I, nan_cov).status().code(), StatusCode::kInvalidArgument);
  Matrix6d indefinite = cov;
  indefinite(4, 4) = -1.0;
  EXPECT_EQ(RelativePoseFactor::Create(I, indefinite).status().code(),
            StatusCode::kInvalidArgument);
  Matrix6d asym = cov;
  asym(0, 1) = 0.5;
  EXPECT_EQ(PosePriorFactor::Create(I, asym).status().code(), StatusCode::kInvalidArgument);
  EXPECT_FALSE(PosePriorFactor::Create(I, Matrix6d::Zero()).ok());
  Eigen::Isometry3d bad = I;
  bad.linear()(0, 0) = 2.0;
  EXPECT_FALSE(RelativePoseFactor::Create(bad, cov).ok());
  Eigen::Isometry3d nan_pose = I;
  nan_pose.translation().x() = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(PosePriorFactor::Create(nan_pose, cov).ok());
}

}  // namespace
}  // namespace slam_mms
