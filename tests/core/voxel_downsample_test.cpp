#include "slam_mms/core/voxel_downsample.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <tuple>

namespace slam_mms {
namespace {

TEST(VoxelDownsampleTest, MatchesBruteForceCentroidsAndIntensities) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-2.0f, 2.0f);
  PointCloud cloud;
  for (int i = 0; i < 20000; ++i)
    cloud.Add({u(rng), u(rng), 0.3f * u(rng)}, 0.25f * (u(rng) + 2.0f), 0.01f * i);
  const double voxel = 0.25;
  const StatusOr<PointCloud> down = VoxelDownsample(cloud, voxel);
  ASSERT_TRUE(down.ok());

  struct Acc {
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    double i = 0.0, t = 0.0;
    int n = 0;
  };
  std::map<std::tuple<long, long, long>, Acc> voxels;
  for (size_t k = 0; k < cloud.size(); ++k) {
    const Eigen::Vector3f& p = cloud.points()[k];
    const auto key = std::make_tuple(static_cast<long>(std::floor(p.x() / voxel)),
                                     static_cast<long>(std::floor(p.y() / voxel)),
                                     static_cast<long>(std::floor(p.z() / voxel)));
    Acc& a = voxels[key];
    a.p += p.cast<double>();
    a.i += cloud.intensities()[k];
    a.t += cloud.time_offsets_s()[k];
    ++a.n;
  }
  ASSERT_EQ(down->size(), voxels.size());
  size_t k = 0;
  for (const auto& [key, a] : voxels) {  // std::map order == (ix, iy, iz) order of the output
    const Eigen::Vector3f expected = (a.p / a.n).cast<float>();
    EXPECT_LT((down->points()[k] - expected).norm(), 1e-6f) << "voxel " << k;
    EXPECT_NEAR(down->intensities()[k], a.i / a.n, 1e-6);
    EXPECT_NEAR(down->time_offsets_s()[k], a.t / a.n, 1e-4);
    // The centroid lies inside its voxel.
    EXPECT_EQ(static_cast<long>(std::floor(down->points()[k].x() / voxel)), std::get<0>(key));
    ++k;
  }
}

TEST(VoxelDownsampleTest, RejectsBadVoxelSizesAndDropsNonFinitePoints) {
  PointCloud cloud;
  cloud.Add({0.01f, 0.01f, 0.01f}, 1.0f);
  cloud.Add({0.03f, 0.01f, 0.01f}, 0.0f);
  cloud.Add({std::numeric_limits<float>::infinity(), 0, 0});
  const StatusOr<PointCloud> down = VoxelDownsample(cloud, 0.1);
  ASSERT_TRUE(down.ok());
  ASSERT_EQ(down->size(), 1u);
  EXPECT_NEAR(down->points()[0].x(), 0.02f, 1e-7f);
  EXPECT_NEAR(down->intensities()[0], 0.5f, 1e-7f);
  EXPECT_FALSE(VoxelDownsample(cloud, 0.0).ok());
  EXPECT_FALSE(VoxelDownsample(cloud, -1.0).ok());
  PointCloud far;
  far.Add({1e9f, 0, 0});
  EXPECT_FALSE(VoxelDownsample(far, 1e-3).ok());
}

}  // namespace
}  // namespace slam_mms
