#include "surfel/parallel_range_image.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

namespace slam_mms::internal {
namespace {

// A scan-like cloud: a ground plane, a wall and scattered points, with NaNs, points out of range
// and exact duplicates (ties for a pixel, which the earlier point must win).
PointCloud MakeCloud(int n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  PointCloud cloud;
  for (int i = 0; i < n; ++i) {
    const float a = 3.14159f * u(rng);
    const float r = 3.0f + 40.0f * (0.5f + 0.5f * u(rng));
    Eigen::Vector3f p(r * std::cos(a), r * std::sin(a), -1.7f + 0.02f * u(rng));
    if (i % 3 == 0) p = Eigen::Vector3f(8.0f + 0.01f * u(rng), 10.0f * u(rng), 3.0f * u(rng));
    if (i % 97 == 0) p.x() = NAN;
    if (i % 101 == 0) p *= 50.0f;  // beyond max range
    cloud.Add(p, static_cast<float>(i % 13));
    if (i % 7 == 0) cloud.Add(p, 1.0f);  // the same point again: same pixel, same range
  }
  return cloud;
}

bool SameBits(const VertexNormalMap& a, const VertexNormalMap& b) {
  const size_t n = a.range.size();
  return a.rows == b.rows && a.cols == b.cols && n == b.range.size() &&
         std::memcmp(a.range.data(), b.range.data(), n * sizeof(float)) == 0 &&
         std::memcmp(a.vertex.data(), b.vertex.data(), n * sizeof(Eigen::Vector3f)) == 0 &&
         std::memcmp(a.normal.data(), b.normal.data(), n * sizeof(Eigen::Vector3f)) == 0 &&
         std::memcmp(a.index.data(), b.index.data(), n * sizeof(int32_t)) == 0;
}

TEST(ParallelRangeImageTest, SameBitsAsTheSerialProjectionForAnyThreadCount) {
  RangeProjectionOptions o;
  o.cols = 1024;
  const RangeProjection proj = *RangeProjection::Create(o);
  for (uint32_t seed : {1u, 2u}) {
    const PointCloud cloud = MakeCloud(150000, seed);
    VertexNormalMap serial;
    proj.ComputeVertexNormalMap(cloud, &serial);
    int pixels = 0, normals = 0;
    for (size_t i = 0; i < serial.range.size(); ++i) {
      pixels += serial.HasVertex(static_cast<int>(i));
      normals += serial.HasNormal(static_cast<int>(i));
    }
    ASSERT_GT(pixels, 20000);
    ASSERT_GT(normals, 10000);
    for (int threads : {1, 2, 3}) {
      ParallelRangeImage image(threads);
      VertexNormalMap out;
      image.ComputeVertexNormalMap(proj, cloud.View(), &out);
      EXPECT_TRUE(SameBits(serial, out)) << "seed " << seed << ", " << threads << " threads";
      // Reused: a smaller cloud leaves nothing of the first behind.
      const PointCloud small = MakeCloud(5000, seed + 10);
      VertexNormalMap serial_small;
      proj.ComputeVertexNormalMap(small, &serial_small);
      image.ComputeVertexNormalMap(proj, small.View(), &out);
      EXPECT_TRUE(SameBits(serial_small, out)) << "reused, " << threads << " threads";
    }
  }
}

TEST(ParallelRangeImageTest, NormalRowsSplitAnywayGiveTheWholeImage) {
  const RangeProjection proj;
  const PointCloud cloud = MakeCloud(100000, 3);
  VertexNormalMap whole;
  proj.ComputeVertexNormalMap(cloud, &whole);
  VertexNormalMap split;
  proj.ComputeVertexMap(cloud, &split);
  proj.ComputeNormals(&split, 40, 64);
  proj.ComputeNormals(&split, -5, 17);  // clamped to [0, 17)
  proj.ComputeNormals(&split, 17, 40);
  proj.ComputeNormals(&split, 70, 90);  // outside the image: nothing
  EXPECT_TRUE(SameBits(whole, split));
}

}  // namespace
}  // namespace slam_mms::internal
