#include "registration/projective_icp.hpp"

#include <gtest/gtest.h>

#include <random>

#include "registration/point_icp.hpp"
#include "registration/synthetic_scene.hpp"
#include "slam_mms/core/lie.hpp"
#include "surfel/cpu_surfel_renderer.hpp"

namespace slam_mms {
namespace {

using testing::MakeStreetScene;
using testing::MakeTunnelScene;
using testing::RenderModel;
using testing::SimulateScan;

double TranslationError(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return (a.inverse() * b).translation().norm();
}
double RotationErrorDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return RotationAngle((a.inverse() * b).linear()) * 180.0 / M_PI;
}
Eigen::Isometry3d Offset(std::mt19937& rng, double trans_m, double rot_deg) {
  std::normal_distribution<double> g(0.0, 1.0);
  Vector6d xi;
  const Eigen::Vector3d w = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  const Eigen::Vector3d v = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  xi << rot_deg * M_PI / 180.0 * w, trans_m * v;
  return se3::Exp(xi);
}

class ProjectiveIcpTest : public ::testing::Test {
 protected:
  void SetUp() override {
    RangeProjectionOptions po;
    po.cols = 1024;  // fast tests; the benchmark uses 64 x 2048
    proj_ = RangeProjection::Create(po).value();
  }
  VertexNormalMap ScanMap(const PointCloud& cloud) const {
    VertexNormalMap m;
    proj_.ComputeVertexNormalMap(cloud, &m);
    return m;
  }
  RangeProjection proj_;
};

TEST_F(ProjectiveIcpTest, OptionsAndInputsAreValidated) {
  ProjectiveIcp::Options o;
  EXPECT_TRUE(o.Validate().ok());
  o.max_angle_deg = 0.0;
  EXPECT_NE(o.Validate().message().find("ProjectiveIcp::Options::max_angle_deg"),
            std::string::npos);
  EXPECT_FALSE(ProjectiveIcp::Create(proj_, o).ok());
  auto icp = ProjectiveIcp::Create(proj_, ProjectiveIcp::Options()).value();
  VertexNormalMap wrong;
  wrong.Reset(32, 512);
  VertexNormalMap scan;
  scan.Reset(64, 1024);
  EXPECT_EQ(icp.Align(scan, wrong, Eigen::Isometry3d::Identity()).status().code(),
            StatusCode::kInvalidArgument);
}

TEST_F(ProjectiveIcpTest, EmptyModelGivesTooFewCorrespondences) {
  const PointCloud cloud =
      SimulateScan(MakeStreetScene(), proj_, Eigen::Isometry3d::Identity(), 0.0, 1);
  VertexNormalMap model;
  model.Reset(proj_.rows(), proj_.cols());
  auto icp = ProjectiveIcp::Create(proj_, ProjectiveIcp::Options()).value();
  auto r = icp.Align(ScanMap(cloud), model, Eigen::Isometry3d::Identity());
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->termination, IcpTermination::kTooFewCorrespondences);
  EXPECT_FALSE(r->IsUsable());
}

TEST_F(ProjectiveIcpTest, ConvergesFromOneMetreFiveDegreeOffsets) {
  const testing::Scene scene = MakeStreetScene();
  const Eigen::Isometry3d T_world_model = Eigen::Isometry3d::Identity();
  const Eigen::Isometry3d T_world_scan =
      MakeIsometry(FromRollPitchYaw(0.01, -0.02, 0.05), Eigen::Vector3d(1.2, 0.3, 0.05));
  const VertexNormalMap model = RenderModel(scene, proj_, T_world_model);
  const VertexNormalMap scan = ScanMap(SimulateScan(scene, proj_, T_world_scan, 0.01, 2));
  const Eigen::Isometry3d T_true = T_world_model.inverse() * T_world_scan;

  auto icp = ProjectiveIcp::Create(proj_, ProjectiveIcp::Options()).value();
  std::mt19937 rng(11);
  for (int trial = 0; trial < 6; ++trial) {
    const Eigen::Isometry3d init = T_true * Offset(rng, 1.0, 5.0);
    auto r = icp.Align(scan, model, init);
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    EXPECT_EQ(r->termination, IcpTermination::kConverged) << IcpTerminationName(r->termination);
    EXPECT_LT(TranslationError(r->T_target_source, T_true), 0.01) << "trial " << trial;
    EXPECT_LT(RotationErrorDeg(r->T_target_source, T_true), 0.05) << "trial " << trial;
    EXPECT_GT(r->inlier_ratio, 0.8);
    EXPECT_LT(r->rms_residual_m, 0.05);
    EXPECT_FALSE(r->degeneracy.degenerate);
    EXPECT_TRUE(r->covariance.isApprox(r->covariance.transpose(), 1e-9));
    EXPECT_GT(r->covariance.diagonal().minCoeff(), 0.0);
  }
}

TEST_F(ProjectiveIcpTest, SingleThreadGivesTheSameResult) {
  const testing::Scene scene = MakeStreetScene();
  const Eigen::Isometry3d T_world_scan =
      MakeIsometry(FromRollPitchYaw(0.0, 0.0, 0.03), Eigen::Vector3d(0.8, -0.2, 0.0));
  const VertexNormalMap model = RenderModel(scene, proj_, Eigen::Isometry3d::Identity());
  const VertexNormalMap scan = ScanMap(SimulateScan(scene, proj_, T_world_scan, 0.01, 3));
  ProjectiveIcp::Options o1;
  o1.num_threads = 1;
  auto a =
      ProjectiveIcp::Create(proj_, o1).value().Align(scan, model, Eigen::Isometry3d::Identity());
  auto b = ProjectiveIcp::Create(proj_, ProjectiveIcp::Options())
               .value()
               .Align(scan, model, Eigen::Isometry3d::Identity());
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->num_inliers, b->num_inliers);
  EXPECT_LT(TranslationError(a->T_target_source, b->T_target_source), 1e-6);
}

TEST_F(ProjectiveIcpTest, TunnelIsDegenerateAlongItsAxis) {
  const testing::Scene scene = MakeTunnelScene();
  const Eigen::Isometry3d T_world_scan =
      MakeIsometry(FromRollPitchYaw(0.0, 0.0, 0.02), Eigen::Vector3d(1.0, 0.2, 0.0));
  const VertexNormalMap model = RenderModel(scene, proj_, Eigen::Isometry3d::Identity());
  const VertexNormalMap scan = ScanMap(SimulateScan(scene, proj_, T_world_scan, 0.01, 4));
  auto icp = ProjectiveIcp::Create(proj_, ProjectiveIcp::Options()).value();
  // Start 0.3 m off along the axis and 0.2 m across it.
  const Eigen::Isometry3d init =
      T_world_scan * MakeIsometry(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.3, 0.2, 0.0));
  auto r = icp.Align(scan, model, init);
  ASSERT_TRUE(r.ok());
  const DegeneracyAnalysis& d = r->degeneracy;
  EXPECT_TRUE(d.degenerate);
  EXPECT_TRUE(d.degenerate_axis[3]) << "v_x information " << d.axis_information[3];
  for (int k : {0, 1, 2, 4, 5}) {
    EXPECT_FALSE(d.degenerate_axis[static_cast<size_t>(k)])
        << "axis " << k << " information " << d.axis_information[k];
  }
  EXPECT_TRUE(d.degenerate_direction[0]);
  EXPECT_FALSE(d.degenerate_direction[1]);
  EXPECT_GT(std::abs(d.eigenvectors(3, 0)), 0.99);
  EXPECT_GT(r->covariance(3, 3), 10.0 * r->covariance(5, 5));
  // Across the axis the offset is removed; along it the initial guess is kept (not drifted).
  const Eigen::Isometry3d err = T_world_scan.inverse() * r->T_target_source;
  EXPECT_LT(std::abs(err.translation().y()), 0.01);
  EXPECT_LT(std::abs(err.translation().z()), 0.01);
  EXPECT_NEAR(err.translation().x(), 0.3, 0.05);
}

// Frame-to-model as the pipeline does it: surfels made from two scans (SuMa's radius rule), the
// model rendered once at the model pose by the surfel module's CpuSurfelRenderer, then
// ProjectiveIcp.
TEST_F(ProjectiveIcpTest, RegistersAgainstCpuSurfelRendererModel) {
  const testing::Scene scene = MakeStreetScene();
  std::vector<Surfel> surfels;
  const double pixel_size =
      std::max(std::tan(0.5 * 28.0 * M_PI / 180.0 / proj_.rows()), std::tan(M_PI / proj_.cols()));
  for (int i = 0; i < 2; ++i) {
    const Eigen::Isometry3d T_world_s =
        MakeIsometry(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-1.0 * i, 0.5 * i, 0.0));
    const VertexNormalMap m = ScanMap(SimulateScan(scene, proj_, T_world_s, 0.005, 20 + i));
    for (int p = 0; p < m.size(); ++p) {
      if (!m.HasVertex(p) || !m.HasNormal(p)) continue;
      const Eigen::Vector3f v = m.vertex[static_cast<size_t>(p)];
      const Eigen::Vector3f n = m.normal[static_cast<size_t>(p)];
      const double d = v.norm();
      const double cos_inc = std::clamp(static_cast<double>(-n.dot(v)) / d, 0.5, 1.0);
      Surfel s;
      s.position = (T_world_s * v.cast<double>()).cast<float>();
      s.normal = (T_world_s.linear() * n.cast<double>()).cast<float>();
      s.radius = static_cast<float>(std::clamp(1.41 * d * pixel_size / cos_inc, 0.05, 1.0));
      surfels.push_back(s);
    }
  }
  SurfelRendererOptions ro;
  ro.projection = proj_.options();
  auto renderer = CpuSurfelRenderer::Create(ro).value();
  VertexNormalMap model;
  ASSERT_TRUE(
      renderer->Render(SurfelRenderInput::All(surfels), Eigen::Isometry3d::Identity(), &model)
          .ok());
  const Eigen::Isometry3d T_world_scan =
      MakeIsometry(FromRollPitchYaw(0.01, -0.02, 0.05), Eigen::Vector3d(1.2, 0.3, 0.05));
  const VertexNormalMap scan = ScanMap(SimulateScan(scene, proj_, T_world_scan, 0.01, 22));
  auto icp = ProjectiveIcp::Create(proj_, ProjectiveIcp::Options()).value();
  std::mt19937 rng(17);
  for (int trial = 0; trial < 3; ++trial) {
    auto r = icp.Align(scan, model, T_world_scan * Offset(rng, 1.0, 5.0));
    ASSERT_TRUE(r.ok());
    EXPECT_TRUE(r->converged()) << IcpTerminationName(r->termination);
    EXPECT_LT(TranslationError(r->T_target_source, T_world_scan), 0.02) << "trial " << trial;
    EXPECT_LT(RotationErrorDeg(r->T_target_source, T_world_scan), 0.1) << "trial " << trial;
    EXPECT_GT(r->inlier_ratio, 0.7);
  }
}

TEST_F(ProjectiveIcpTest, AgreesWithPointIcpFrameToFrame) {
  // The same problem for both: register scan B to scan A (A's vertex/normal map as the model).
  const testing::Scene scene = MakeStreetScene();
  const Eigen::Isometry3d T_world_b =
      MakeIsometry(FromRollPitchYaw(0.005, 0.01, -0.04), Eigen::Vector3d(1.1, -0.2, 0.02));
  const PointCloud cloud_a = SimulateScan(scene, proj_, Eigen::Isometry3d::Identity(), 0.01, 5);
  const PointCloud cloud_b = SimulateScan(scene, proj_, T_world_b, 0.01, 6);
  const Eigen::Isometry3d init =
      MakeIsometry(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.9, 0.0, 0.0));  // ~odometry

  auto proj_icp = ProjectiveIcp::Create(proj_, ProjectiveIcp::Options()).value();
  auto a = proj_icp.Align(ScanMap(cloud_b), ScanMap(cloud_a), init);
  PointIcp::Options po;
  po.source_voxel_size = 0.3;
  auto point_icp = PointIcp::Create(po).value();
  ASSERT_TRUE(point_icp.SetTarget(cloud_a.View()).ok());
  auto b = point_icp.Align(cloud_b.View(), init);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_TRUE(a->converged());
  EXPECT_TRUE(b->converged());
  EXPECT_LT(TranslationError(a->T_target_source, b->T_target_source), 0.02);
  EXPECT_LT(RotationErrorDeg(a->T_target_source, b->T_target_source), 0.1);
  EXPECT_LT(TranslationError(a->T_target_source, T_world_b), 0.02);
  EXPECT_LT(TranslationError(b->T_target_source, T_world_b), 0.02);
}

}  // namespace
}  // namespace slam_mms
