#include "pipeline/voxel_accumulator.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>
#include <tuple>

#include "slam_mms/core/voxel_downsample.hpp"

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
  acc.Reset();
  EXPECT_EQ(acc.size(), 0u);
  EXPECT_EQ(acc.Cloud().size(), 0u);
}

// With first-observation tracking: the centroids are those of an untracked grid, and each voxel
// gets the time and scan of its first point (scan start + that point's own offset).
TEST(VoxelAccumulatorTest, TracksTheFirstObservationWithoutChangingCentroids) {
  std::mt19937 rng(8);
  std::uniform_real_distribution<float> u(-10.0f, 10.0f);
  PointCloud a, b;
  for (int i = 0; i < 20000; ++i) {
    a.Add(Eigen::Vector3f(u(rng), u(rng), 0.1f * u(rng)), 1.0f, 0.1f * i / 20000.0f);
    b.Add(Eigen::Vector3f(u(rng) + 10.0f, u(rng), 0.1f * u(rng)), 2.0f, 0.1f * i / 20000.0f);
  }
  const int64_t t_a = 1317042651000000000, t_b = t_a + 100000000;
  const ScanStamp stamp_a{t_a, &a.time_offsets_s(), 41};
  const ScanStamp stamp_b{t_b, &b.time_offsets_s(), 42};
  const double voxel = 1.0;
  VoxelAccumulator plain(voxel), tracked(voxel, true);
  plain.Add(a, Eigen::Isometry3d::Identity(), 100.0);
  plain.Add(b, Eigen::Isometry3d::Identity(), 100.0);
  tracked.Add(a, Eigen::Isometry3d::Identity(), 100.0, &stamp_a);
  tracked.Add(b, Eigen::Isometry3d::Identity(), 100.0, &stamp_b);
  std::vector<int64_t> time_ns, scan;
  const PointCloud c = tracked.Cloud(&time_ns, &scan);
  const PointCloud ref = plain.Cloud();
  ASSERT_EQ(c.size(), ref.size());
  EXPECT_EQ(c.points(), ref.points());
  ASSERT_EQ(time_ns.size(), c.size());
  ASSERT_EQ(scan.size(), c.size());
  // Reference: the earliest point of each voxel (a's points come first, in index order).
  std::map<std::tuple<int64_t, int64_t, int64_t>, std::pair<int64_t, int64_t>> first;
  for (const auto& [cloud, stamp] : {std::make_pair(&a, &stamp_a), std::make_pair(&b, &stamp_b)}) {
    for (size_t k = 0; k < cloud->size(); ++k) {
      const Eigen::Vector3d p = cloud->points()[k].cast<double>();
      const auto key = std::make_tuple(static_cast<int64_t>(std::floor(p.x() / voxel)),
                                       static_cast<int64_t>(std::floor(p.y() / voxel)),
                                       static_cast<int64_t>(std::floor(p.z() / voxel)));
      const int64_t t = stamp->scan_start_ns +
                        std::llround(static_cast<double>(cloud->time_offsets_s()[k]) * 1e9);
      first.emplace(key, std::make_pair(t, stamp->scan_index));  // keeps the first
    }
  }
  ASSERT_EQ(first.size(), c.size());
  size_t i = 0, from_b = 0;
  for (const auto& [key, value] : first) {  // std::map order = the grid's key order
    EXPECT_EQ(time_ns[i], value.first) << i;
    EXPECT_EQ(scan[i], value.second) << i;
    from_b += scan[i] == 42;
    ++i;
  }
  EXPECT_GT(from_b, 0u);
  // Untracked: no stamps.
  plain.Cloud(&time_ns, &scan);
  EXPECT_TRUE(time_ns.empty());
}

// Far from the origin (150 km at 0.1 m: beyond the old 21-bit keys, which wrapped the voxel's
// corner 209.7 km away) the centroids stay where their points are.
// Reset keeps the table (sized by a large first submap) for the next one: a smaller submap
// accumulated after it gives the same bits (centroids, intensities, first observations) as a
// fresh accumulator, and nothing of the first submap is left.
TEST(VoxelAccumulatorTest, ResetKeepsTheTableAndGivesTheSameCloudsAsANewGrid) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-20.0f, 20.0f);
  PointCloud big, small;
  for (int i = 0; i < 200000; ++i) big.Add(Eigen::Vector3f(u(rng), u(rng), u(rng)), 1.0f, 0.0f);
  for (int i = 0; i < 30000; ++i) {
    small.Add(Eigen::Vector3f(0.5f * u(rng), u(rng), 0.1f * u(rng)), 0.5f, 1e-6f * i);
  }
  const ScanStamp stamp_big{1317042651000000000, &big.time_offsets_s(), 7};
  const ScanStamp stamp_small{1317042652000000000, &small.time_offsets_s(), 8};
  const double voxel = 0.2;
  VoxelAccumulator reused(voxel, true), fresh(voxel, true);
  reused.Add(big, Eigen::Isometry3d::Identity(), 100.0, &stamp_big);
  const size_t capacity = reused.MemoryBytes();
  reused.Reset();
  EXPECT_EQ(reused.size(), 0u);
  EXPECT_EQ(reused.Cloud().size(), 0u);
  EXPECT_EQ(reused.MemoryBytes(), capacity);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(1.0, -2.0, 0.3);
  reused.Add(small, T, 100.0, &stamp_small);
  fresh.Add(small, T, 100.0, &stamp_small);
  EXPECT_EQ(reused.MemoryBytes(), capacity);  // no growth: the kept table was large enough
  std::vector<int64_t> t_reused, s_reused, t_fresh, s_fresh;
  const PointCloud a = reused.Cloud(&t_reused, &s_reused);
  const PointCloud b = fresh.Cloud(&t_fresh, &s_fresh);
  ASSERT_GT(b.size(), 1000u);
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) {
    ASSERT_EQ(a.points()[k], b.points()[k]) << k;
    ASSERT_EQ(a.intensities()[k], b.intensities()[k]) << k;
  }
  EXPECT_EQ(t_reused, t_fresh);
  EXPECT_EQ(s_reused, s_fresh);
  EXPECT_EQ(s_reused.front(), 8);
}

TEST(VoxelAccumulatorTest, KeepsVoxelsFarFromTheOrigin) {
  PointCloud cloud;
  cloud.Add(Eigen::Vector3f(0.01f, 0.02f, 0.03f), 1.0f);
  cloud.Add(Eigen::Vector3f(0.03f, 0.04f, 0.05f), 3.0f);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(150000.0, -150000.0, 20.0);
  VoxelAccumulator acc(0.1);
  acc.Add(cloud, T, 100.0);
  acc.Add(cloud, Eigen::Isometry3d::Identity(), 100.0);
  ASSERT_EQ(acc.size(), 2u);
  EXPECT_EQ(acc.num_out_of_range(), 0u);
  const PointCloud out = acc.Cloud();  // cell order: the one at x = 0 first
  ASSERT_EQ(out.size(), 2u);
  EXPECT_NEAR(out.points()[0].x(), 0.02f, 1e-6f);
  EXPECT_NEAR(out.points()[1].x(), 150000.02f, 0.02f);
  EXPECT_NEAR(out.points()[1].y(), -149999.97f, 0.02f);
  EXPECT_NEAR(out.intensities()[1], 2.0f, 1e-6f);
  // Beyond the grid's range (2^30 - 1 voxels): dropped and counted, not wrapped.
  VoxelAccumulator tiny(1e-6);
  T.translation() = Eigen::Vector3d(2000.0, 0.0, 0.0);
  tiny.Add(cloud, T, 100.0);
  EXPECT_EQ(tiny.size(), 0u);
  EXPECT_EQ(tiny.num_out_of_range(), 2u);
}

// Cloud() lists the voxels in cell order ((x, y, z), as VoxelDownsample does), both where the
// cells fit one 64-bit sort key (a submap: radix-sorted keys) and where they do not (clusters
// hundreds of km apart: the cells compared).
TEST(VoxelAccumulatorTest, CloudIsInCellOrder) {
  // Points on cell centres of 0.125 m cells (exact in float and double, far away too), so that
  // each output centroid names its cell exactly.
  constexpr double kVoxel = 0.125;
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> horizontal(-320, 320);
  std::uniform_int_distribution<int> vertical(-64, 64);
  PointCloud cloud;
  for (int i = 0; i < 100000; ++i) {
    cloud.Add(Eigen::Vector3f((horizontal(rng) + 0.5f) * kVoxel, (horizontal(rng) + 0.5f) * kVoxel,
                              (vertical(rng) + 0.5f) * kVoxel),
              1.0f);
  }
  // 2^18 m apart on every axis: 2^21 cells, so 3 x 22 bits, more than one 64-bit key holds.
  for (const double far_m : {0.0, 262144.0}) {
    SCOPED_TRACE(far_m);
    VoxelAccumulator acc(kVoxel);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = Eigen::Vector3d(1000.0, -2000.0, 30.0);
    acc.Add(cloud, T, 100.0);
    T.translation() = Eigen::Vector3d(1000.0 + far_m, -2000.0 - far_m, 30.0 + far_m);
    acc.Add(cloud, T, 100.0);
    const PointCloud out = acc.Cloud();
    ASSERT_EQ(out.size(), acc.size());
    ASSERT_GT(out.size(), 50000u);
    const VoxelGrid grid(kVoxel);
    VoxelCell prev;
    for (size_t k = 0; k < out.size(); ++k) {
      VoxelCell c;
      const Eigen::Vector3d p = out.points()[k].cast<double>();
      ASSERT_TRUE(grid.CellOf(p, &c));
      if (k > 0) {
        ASSERT_TRUE(prev < c) << k;
      }
      prev = c;
    }
  }
}

// Points on and next to voxel faces (decimal faces such as 0.3 and 3.0, where p * (1 / voxel) and
// p / voxel disagree, and negative ones): the accumulator and VoxelDownsample put them in the same
// voxels, the one cell arithmetic of core/voxel_grid.hpp.
TEST(VoxelAccumulatorTest, AgreesWithVoxelDownsampleOnVoxelFaces) {
  PointCloud cloud;
  for (int k = -40; k <= 40; ++k) {
    const float face = static_cast<float>(k) * 0.1f;
    for (float x : {face, std::nextafter(face, 1e9f), std::nextafter(face, -1e9f)}) {
      cloud.Add(Eigen::Vector3f(x, 0.05f, -x), 1.0f);
      cloud.Add(Eigen::Vector3f(0.3f, x, 3.0f), 1.0f);
    }
  }
  for (double voxel : {0.1, 0.3, 0.25}) {
    VoxelAccumulator acc(voxel);
    acc.Add(cloud, Eigen::Isometry3d::Identity(), 100.0);
    const StatusOr<PointCloud> down = VoxelDownsample(cloud, voxel);
    ASSERT_TRUE(down.ok());
    const PointCloud out = acc.Cloud();
    ASSERT_EQ(out.size(), down->size()) << voxel;
    for (size_t i = 0; i < out.size(); ++i) {  // both in cell order
      EXPECT_LT((out.points()[i] - down->points()[i]).norm(), 1e-5f) << voxel << " voxel " << i;
    }
  }
}

}  // namespace
}  // namespace slam_mms::internal
