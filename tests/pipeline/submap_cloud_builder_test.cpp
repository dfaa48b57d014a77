#include "pipeline/submap_cloud_builder.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <random>

namespace slam_mms::internal {
namespace {

PointCloud RandomScan(int n, uint32_t seed, std::vector<float>* dt) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-40.0f, 40.0f);
  PointCloud cloud;
  dt->clear();
  for (int i = 0; i < n; ++i) {
    cloud.Add(Eigen::Vector3f(u(rng), u(rng), 0.05f * u(rng)), static_cast<float>(i % 9));
    dt->push_back(1e-6f * static_cast<float>(i));
  }
  return cloud;
}

bool SameCloud(const PointCloud& a, const PointCloud& b) {
  return a.size() == b.size() &&
         std::memcmp(a.points().data(), b.points().data(), a.size() * sizeof(Eigen::Vector3f)) ==
             0 &&
         std::memcmp(a.intensities().data(), b.intensities().data(), a.size() * sizeof(float)) == 0;
}

// The background accumulation gives the clouds of the inline one, bit for bit, over two submaps;
// the caller may overwrite its scan as soon as Add returns.
TEST(SubmapCloudBuilderTest, AsynchronousEqualsInline) {
  SubmapCloudBuilder inline_builder(0.1, 0.5, /*asynchronous=*/false);
  SubmapCloudBuilder async_builder(0.1, 0.5, /*asynchronous=*/true);
  std::vector<float> dt;
  PointCloud scan;
  for (int submap = 0; submap < 2; ++submap) {
    for (int k = 0; k < 7; ++k) {
      const int64_t index = 10 * submap + k;
      scan = RandomScan(40000, static_cast<uint32_t>(index + 1), &dt);
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.translation() = Eigen::Vector3d(0.7 * k, 0.1 * k, 0.0);
      T.linear() = Eigen::AngleAxisd(0.05 * k, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      const int64_t start_ns = 1000000000LL * index;
      inline_builder.Add(scan, dt, start_ns, index, T, 35.0);
      async_builder.Add(scan, dt, start_ns, index, T, 35.0);
      scan = PointCloud();  // the builder copied what it needs
      dt.assign(dt.size(), -1.0f);
    }
    const SubmapCloudBuilder::Clouds a = inline_builder.Build();
    const SubmapCloudBuilder::Clouds b = async_builder.Build();
    ASSERT_GT(a.map.size(), 100000u);
    ASSERT_GT(a.registration.size(), 10000u);
    EXPECT_TRUE(SameCloud(a.map, b.map)) << "submap " << submap;
    EXPECT_TRUE(SameCloud(a.registration, b.registration)) << "submap " << submap;
    EXPECT_EQ(a.time_ns, b.time_ns);
    EXPECT_EQ(a.scan_index, b.scan_index);
    ASSERT_EQ(a.scan_index.size(), a.map.size());
    EXPECT_EQ(a.scan_index.front() / 10, submap);  // only this submap's scans
    inline_builder.Clear();
    async_builder.Clear();
  }
  // Destroyed with scans pending: they are accumulated first (no crash, no leak under ASan).
  SubmapCloudBuilder pending(0.1, 0.5, true);
  scan = RandomScan(1000, 5, &dt);
  for (int k = 0; k < 5; ++k) pending.Add(scan, dt, 0, k, Eigen::Isometry3d::Identity(), 35.0);
}

}  // namespace
}  // namespace slam_mms::internal
