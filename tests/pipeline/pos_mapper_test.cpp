// PosMapper (src/pipeline/pos_mapper.hpp): gnss_ins's POS-only mapping on its own.

#include "pipeline/pos_mapper.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "slam_mms/core/lie.hpp"

namespace slam_mms::internal {
namespace {

constexpr double kScanS = 0.1;

InsState State(double t, const Eigen::Vector3d& p, double yaw) {
  InsState s;
  s.stamp = Timestamp::FromSeconds(1000.0 + t);
  s.T_world_body = Eigen::Translation3d(p) * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
  s.cov_T_world_body = Matrix6d::Identity() * (1e-4 * (1.0 + t));
  return s;
}

// Points spread in 4 m voxels apart (so that none share a voxel of the map), one at each time
// offset over the scan.
Scan ScanAt(double t, int64_t index) {
  Scan s;
  s.index = index;
  s.source = "scan " + std::to_string(index);
  s.stamp_start = Timestamp::FromSeconds(1000.0 + t);
  s.stamp_end = s.stamp_start.PlusSeconds(kScanS);
  for (int k = 0; k < 5; ++k) {
    s.cloud.Add(Eigen::Vector3f(10.0f, -8.0f + 4.0f * k, 1.0f), 0.1f * k,
                static_cast<float>(kScanS * k / 4.0));
  }
  return s;
}

PosMapper MakeMapper(const Eigen::Isometry3d& T_body_lidar, double max_range_m = 60.0) {
  ScanDeskewer::Options o;
  o.num_knots = 0;  // exact per-point interpolation
  o.num_threads = 1;
  auto d = ScanDeskewer::Create(o);
  EXPECT_TRUE(d.ok());
  return PosMapper(*d, T_body_lidar, 0.1, max_range_m);
}

TEST(PosMapperTest, PlacesEveryPointWhereThePosWasWhenItWasMeasured) {
  Eigen::Isometry3d T_body_lidar = Eigen::Isometry3d::Identity();
  T_body_lidar.translation() << 0.5, 0.0, 1.7;
  PosMapper mapper = MakeMapper(T_body_lidar);
  // Moving 1 m in x and turning 0.1 rad during the scan.
  const InsState s0 = State(0.0, Eigen::Vector3d(5, 2, 0), 0.3);
  const InsState s1 = State(kScanS, Eigen::Vector3d(6, 2, 0), 0.4);
  const Scan scan = ScanAt(0.0, 7);
  auto res = mapper.Map(scan, s0, s1);
  ASSERT_TRUE(res.ok()) << res.status().ToString();
  EXPECT_EQ(res->motion_factor, MotionFactorType::kPos);
  EXPECT_EQ(res->scan_index, 7);
  EXPECT_TRUE(res->T_world_body.isApprox(s0.T_world_body));
  ASSERT_EQ(mapper.trajectory().size(), 1u);
  EXPECT_EQ(mapper.trajectory()[0].stamp, scan.stamp_start);
  ASSERT_TRUE(mapper.trajectory()[0].cov_T_world_body.has_value());
  EXPECT_TRUE(mapper.trajectory()[0].cov_T_world_body->isApprox(s0.cov_T_world_body));

  MapPointStamps stamps;
  const PointCloud map = mapper.Cloud(&stamps);
  ASSERT_EQ(map.size(), 5u);
  ASSERT_EQ(stamps.size(), 5u);
  // The first point at the scan start: at s0. The last at the scan end: at s1. Between them the
  // LiDAR moves with the constant twist of its motion over the scan (ScanDeskewer).
  const Eigen::Isometry3d T_w_l0 = s0.T_world_body * T_body_lidar;
  const Vector6d xi = se3::Log(T_w_l0.inverse() * s1.T_world_body * T_body_lidar);
  for (size_t k = 0; k < 5; ++k) {
    const double a = k / 4.0;
    const Eigen::Vector3d p = scan.cloud.points()[k].cast<double>();
    const Eigen::Vector3d expected = T_w_l0 * se3::Exp(a * xi) * p;
    double best = 1e9;
    size_t j_best = 0;
    for (size_t j = 0; j < map.size(); ++j) {
      const double d = (map.points()[j].cast<double>() - expected).norm();
      if (d < best) best = d, j_best = j;
    }
    EXPECT_LT(best, 2e-3) << "point " << k;
    EXPECT_EQ(stamps.scan_index[j_best], 7);
    EXPECT_NEAR((stamps.time_ns[j_best] - scan.stamp_start.nanoseconds()) * 1e-9, kScanS * a, 1e-6);
  }
}

TEST(PosMapperTest, DropsPointsBeyondTheMapRange) {
  PosMapper mapper = MakeMapper(Eigen::Isometry3d::Identity(), /*max_range_m=*/10.5);
  const InsState s = State(0.0, Eigen::Vector3d::Zero(), 0.0);
  InsState s1 = s;
  s1.stamp = s.stamp.PlusSeconds(kScanS);
  ASSERT_TRUE(mapper.Map(ScanAt(0.0, 1), s, s1).ok());
  // Ranges: sqrt(100 + y^2 + 1) for y = -8, -4, 0, 4, 8: only y = 0 is within 10.5 m.
  EXPECT_EQ(mapper.Cloud(nullptr).size(), 1u);
}

TEST(PosMapperTest, RejectsAScanNotAfterThePreviousOneAndAddsNothing) {
  PosMapper mapper = MakeMapper(Eigen::Isometry3d::Identity());
  const InsState a0 = State(0.0, Eigen::Vector3d::Zero(), 0.0);
  const InsState a1 = State(kScanS, Eigen::Vector3d(1, 0, 0), 0.0);
  ASSERT_TRUE(mapper.Map(ScanAt(0.0, 1), a0, a1).ok());
  const size_t n = mapper.Cloud(nullptr).size();
  auto again = mapper.Map(ScanAt(0.0, 2), a0, a1);
  ASSERT_FALSE(again.ok());
  EXPECT_EQ(again.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(again.status().message().find("scan 2"), std::string::npos) << again.status().message();
  EXPECT_EQ(mapper.Cloud(nullptr).size(), n);
  EXPECT_EQ(mapper.trajectory().size(), 1u);
  // A bad motion (non-finite) is the de-skewer's InvalidArgument, and adds nothing either.
  InsState bad = State(0.2 + kScanS, Eigen::Vector3d(2, 0, 0), 0.0);
  bad.T_world_body.translation().x() = std::nan("");
  EXPECT_FALSE(mapper.Map(ScanAt(0.2, 3), State(0.2, Eigen::Vector3d(2, 0, 0), 0.0), bad).ok());
  EXPECT_EQ(mapper.trajectory().size(), 1u);
  EXPECT_EQ(mapper.Cloud(nullptr).size(), n);
}

}  // namespace
}  // namespace slam_mms::internal
