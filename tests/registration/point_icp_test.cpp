#include "registration/point_icp.hpp"

#include <gtest/gtest.h>

#include <random>

#include "registration/point_to_plane.hpp"
#include "registration/synthetic_scene.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms {
namespace {

using registration_internal::PointToPlaneResidual;
using testing::MakeStreetScene;
using testing::MakeTunnelScene;
using testing::SimulateScan;

double TranslationError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.inverse() * b).translation().norm();
}
double RotationErrorDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return RotationAngle((a.inverse() * b).linear()) * 180.0 / M_PI;
}

// Offsets of 1 m and 5 deg along a seeded random direction / axis.
Eigen::Isometry3d Offset(std::mt19937& rng, double trans_m, double rot_deg) {
  std::normal_distribution<double> g(0.0, 1.0);
  Vector6d xi;
  const Eigen::Vector3d w = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  const Eigen::Vector3d v = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  xi << rot_deg * M_PI / 180.0 * w, trans_m * v;
  return se3::Exp(xi);
}

TEST(PointToPlaneTest, FloatJacobianOfTheProjectiveHotLoopMatchesDouble) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Vector6d xi;
    for (int i = 0; i < 6; ++i) xi[i] = u(rng);
    const Eigen::Isometry3d T = se3::Exp(xi);
    const Eigen::Vector3d p(30 * u(rng), 30 * u(rng), 3 * u(rng));
    const Eigen::Vector3d q = T * p + Eigen::Vector3d(u(rng), u(rng), u(rng));
    const Eigen::Vector3d n = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    Vector6d Jd;
    Eigen::Matrix<float, 6, 1> Jf;
    const double rd = PointToPlaneResidual<double>(T.linear(), T.translation(), p, q, n, &Jd);
    const float rf =
        PointToPlaneResidual<float>(T.linear().cast<float>(), T.translation().cast<float>(),
                                    p.cast<float>(), q.cast<float>(), n.cast<float>(), &Jf);
    EXPECT_NEAR(rf, rd, 1e-4);
    EXPECT_LT((Jf.cast<double>() - Jd).norm(), 1e-4 * (1.0 + Jd.norm()));
  }
}

TEST(PointToPlaneTest, JacobianMatchesNumericDifferentiation) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Vector6d xi;
    for (int i = 0; i < 6; ++i) xi[i] = 2.0 * u(rng);
    const Eigen::Isometry3d T = se3::Exp(xi);
    const Eigen::Vector3d p(10 * u(rng), 10 * u(rng), 3 * u(rng));
    const Eigen::Vector3d q(10 * u(rng), 10 * u(rng), 3 * u(rng));
    const Eigen::Vector3d n = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    Vector6d J;
    PointToPlaneResidual<double>(T.linear(), T.translation(), p, q, n, &J);
    const double h = 1e-6;
    for (int k = 0; k < 6; ++k) {
      Vector6d d = Vector6d::Zero();
      d[k] = h;
      const Eigen::Isometry3d Tp = T * se3::Exp(d), Tm = T * se3::Exp(-d);
      const double rp =
          PointToPlaneResidual<double>(Tp.linear(), Tp.translation(), p, q, n, nullptr);
      const double rm =
          PointToPlaneResidual<double>(Tm.linear(), Tm.translation(), p, q, n, nullptr);
      EXPECT_NEAR(J[k], (rp - rm) / (2 * h), 1e-6) << "trial " << trial << " k " << k;
    }
  }
}

TEST(PointIcpTest, OptionsValidateNamesFieldAndRule) {
  PointIcp::Options o;
  EXPECT_TRUE(o.Validate().ok());
  o.max_iterations = 0;
  const Status s = o.Validate();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("PointIcp::Options::max_iterations"), std::string::npos);
  EXPECT_FALSE(PointIcp::Create(o).ok());
}

TEST(PointIcpTest, ErrorsWithoutTargetOrSource) {
  PointIcp icp;
  PointCloud src;
  src.Add({1, 2, 3});
  EXPECT_EQ(icp.Align(src.View(), Eigen::Isometry3d::Identity()).status().code(),
            StatusCode::kFailedPrecondition);
  ASSERT_TRUE(icp.SetTarget(src.View()).code() == StatusCode::kInvalidArgument);  // too few
}

TEST(PointIcpTest, NormalsOfAPlaneArePerpendicularToIt) {
  PointCloud plane;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-5.0f, 5.0f);
  for (int i = 0; i < 2000; ++i) plane.Add({u(rng), u(rng), 0.5f * u(rng) + 2.0f});
  // Tilt: z = 2 + 0.5 x' means points (x, y, 2 + 0.5 x) ... make a real plane z = 0.2 x + 1.
  for (auto& p : plane.points()) p.z() = 0.2f * p.x() + 1.0f;
  PointIcp icp;
  ASSERT_TRUE(icp.SetTarget(plane.View()).ok());
  const Eigen::Vector3f n_true = Eigen::Vector3f(-0.2f, 0.0f, 1.0f).normalized();
  for (const auto& n : icp.target_normals()) {
    ASSERT_GT(n.norm(), 0.5f);
    EXPECT_GT(std::abs(n.dot(n_true)), 0.9999f);
  }
}

class PointIcpSceneTest : public ::testing::Test {
 protected:
  void SetUp() override {
    RangeProjectionOptions po;
    po.cols = 1024;  // fast tests; the benchmark uses 2048
    proj_ = RangeProjection::Create(po).value();
  }
  RangeProjection proj_;
};

TEST_F(PointIcpSceneTest, ConvergesFromOneMetreFiveDegreeOffsets) {
  const testing::Scene scene = MakeStreetScene();
  const Eigen::Isometry3d T_world_a = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_world_b =
      MakeIsometry(FromRollPitchYaw(0.01, -0.02, 0.05), Eigen::Vector3d(1.2, 0.3, 0.05));
  const PointCloud target = SimulateScan(scene, proj_, T_world_a, 0.01, 1);
  const PointCloud source = SimulateScan(scene, proj_, T_world_b, 0.01, 2);
  const Eigen::Isometry3d T_true = T_world_a.inverse() * T_world_b;

  PointIcp::Options o;
  o.source_voxel_size = 0.3;
  auto icp = PointIcp::Create(o).value();
  ASSERT_TRUE(icp.SetTarget(target.View()).ok());
  std::mt19937 rng(11);
  for (int trial = 0; trial < 6; ++trial) {
    const Eigen::Isometry3d init = T_true * Offset(rng, 1.0, 5.0);
    auto r = icp.Align(source.View(), init);
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    EXPECT_EQ(r->termination, IcpTermination::kConverged) << IcpTerminationName(r->termination);
    EXPECT_LT(TranslationError(r->T_target_source, T_true), 0.02) << "trial " << trial;
    EXPECT_LT(RotationErrorDeg(r->T_target_source, T_true), 0.1) << "trial " << trial;
    EXPECT_GT(r->inlier_ratio, 0.7);
    EXPECT_LT(r->rms_residual_m, 0.05);  // 1 cm range noise + corner points
    EXPECT_FALSE(r->degeneracy.degenerate);
    // Covariance: symmetric positive definite, small for a well-constrained scene.
    EXPECT_TRUE(r->covariance.isApprox(r->covariance.transpose(), 1e-9));
    EXPECT_GT(r->covariance.diagonal().minCoeff(), 0.0);
    EXPECT_LT(std::sqrt(r->covariance.diagonal().tail<3>().maxCoeff()), 0.01);
  }
}

TEST_F(PointIcpSceneTest, TunnelIsDegenerateAlongItsAxis) {
  const testing::Scene scene = MakeTunnelScene();
  const Eigen::Isometry3d T_world_b =
      MakeIsometry(FromRollPitchYaw(0.0, 0.0, 0.02), Eigen::Vector3d(1.0, 0.2, 0.0));
  const PointCloud target = SimulateScan(scene, proj_, Eigen::Isometry3d::Identity(), 0.01, 3);
  const PointCloud source = SimulateScan(scene, proj_, T_world_b, 0.01, 4);
  PointIcp::Options o;
  o.source_voxel_size = 0.3;
  auto icp = PointIcp::Create(o).value();
  ASSERT_TRUE(icp.SetTarget(target.View()).ok());
  auto r = icp.Align(source.View(), T_world_b);
  ASSERT_TRUE(r.ok());
  const DegeneracyAnalysis& d = r->degeneracy;
  EXPECT_TRUE(d.degenerate);
  EXPECT_TRUE(d.degenerate_axis[3]) << "v_x information " << d.axis_information[3];
  for (int k : {0, 1, 2, 4, 5}) {
    EXPECT_FALSE(d.degenerate_axis[static_cast<size_t>(k)])
        << "axis " << k << " information " << d.axis_information[k];
  }
  // The weakest direction is translation along the corridor (x of the source frame ~ world x).
  EXPECT_TRUE(d.degenerate_direction[0]);
  EXPECT_FALSE(d.degenerate_direction[1]);
  EXPECT_GT(std::abs(d.eigenvectors(3, 0)), 0.99);
  // The unobservable direction keeps the initial guess and gets a huge variance.
  EXPECT_GT(r->covariance(3, 3), 10.0 * r->covariance(5, 5));
  // The observable part is right.
  const Eigen::Isometry3d err = T_world_b.inverse() * r->T_target_source;
  EXPECT_LT(std::abs(err.translation().y()), 0.01);
  EXPECT_LT(std::abs(err.translation().z()), 0.01);
}

TEST_F(PointIcpSceneTest, StreetIsNotDegenerate) {
  const testing::Scene scene = MakeStreetScene();
  const PointCloud cloud = SimulateScan(scene, proj_, Eigen::Isometry3d::Identity(), 0.0, 5);
  PointIcp::Options o;
  o.source_voxel_size = 0.3;
  auto icp = PointIcp::Create(o).value();
  ASSERT_TRUE(icp.SetTarget(cloud.View()).ok());
  auto r = icp.Align(cloud.View(), Eigen::Isometry3d::Identity());
  ASSERT_TRUE(r.ok());
  EXPECT_FALSE(r->degeneracy.degenerate);
  for (int k = 0; k < 6; ++k) EXPECT_GT(r->degeneracy.axis_information[k], 0.01) << k;
}

TEST(PointIcpTest, TooFewCorrespondencesIsReported) {
  PointCloud target, source;
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-5.0f, 5.0f);
  for (int i = 0; i < 500; ++i) target.Add({u(rng), u(rng), 0.0f});
  for (int i = 0; i < 500; ++i) source.Add({u(rng), u(rng), 50.0f});  // far away
  PointIcp icp;
  ASSERT_TRUE(icp.SetTarget(target.View()).ok());
  auto r = icp.Align(source.View(), Eigen::Isometry3d::Identity());
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->termination, IcpTermination::kTooFewCorrespondences);
  EXPECT_FALSE(r->IsUsable());
}

}  // namespace
}  // namespace slam_mms
