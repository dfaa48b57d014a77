#include "slam_mms/eval/scan_statistics.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace slam_mms::eval {
namespace {

// A 64-beam scan of flat ground 1.73 m below the sensor and a wall 10 m ahead (x = 10), ring by
// ring, each ring clockwise from the rear, 1024 firings per ring (upper beams see the wall only).
PointCloud SyntheticScan() {
  PointCloud c;
  for (int b = 0; b < 64; ++b) {
    const double el = (2.0 - b * 26.8 / 63.0) * M_PI / 180.0;
    for (int j = 0; j < 1024; ++j) {
      const double az = M_PI - 2.0 * M_PI * (j + 0.5) / 1024.0;
      const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                              std::sin(el));
      double r = 1e9;
      if (d.z() < 0.0) r = std::min(r, -1.73 / d.z());
      if (d.x() > 0.0) r = std::min(r, 10.0 / d.x());
      if (r > 80.0) continue;
      c.Add((r * d).cast<float>(), 0.5f);
    }
  }
  return c;
}

TEST(ScanStatistics, RecoversRingsAndClassesOfAKnownScene) {
  const PointCloud scan = SyntheticScan();
  const std::vector<int> rings = RecoverRings(scan, 64);
  ASSERT_EQ(rings.size(), scan.size());
  EXPECT_EQ(*std::max_element(rings.begin(), rings.end()), 63);
  const StatusOr<ScanStatistics> s = ComputeScanStatistics(scan);
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_EQ(s->points, scan.size());
  EXPECT_EQ(s->rings_recovered_scans, 1u);
  // Only ground and wall: almost every neighbourhood is ground or facade, nothing is scatter.
  EXPECT_GT(s->ClassShare(s->class_ground) + s->ClassShare(s->class_facade), 0.7);
  EXPECT_LT(s->ClassShare(s->class_scatter), 0.02);
  EXPECT_GT(s->ClassShare(s->class_facade), 0.05);
  // No depth edge with a point floating between foreground and background.
  EXPECT_LT(s->MixedPixelFraction(), 0.002);
}

TEST(ScanStatistics, MixedPixelsAreCounted) {
  // A pillar (x = 10, |y| < 2) in front of a wall (x = 20): on every ring that sees both, the
  // first wall point beyond each side of the pillar is moved half-way towards it (a mixed pixel).
  PointCloud scan;
  size_t moved = 0;
  for (int b = 0; b < 64; ++b) {
    const double el = (2.0 - b * 26.8 / 63.0) * M_PI / 180.0;
    bool prev_pillar = false;
    for (int j = 0; j < 1024; ++j) {
      const double az = M_PI - 2.0 * M_PI * (j + 0.5) / 1024.0;
      const Eigen::Vector3d d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az),
                              std::sin(el));
      if (d.x() <= 0.3) continue;  // the front only
      const double r_pillar = 10.0 / d.x();
      bool pillar = std::abs(r_pillar * d.y()) < 2.0;
      double r = pillar ? r_pillar : 20.0 / d.x();
      const bool ground = d.z() < 0.0 && -1.73 / d.z() < r;
      if (ground) {
        r = -1.73 / d.z();
        pillar = false;
      }
      if (!ground && !pillar && prev_pillar) {
        r = 0.5 * (r + r_pillar);  // just after the pillar's edge
        ++moved;
      }
      prev_pillar = pillar;
      scan.Add((r * d).cast<float>(), 0.5f);
    }
  }
  ASSERT_GT(moved, 5u);
  const StatusOr<ScanStatistics> s = ComputeScanStatistics(scan);
  ASSERT_TRUE(s.ok());
  EXPECT_GE(s->mixed_pixels, moved);
  EXPECT_LE(s->mixed_pixels, moved + 2);
}

TEST(ScanStatistics, CompareGivesZeroDistanceForIdenticalAndFlagsDifferent) {
  const StatusOr<ScanStatistics> a = ComputeScanStatistics(SyntheticScan());
  ASSERT_TRUE(a.ok());
  for (const StatisticComparison& c : CompareScanStatistics(*a, *a)) {
    if (c.is_histogram) EXPECT_NEAR(c.value, 0.0, 1e-12) << c.name;
    if (!c.is_histogram && c.real != 0.0) EXPECT_NEAR(c.value, 1.0, 1e-12) << c.name;
  }
  PointCloud scaled = SyntheticScan();
  for (Eigen::Vector3f& q : scaled.points()) q *= 2.0f;
  const StatusOr<ScanStatistics> b = ComputeScanStatistics(scaled);
  ASSERT_TRUE(b.ok());
  bool range_flagged = false;
  for (const StatisticComparison& c : CompareScanStatistics(*a, *b)) {
    if (c.name == "range_m") range_flagged = !c.met && c.value > 0.3;
  }
  EXPECT_TRUE(range_flagged);
}

TEST(ScanStatistics, BadOptionsAndMismatchedHistogramsAreErrors) {
  ScanStatisticsOptions o;
  o.query_stride = 0;
  const StatusOr<ScanStatistics> s = ComputeScanStatistics(SyntheticScan(), o);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().ToString().find("ScanStatisticsOptions::query_stride"), std::string::npos);
  Histogram h1("a", "a", 0, 1, 10), h2("b", "b", 0, 1, 5);
  EXPECT_FALSE(h1.Merge(h2).ok());
  // Too few rings: nothing recovered.
  PointCloud one_ring;
  for (int j = 0; j < 2000; ++j) {
    const double az = M_PI - 2.0 * M_PI * j / 2000.0;
    one_ring.Add(Eigen::Vector3f(10.0f * std::cos(az), 10.0f * std::sin(az), -1.7f));
  }
  EXPECT_TRUE(RecoverRings(one_ring, 64).empty());
}

}  // namespace
}  // namespace slam_mms::eval
