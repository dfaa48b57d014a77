#include "slam_mms/surfel/range_projection.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

namespace slam_mms {
namespace {

TEST(RangeProjectionTest, ValidateNamesFieldAndRule) {
  RangeProjectionOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.rows = 0;
  Status s = o.Validate();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("RangeProjectionOptions::rows = 0; must be > 0"), std::string::npos);
  o = RangeProjectionOptions();
  o.fov_down_deg = 5.0;
  EXPECT_FALSE(RangeProjection::Create(o).ok());
  o = RangeProjectionOptions();
  o.max_range_m = 1.0;
  EXPECT_FALSE(o.Validate().ok());
}

TEST(RangeProjectionTest, ProjectUnprojectRoundTrip) {
  const RangeProjection proj;
  std::mt19937 rng(42);
  std::uniform_real_distribution<float> yaw(-3.14159f, 3.14159f);
  std::uniform_real_distribution<float> pitch(-24.9f * 3.14159f / 180.f, 2.9f * 3.14159f / 180.f);
  std::uniform_real_distribution<float> range(2.5f, 90.0f);
  for (int i = 0; i < 2000; ++i) {
    const float y = yaw(rng), p = pitch(rng), r = range(rng);
    const Eigen::Vector3f pt(r * std::cos(p) * std::cos(y), r * std::cos(p) * std::sin(y),
                             r * std::sin(p));
    ProjectedPoint px;
    ASSERT_TRUE(proj.Project(pt, &px)) << pt.transpose();
    EXPECT_GE(px.col, 0);
    EXPECT_LT(px.col, proj.cols());
    EXPECT_GE(px.row, 0);
    EXPECT_LT(px.row, proj.rows());
    EXPECT_NEAR(px.range, r, 1e-4f * r);
    const Eigen::Vector3f back = proj.Unproject(px.u, px.v, px.range);
    EXPECT_LT((back - pt).norm(), 2e-5f * r + 1e-5f) << pt.transpose();
    // The pixel-centre ray is within half a pixel of the point's direction.
    const Eigen::Vector3f d = proj.RayDirection(px.row, px.col);
    EXPECT_NEAR(d.norm(), 1.0f, 1e-5f);
    const float ang = std::acos(std::clamp(d.dot(pt.normalized()), -1.0f, 1.0f));
    const float half_diag =
        0.5f * std::hypot(2.0f * 3.14159f / proj.cols(), 28.0f * 3.14159f / 180.0f / proj.rows());
    EXPECT_LE(ang, half_diag * 1.01f);
  }
}

TEST(RangeProjectionTest, ConventionsAndGates) {
  const RangeProjection proj;
  ProjectedPoint px;
  // Straight ahead at the horizon: column cols/2, row fov_up / fov * rows.
  ASSERT_TRUE(proj.Project({10.f, 0.f, 0.f}, &px));
  EXPECT_NEAR(px.u, 1024.0f, 1e-3f);
  EXPECT_NEAR(px.v, 3.0f / 28.0f * 64.0f, 1e-3f);
  // Left (+y) lands at smaller columns, right at larger.
  ASSERT_TRUE(proj.Project({0.f, 10.f, 0.f}, &px));
  EXPECT_NEAR(px.u, 512.0f, 1e-3f);
  ASSERT_TRUE(proj.Project({0.f, -10.f, 0.f}, &px));
  EXPECT_NEAR(px.u, 1536.0f, 1e-3f);
  // Up is row 0 side.
  ASSERT_TRUE(proj.Project({10.f, 0.f, -3.f}, &px));
  EXPECT_GT(px.v, 3.0f / 28.0f * 64.0f);
  // Gates: too near, too far, above and below the FOV.
  EXPECT_FALSE(proj.Project({1.f, 0.f, 0.f}, &px));
  EXPECT_FALSE(proj.Project({150.f, 0.f, 0.f}, &px));
  EXPECT_FALSE(proj.Project({10.f, 0.f, 1.f}, &px));
  EXPECT_FALSE(proj.Project({10.f, 0.f, -6.f}, &px));
  EXPECT_FALSE(proj.Project({NAN, 0.f, 0.f}, &px));
}

// A scan of the plane z = -1.73 (the ground under a KITTI car) plus a wall x = 20.
PointCloud SyntheticScan(const RangeProjection& proj) {
  PointCloud cloud;
  for (int r = 0; r < proj.rows(); ++r) {
    for (int c = 0; c < proj.cols(); ++c) {
      const Eigen::Vector3f d = proj.RayDirection(r, c);
      float t = std::numeric_limits<float>::infinity();
      if (d.z() < -1e-3f) t = -1.73f / d.z();
      if (d.x() > 1e-3f) t = std::min(t, 20.0f / d.x());
      if (t < 90.0f) cloud.Add(t * d);
    }
  }
  return cloud;
}

TEST(RangeProjectionTest, VertexAndNormalMapsOfPlanes) {
  const RangeProjection proj;
  const PointCloud cloud = SyntheticScan(proj);
  VertexNormalMap map;
  proj.ComputeVertexNormalMap(cloud, &map);
  ASSERT_EQ(map.rows, 64);
  ASSERT_EQ(map.cols, 2048);
  EXPECT_EQ(map.CountVertices(), static_cast<int>(cloud.size()));
  int checked = 0;
  for (int i = 0; i < map.size(); ++i) {
    if (!map.HasVertex(i)) {
      EXPECT_EQ(map.index[i], -1);
      continue;
    }
    const Eigen::Vector3f& v = map.vertex[i];
    EXPECT_EQ(cloud.points()[map.index[i]], v);
    EXPECT_NEAR(map.range[i], v.norm(), 1e-4f);
    if (!map.HasNormal(i)) continue;
    const Eigen::Vector3f& n = map.normal[i];
    EXPECT_NEAR(n.norm(), 1.0f, 1e-4f);
    EXPECT_LT(n.dot(v), 0.0f);
    // Away from the ground/wall edge the normal is the plane's.
    if (std::abs(v.z() + 1.73f) < 1e-3f && v.x() < 17.0f) {
      EXPECT_GT(n.z(), 0.999f) << v.transpose();
      ++checked;
    } else if (std::abs(v.x() - 20.0f) < 1e-3f && v.z() > -1.0f && std::abs(v.y()) < 40.0f) {
      EXPECT_LT(n.x(), -0.999f) << v.transpose();
      ++checked;
    }
  }
  EXPECT_GT(checked, 60000);
  // Nearly all vertices get a normal.
  EXPECT_GT(map.CountNormals(), map.CountVertices() * 95 / 100);
}

TEST(RangeProjectionTest, NearestPointWinsAndDiscontinuityHasNoNormal) {
  const RangeProjection proj;
  PointCloud cloud;
  cloud.Add({30.f, 0.f, 0.f});
  cloud.Add({10.f, 0.f, 0.f});
  cloud.Add({20.f, 0.f, 0.f});
  VertexNormalMap map;
  proj.ComputeVertexNormalMap(cloud, &map);
  ASSERT_EQ(map.CountVertices(), 1);
  ProjectedPoint px;
  ASSERT_TRUE(proj.Project({10.f, 0.f, 0.f}, &px));
  const int k = map.PixelIndex(px.row, px.col);
  EXPECT_EQ(map.index[k], 1);
  EXPECT_FLOAT_EQ(map.range[k], 10.f);
  EXPECT_FALSE(map.HasNormal(k));  // no neighbours
}

}  // namespace
}  // namespace slam_mms
