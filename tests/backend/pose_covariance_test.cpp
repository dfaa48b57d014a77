// backend_internal::PoseBlockCovariance: the marginal covariance of a pose block, (a) against the
// closed form for a single prior, (b) the same bits whatever the memory addresses of the blocks and
// the thread count (ceres::Covariance ordered blocks by address: issue #19's determinism finding),
// (c) its errors.
#include <ceres/loss_function.h>
#include <ceres/problem.h>
#include <gtest/gtest.h>

#include <array>
#include <memory>
#include <random>
#include <vector>

#include "backend/ceres_solve.hpp"
#include "backend/pose_block.hpp"
#include "backend/pose_prior_factor.hpp"
#include "backend/relative_pose_factor.hpp"
#include "backend_test_util.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms {
namespace {

using backend_internal::PoseBlockCovariance;
using testing_backend::DiagonalCovariance;

ceres::Problem::Options ProblemOptions() {
  ceres::Problem::Options o;
  o.manifold_ownership = ceres::TAKE_OWNERSHIP;
  return o;
}

TEST(PoseCovarianceTest, SinglePriorGivesItsCovariance) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  // A full (correlated) prior covariance.
  Matrix6d A;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) A(i, j) = 0.1 * n(rng);
  }
  const Matrix6d sigma = A * A.transpose() + DiagonalCovariance(0.01, 0.1);
  const Eigen::Isometry3d T =
      MakeIsometry(so3::Exp(Eigen::Vector3d(0.3, -0.2, 1.1)), Eigen::Vector3d(10.0, -4.0, 2.0));
  PoseBlock block = PoseToBlock(T);
  ceres::Problem problem(ProblemOptions());
  problem.AddParameterBlock(block.data(), kPoseBlockSize, NewPoseManifold());
  auto prior = PosePriorFactor::Create(T, sigma);
  ASSERT_TRUE(prior.ok());
  problem.AddResidualBlock(prior->release(), nullptr, block.data());
  auto cov = PoseBlockCovariance(&problem, block.data(), 1);
  ASSERT_TRUE(cov.ok()) << cov.status().ToString();
  EXPECT_LT((*cov - sigma).norm(), 1e-9 * sigma.norm()) << *cov << "\n\n" << sigma;
}

// A chain of `n` poses with odometry and skip factors and a prior on the first, whose block for
// pose i is storage[slot(i)]: the same problem, built in the same order, at other addresses.
struct Chain {
  std::vector<PoseBlock> storage;
  std::unique_ptr<ceres::Problem> problem;
  double* block(int i) { return storage[static_cast<size_t>(slot[static_cast<size_t>(i)])].data(); }
  std::vector<int> slot;
};

void BuildChain(int n, bool reversed, Chain* c) {
  c->storage.assign(static_cast<size_t>(n), PoseBlock{});
  c->slot.resize(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) c->slot[static_cast<size_t>(i)] = reversed ? n - 1 - i : i;
  c->problem = std::make_unique<ceres::Problem>(ProblemOptions());
  std::mt19937 rng(11);
  std::normal_distribution<double> noise(0.0, 0.01);
  std::vector<Eigen::Isometry3d> truth;
  Eigen::Isometry3d cur = Eigen::Isometry3d::Identity();
  for (int i = 0; i < n; ++i) {
    truth.push_back(cur);
    Vector6d step;
    step << 0.01 * std::sin(0.7 * i), 0.02, 0.05 * std::cos(0.3 * i), 1.0, 0.1, 0.02;
    cur = cur * se3::Exp(step);
  }
  auto noisy = [&](const Eigen::Isometry3d& T) {
    Vector6d e;
    for (int k = 0; k < 6; ++k) e(k) = noise(rng);
    return T * se3::Exp(e);
  };
  for (int i = 0; i < n; ++i) {
    PoseBlock& b = c->storage[static_cast<size_t>(c->slot[static_cast<size_t>(i)])];
    b = PoseToBlock(noisy(truth[static_cast<size_t>(i)]));
    c->problem->AddParameterBlock(b.data(), kPoseBlockSize, NewPoseManifold());
    if (i == 0) {
      auto p = PosePriorFactor::Create(truth[0], DiagonalCovariance(1e-3, 1e-2));
      ASSERT_TRUE(p.ok());
      c->problem->AddResidualBlock(p->release(), nullptr, c->block(0));
    } else {
      auto f = RelativePoseFactor::Create(
          noisy(truth[static_cast<size_t>(i - 1)].inverse() * truth[static_cast<size_t>(i)]),
          DiagonalCovariance(0.01, 0.05));
      ASSERT_TRUE(f.ok());
      c->problem->AddResidualBlock(f->release(), new ceres::HuberLoss(1.0), c->block(i - 1),
                                   c->block(i));
    }
    if (i >= 2) {
      auto f = RelativePoseFactor::Create(
          noisy(truth[static_cast<size_t>(i - 2)].inverse() * truth[static_cast<size_t>(i)]),
          DiagonalCovariance(0.005, 0.03));
      ASSERT_TRUE(f.ok());
      c->problem->AddResidualBlock(f->release(), nullptr, c->block(i - 2), c->block(i));
    }
  }
}

TEST(PoseCovarianceTest, SameBitsWhateverTheAddressesAndThreads) {
  constexpr int kPoses = 40;
  Chain forward, reversed;
  BuildChain(kPoses, false, &forward);
  BuildChain(kPoses, true, &reversed);
  ASSERT_LT(reversed.block(kPoses - 1), reversed.block(0));  // address order against insertion
  for (int i : {kPoses - 1, kPoses / 2, 1}) {
    auto a = PoseBlockCovariance(forward.problem.get(), forward.block(i), 1);
    auto b = PoseBlockCovariance(reversed.problem.get(), reversed.block(i), 1);
    auto c = PoseBlockCovariance(reversed.problem.get(), reversed.block(i), 2);
    ASSERT_TRUE(a.ok() && b.ok() && c.ok()) << a.status().ToString();
    for (int k = 0; k < 36; ++k) {
      ASSERT_EQ(a->data()[k], b->data()[k]) << "pose " << i << " entry " << k;
      ASSERT_EQ(a->data()[k], c->data()[k]) << "pose " << i << " entry " << k << " (2 threads)";
    }
    // Uncertainty grows along the chain away from the prior.
    EXPECT_GT(a->trace(), 0.0);
  }
  const double near = PoseBlockCovariance(forward.problem.get(), forward.block(1), 1)->trace();
  const double far =
      PoseBlockCovariance(forward.problem.get(), forward.block(kPoses - 1), 1)->trace();
  EXPECT_GT(far, 3.0 * near);
}

TEST(PoseCovarianceTest, UnconstrainedAndConstantPosesAreErrors) {
  Chain c;
  BuildChain(5, false, &c);
  // Without the prior the chain floats: rank-deficient (gauge freedom).
  std::vector<ceres::ResidualBlockId> residuals;
  c.problem->GetResidualBlocksForParameterBlock(c.block(0), &residuals);
  for (ceres::ResidualBlockId r : residuals) {
    std::vector<double*> blocks;
    c.problem->GetParameterBlocksForResidualBlock(r, &blocks);
    if (blocks.size() == 1) c.problem->RemoveResidualBlock(r);
  }
  auto floating = PoseBlockCovariance(c.problem.get(), c.block(4), 1);
  ASSERT_FALSE(floating.ok());
  EXPECT_EQ(floating.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(floating.status().message().find("rank-deficient"), std::string::npos);
  // Holding the first pose fixes the gauge.
  c.problem->SetParameterBlockConstant(c.block(0));
  EXPECT_TRUE(PoseBlockCovariance(c.problem.get(), c.block(4), 1).ok());
  auto constant = PoseBlockCovariance(c.problem.get(), c.block(0), 1);
  ASSERT_FALSE(constant.ok());
  EXPECT_EQ(constant.status().code(), StatusCode::kFailedPrecondition);
  PoseBlock outside = PoseToBlock(Eigen::Isometry3d::Identity());
  EXPECT_EQ(PoseBlockCovariance(c.problem.get(), outside.data(), 1).status().code(),
            StatusCode::kNotFound);
}

}  // namespace
}  // namespace slam_mms
