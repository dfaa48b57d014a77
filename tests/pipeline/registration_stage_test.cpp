// RegistrationStage (step 4 of Localizer::ProcessScan) on the synthetic street of
// tests/registration/synthetic_scene.hpp: the scan's body pose in the submap from the ICP result
// through the extrinsic and the submap pose, the covariance law (scale, Ad(T_body_lidar), floor,
// symmetry), and the cases that register nothing (a submap reference, no model, an inlier ratio
// below the minimum).
#include "pipeline/registration_stage.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "registration/synthetic_scene.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms::internal {
namespace {

Eigen::Isometry3d BodyLidar() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translate(Eigen::Vector3d(0.3, -0.1, 1.2));
  T.rotate(Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitZ()));
  T.rotate(Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitY()));
  return T;
}

class RegistrationStageTest : public ::testing::Test {
 protected:
  void SetUp() override {
    RangeProjectionOptions po;
    po.cols = 1024;
    proj_ = RangeProjection::Create(po).value();
    options_.num_threads = 1;
    options_.dynamic.enabled = false;
    // The submap frame somewhere in the world; the LiDAR truly at T_world_lidar_true, predicted
    // at the identity (1.2 m, 3 deg off), where the model is rendered.
    T_world_submap_ = MakeIsometry(FromRollPitchYaw(0.0, 0.0, 0.1), Eigen::Vector3d(-3, 1, -1.2));
    T_world_lidar_true_ =
        MakeIsometry(FromRollPitchYaw(0.01, -0.02, 0.05), Eigen::Vector3d(1.2, 0.3, 0.05));
    const testing::Scene scene = testing::MakeStreetScene();
    model_ = testing::RenderModel(scene, proj_, Eigen::Isometry3d::Identity());
    scan_.cloud = testing::SimulateScan(scene, proj_, T_world_lidar_true_, 0.01, 7);
    proj_.ComputeVertexNormalMap(scan_.cloud, &scan_.vnm);
  }

  /// The step of a scan predicted with the LiDAR at the identity (world).
  ScanStep Step() const {
    ScanStep step;
    step.T_world_submap = T_world_submap_;
    step.T_world_lidar_pred = Eigen::Isometry3d::Identity();
    step.pred.T_submap =
        T_world_submap_.inverse() * step.T_world_lidar_pred * BodyLidar().inverse();
    step.pred.factor = MotionFactorType::kConstantVelocity;
    step.have_model = true;
    return step;
  }

  /// Runs a stage with `options` on a copy of the scan.
  ScanStep Run(const Localizer::Options& options, ScanStep step, LocalizationResult* res) {
    auto stage = RegistrationStage::Create(options, proj_, BodyLidar());
    EXPECT_TRUE(stage.ok()) << stage.status().ToString();
    DeskewedScan scan = scan_;
    Scan raw;
    raw.index = 5;
    EXPECT_TRUE(stage->Register(raw, model_, &scan, &map_, &step, res).ok());
    return step;
  }

  RangeProjection proj_;
  Localizer::Options options_;
  Eigen::Isometry3d T_world_submap_, T_world_lidar_true_;
  VertexNormalMap model_;
  DeskewedScan scan_;
  SurfelMap map_;
};

TEST_F(RegistrationStageTest, TheResultIsTheBodyPoseInTheSubmap) {
  LocalizationResult res;
  const ScanStep step = Run(options_, Step(), &res);
  EXPECT_TRUE(res.registered);
  EXPECT_GT(res.inlier_ratio, 0.8);
  EXPECT_GT(res.num_inliers, 0);
  ASSERT_TRUE(step.T_submap_reg.has_value());
  const Eigen::Isometry3d T_submap_body_true =
      T_world_submap_.inverse() * T_world_lidar_true_ * BodyLidar().inverse();
  const Eigen::Isometry3d err = T_submap_body_true.inverse() * *step.T_submap_reg;
  EXPECT_LT(err.translation().norm(), 0.01);
  EXPECT_LT(RotationAngle(err.linear()) * 180.0 / M_PI, 0.05);
}

TEST_F(RegistrationStageTest, TheCovarianceIsTheScaledIcpCovarianceInTheBodyFramePlusTheFloor) {
  LocalizationResult res;
  const ScanStep step = Run(options_, Step(), &res);
  ASSERT_TRUE(step.T_submap_reg.has_value());
  // The oracle: the ICP on its own (deterministic), its covariance carried from the LiDAR to the
  // body by Ad(T_body_lidar), scaled, plus the floor.
  ProjectiveIcp::Options icp_options;
  static_cast<ProjectiveIcpOptions&>(icp_options) = options_.icp;
  icp_options.num_threads = 1;
  auto icp = ProjectiveIcp::Create(proj_, icp_options).value();
  auto r = icp.Align(scan_.vnm, model_, Eigen::Isometry3d::Identity());
  ASSERT_TRUE(r.ok());
  const Matrix6d Ad = se3::Adjoint(BodyLidar());
  Vector6d floor;
  floor << Eigen::Vector3d::Constant(std::pow(options_.reg_sigma_floor_rot_rad, 2)),
      Eigen::Vector3d::Constant(std::pow(options_.reg_sigma_floor_trans_m, 2));
  Matrix6d expected = options_.reg_cov_scale * (Ad * r->covariance * Ad.transpose());
  expected.diagonal() += floor;
  EXPECT_TRUE(step.cov_reg.isApprox(expected, 1e-12));
  EXPECT_EQ(step.cov_reg, step.cov_reg.transpose());
  EXPECT_TRUE(((step.cov_reg.diagonal() - floor).array() > 0.0).all());
  EXPECT_EQ(res.num_inliers, r->num_inliers);
  EXPECT_EQ(res.icp_iterations, r->iterations);
}

TEST_F(RegistrationStageTest, NothingIsRegisteredForAReferenceOrWithoutAModel) {
  ScanStep reference = Step();
  reference.is_reference = true;
  LocalizationResult res;
  EXPECT_FALSE(Run(options_, reference, &res).T_submap_reg.has_value());
  EXPECT_FALSE(res.registered);
  ScanStep no_model = Step();
  no_model.have_model = false;
  res = LocalizationResult();
  EXPECT_FALSE(Run(options_, no_model, &res).T_submap_reg.has_value());
  EXPECT_FALSE(res.registered);
}

TEST_F(RegistrationStageTest, AnInlierRatioBelowTheMinimumIsNotUsed) {
  Localizer::Options strict = options_;
  strict.min_inlier_ratio = 1.0;
  LocalizationResult res;
  const ScanStep step = Run(strict, Step(), &res);
  EXPECT_TRUE(res.registered);  // aligned and reported...
  ASSERT_LT(res.inlier_ratio, 1.0);
  EXPECT_FALSE(step.T_submap_reg.has_value());  // ...but not used
}

}  // namespace
}  // namespace slam_mms::internal
