// Ceres never sees a NaN or an invalid problem (issue 10): every backend entry point validates
// poses, covariances and states before building the problem, and a solve that fails (a factor
// producing NaN) comes back as a SolveSummary with the estimate restored, never as an abort.
#include <ceres/sized_cost_function.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "backend/backend_test_util.hpp"
#include "backend/pose_prior_factor.hpp"
#include "backend/relative_pose_factor.hpp"
#include "backend/sliding_window_graph.hpp"
#include "slam_mms/backend/submap_graph.hpp"

namespace slam_mms {
namespace {

using ::testing::HasSubstr;
using testing_backend::DiagonalCovariance;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Evaluates to NaN residuals (and Jacobians): a factor gone bad at run time.
class NanResidual final : public ceres::SizedCostFunction<1, 7> {
 public:
  bool Evaluate(double const* const*, double* residuals, double** jacobians) const override {
    residuals[0] = kNaN;
    if (jacobians != nullptr && jacobians[0] != nullptr) {
      for (int i = 0; i < 7; ++i) jacobians[0][i] = kNaN;
    }
    return true;
  }
};

TEST(BackendInputValidationTest, BadCovariancesAreRejectedWithTheReason) {
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  const Matrix6d good = DiagonalCovariance(0.01, 0.1);
  struct Case {
    Matrix6d cov;
    const char* reason;
  };
  Matrix6d nan = good, inf = good, asym = good, indefinite = good, near_singular = good;
  nan(1, 1) = kNaN;
  inf(4, 4) = kInf;
  asym(0, 5) = 1e-3;
  indefinite(3, 3) = -0.01;
  near_singular(2, 2) = 1e-20;
  const std::vector<Case> cases = {
      {nan, "NaN or Inf entry"},
      {inf, "NaN or Inf entry"},
      {Matrix6d::Zero(), "covariance is zero"},
      {asym, "not symmetric"},
      {indefinite, "not positive definite"},
      {near_singular, "not positive definite"},
  };
  for (const Case& c : cases) {
    EXPECT_THAT(RelativePoseFactor::Create(I, c.cov).status().message(), HasSubstr(c.reason));
    EXPECT_THAT(PosePriorFactor::Create(I, c.cov).status().message(), HasSubstr(c.reason));
  }
  EXPECT_TRUE(RelativePoseFactor::Create(I, good).ok());
}

TEST(BackendInputValidationTest, BadPosesAndStatesAreRejectedBeforeCeres) {
  auto g = SlidingWindowGraph::Create();
  ASSERT_TRUE(g.ok());
  const Matrix6d cov = DiagonalCovariance(0.01, 0.1);
  StateInit init;
  init.v_frame = Eigen::Vector3d(1.0, kNaN, 0.0);
  EXPECT_EQ(g->AddState(0, init).code(), StatusCode::kInvalidArgument);
  init = StateInit{};
  Vector6d bias = Vector6d::Zero();
  bias(5) = kInf;
  init.imu_bias = bias;
  EXPECT_EQ(g->AddState(0, init).code(), StatusCode::kInvalidArgument);
  init = StateInit{};
  init.T_frame_body.linear() *= 1.01;  // not a rotation
  EXPECT_THAT(g->AddState(0, init).message(), HasSubstr("rotation is not orthonormal"));

  ASSERT_TRUE(g->AddState(1, StateInit{}).ok());
  ASSERT_TRUE(g->AddState(2, StateInit{}).ok());
  Eigen::Isometry3d nan_pose = Eigen::Isometry3d::Identity();
  nan_pose.translation().y() = kNaN;
  EXPECT_THAT(
      g->AddRelativePoseFactor(1, 2, nan_pose, cov, FactorKind::kRegistration).status().message(),
      HasSubstr("NaN or Inf"));
  EXPECT_EQ(g->SetPose(2, nan_pose).code(), StatusCode::kInvalidArgument);
  MotionPrediction bad_prediction;
  bad_prediction.covariance = cov;
  bad_prediction.covariance(0, 0) = kNaN;
  EXPECT_EQ(g->AddRelativePoseFactor(1, 2, Eigen::Isometry3d::Identity(), cov,
                                     FactorKind::kRegistration, RobustLoss(), bad_prediction)
                .status()
                .code(),
            StatusCode::kInvalidArgument);
  // Covariance of a state that no factor constrains: a value or a Status, never a Ceres CHECK.
  auto unconstrained = g->PoseCovariance(2);
  if (unconstrained.ok()) EXPECT_TRUE(unconstrained->allFinite());

  auto sg = SubmapGraph::Create();
  ASSERT_TRUE(sg.ok());
  ASSERT_TRUE(sg->AddSubmap(0, Eigen::Isometry3d::Identity()).ok());
  EXPECT_EQ(sg->AddScan(0, 7, Timestamp::FromNanoseconds(1), nan_pose).code(),
            StatusCode::kInvalidArgument);
  Matrix6d nan_cov = cov;
  nan_cov(3, 4) = nan_cov(4, 3) = kNaN;
  EXPECT_EQ(sg->AddPosePrior(0, Eigen::Isometry3d::Identity(), nan_cov).code(),
            StatusCode::kInvalidArgument);
  Eigen::Matrix3d not_pd = Eigen::Matrix3d::Identity();
  not_pd(2, 2) = -1.0;
  EXPECT_THAT(sg->AddGnssPrior(0, Eigen::Vector3d::Zero(), not_pd).message(),
              HasSubstr("not positive definite"));
}

TEST(BackendInputValidationTest, NanFactorMakesTheSolveFailAndRestoresTheEstimate) {
  auto g = SlidingWindowGraph::Create();
  ASSERT_TRUE(g.ok());
  Eigen::Isometry3d T1 = Eigen::Isometry3d::Identity();
  T1.translation() = Eigen::Vector3d(1.0, 2.0, 3.0);
  StateInit init;
  init.T_frame_body = T1;
  ASSERT_TRUE(g->AddState(1, init).ok());
  ASSERT_TRUE(g->AddPosePrior(1, Eigen::Isometry3d::Identity(), DiagonalCovariance(0.1, 1.0)).ok());
  ASSERT_TRUE(g->AddCostFunction(std::make_unique<NanResidual>(), {{1, StateBlock::kPose}}).ok());
  auto summary = g->Solve();
  ASSERT_TRUE(summary.ok()) << summary.status().ToString();
  EXPECT_EQ(summary->termination, SolveTermination::kFailure) << summary->message;
  EXPECT_FALSE(summary->usable());
  auto pose = g->Pose(1);
  ASSERT_TRUE(pose.ok());
  EXPECT_TRUE(pose->isApprox(T1)) << "the estimate before the solve is kept";
  EXPECT_TRUE(pose->matrix().allFinite());
}

}  // namespace
}  // namespace slam_mms
