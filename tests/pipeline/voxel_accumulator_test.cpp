#include "pipeline/voxel_accumulator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <tuple>

namespace slam_mms::internal {
namespace {

// The open-addressing grid against a std::map reference: same voxels, centroids and intensities,
// through several growths of the table and two Add calls with a transform.
TEST(VoxelAccumulatorTest, MatchesReferenceGrid) {
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> u(-30.0f, 30.0f);
  PointCloud cloud;
  for (int i = 0; i < 300000; ++i)
    cloud.Add(Eigen::Vector3f(u(rng), u(rng), 0.1f * u(rng)), 1.0f * (i % 7));
  cloud.Add(Eigen::Vector3f(NAN, 0, 0), 1.0f);      // skipped
  cloud.Add(Eigen::Vector3f(100, 100, 100), 1.0f);  // beyond max range, skipped
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(-3.0, 2.0, 0.5);
  T.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const double voxel = 0.5;
  VoxelAccumulator acc(voxel);
  acc.Add(cloud, Eigen::Isometry3d::Identity(), 60.0);
  acc.Add(cloud, T, 60.0);

  struct Sum {
    double x = 0, y = 0, z = 0, i = 0;
    int n = 0;
  };
  std::map<std::tuple<int64_t, int64_t, int64_t>, Sum> ref;
  for (const Eigen::Isometry3d& pose : {Eigen::Isometry3d::Identity(), T}) {
    for (size_t k = 0; k < cloud.size(); ++k) {
      const Eigen::Vector3f& q = cloud.points()[k];
      if (!q.allFinite() || q.squaredNorm() > 3600.0f) continue;
      const Eigen::Vector3d p =
          (pose.linear().cast<float>() * q).cast<double>() + pose.translation();
      Sum& s = ref[{static_cast<int64_t>(std::floor(p.x() / voxel)),
                    static_cast<int64_t>(std::floor(p.y() / voxel)),
                    static_cast<int64_t>(std::floor(p.z() / voxel))}];
      s.x += p.x();
      s.y += p.y();
      s.z += p.z();
      s.i += cloud.intensities()[k];
      ++s.n;
    }
  }
  ASSERT_EQ(acc.size(), ref.size());
  const PointCloud out = acc.Cloud();
  ASSERT_EQ(out.size(), ref.size());
  std::map<std::tuple<int64_t, int64_t, int64_t>, size_t> index;
  for (size_t k = 0; k < out.size(); ++k) {
    const Eigen::Vector3f& p = out.points()[k];
    index[{static_cast<int64_t>(std::floor(p.x() / voxel)),
           static_cast<int64_t>(std::floor(p.y() / voxel)),
           static_cast<int64_t>(std::floor(p.z() / voxel))}] = k;
  }
  ASSERT_EQ(index.size(), ref.size());
  for (const auto& [key, s] : ref) {
    const auto it = index.find(key);
    ASSERT_NE(it, index.end());
    const Eigen::Vector3f& p = out.points()[it->second];
    EXPECT_NEAR(p.x(), s.x / s.n, 1e-4);
    EXPECT_NEAR(p.y(), s.y / s.n, 1e-4);
    EXPECT_NEAR(p.z(), s.z / s.n, 1e-4);
    EXPECT_NEAR(out.intensities()[it->second], s.i / s.n, 1e-4);
  }
  acc.Clear();
  EXPECT_EQ(acc.size(), 0u);
  EXPECT_EQ(acc.Cloud().size(), 0u);
}

}  // namespace
}  // namespace slam_mms::internal
