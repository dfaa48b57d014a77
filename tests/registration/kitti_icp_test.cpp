// Real KITTI raw frames (drive 0013, ../shared/data): consecutive scans registered with PointIcp
// and ProjectiveIcp; the recovered motion is compared with the OXTS relative motion.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <random>

#include "registration/kitti_frames.hpp"
#include "registration/point_icp.hpp"
#include "registration/projective_icp.hpp"
#include "slam_mms/core/lie.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

struct PairError {
  double trans_m, rot_deg;
};

PairError Error(const Eigen::Isometry3d& est, const Eigen::Isometry3d& ref) {
  const Eigen::Isometry3d d = ref.inverse() * est;
  return {d.translation().norm(), RotationAngle(d.linear()) * 180.0 / M_PI};
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

class KittiIcpTest : public ::testing::Test {
 protected:
  static constexpr int kFrames = 7;  // 6 consecutive pairs keep the test fast
  void SetUp() override {
    SLAM_MMS_REQUIRE_KITTI_RAW();
    ASSERT_TRUE(drive_.Load(testing::KittiRawDriveDir(), 50));
  }
  testing::KittiDrive drive_;
};

TEST_F(KittiIcpTest, ConsecutiveFramesMatchOxtsMotion) {
  const RangeProjection proj;  // HDL-64: 64 x 2048
  auto projective = ProjectiveIcp::Create(proj, ProjectiveIcp::Options()).value();
  PointIcp::Options po;
  po.source_voxel_size = 0.3;
  auto point = PointIcp::Create(po).value();

  std::vector<double> et_proj, er_proj, et_point, er_point;
  PointCloud prev = drive_.Scan(0, true);
  VertexNormalMap prev_map, cur_map;
  proj.ComputeVertexNormalMap(prev, &prev_map);
  for (int k = 1; k < kFrames; ++k) {
    const PointCloud cur = drive_.Scan(k, true);
    proj.ComputeVertexNormalMap(cur, &cur_map);
    const Eigen::Isometry3d T_ref = drive_.RelativeLidar(k - 1, k);
    // Identity start: the vehicle moves ~1.2 m and turns up to a degree between scans.
    const Eigen::Isometry3d init = Eigen::Isometry3d::Identity();

    auto a = projective.Align(cur_map, prev_map, init);
    ASSERT_TRUE(a.ok());
    EXPECT_TRUE(a->converged()) << IcpTerminationName(a->termination);
    ASSERT_TRUE(point.SetTarget(prev.View()).ok());
    auto b = point.Align(cur.View(), init);
    ASSERT_TRUE(b.ok());
    EXPECT_TRUE(b->converged()) << IcpTerminationName(b->termination);
    const PairError ea = Error(a->T_target_source, T_ref), eb = Error(b->T_target_source, T_ref);
    std::printf(
        "pair %d-%d  |t_oxts| %.3f m  projective: %.3f m %.3f deg (%d it, inl %.2f)  point: %.3f m "
        "%.3f deg (%d it)\n",
        k - 1, k, T_ref.translation().norm(), ea.trans_m, ea.rot_deg, a->iterations,
        a->inlier_ratio, eb.trans_m, eb.rot_deg, b->iterations);
    et_proj.push_back(ea.trans_m);
    er_proj.push_back(ea.rot_deg);
    et_point.push_back(eb.trans_m);
    er_point.push_back(eb.rot_deg);
    EXPECT_LT(ea.trans_m, 0.05) << "projective pair " << k;
    EXPECT_LT(eb.trans_m, 0.05) << "point pair " << k;
    EXPECT_LT(ea.rot_deg, 0.2) << "projective pair " << k;
    EXPECT_LT(eb.rot_deg, 0.2) << "point pair " << k;
    prev = cur;
    std::swap(prev_map, cur_map);
  }
  std::printf("median error vs OXTS: projective %.3f m %.3f deg; point %.3f m %.3f deg\n",
              Median(et_proj), Median(er_proj), Median(et_point), Median(er_point));
  EXPECT_LT(Median(et_proj), 0.03);
  EXPECT_LT(Median(et_point), 0.03);
}

// Without de-skew both scans are distorted by the ~1.2 m of motion during the sweep; the ICP then
// estimates a motion between "averaged" scan times. Measured and bounded here, not hidden.
TEST_F(KittiIcpTest, RawScansWithoutDeskew) {
  const RangeProjection proj;
  auto projective = ProjectiveIcp::Create(proj, ProjectiveIcp::Options()).value();
  std::vector<double> et;
  VertexNormalMap prev_map, cur_map;
  proj.ComputeVertexNormalMap(drive_.Scan(30, false), &prev_map);
  for (int k = 31; k < 34; ++k) {
    proj.ComputeVertexNormalMap(drive_.Scan(k, false), &cur_map);
    auto a = projective.Align(cur_map, prev_map, Eigen::Isometry3d::Identity());
    ASSERT_TRUE(a.ok());
    const PairError e = Error(a->T_target_source, drive_.RelativeLidar(k - 1, k));
    std::printf("raw pair %d-%d: projective %.3f m %.3f deg\n", k - 1, k, e.trans_m, e.rot_deg);
    et.push_back(e.trans_m);
    std::swap(prev_map, cur_map);
  }
  EXPECT_LT(Median(et), 0.10);
}

TEST_F(KittiIcpTest, ConvergesFromOneMetreFiveDegreeOffsets) {
  const RangeProjection proj;
  auto projective = ProjectiveIcp::Create(proj, ProjectiveIcp::Options()).value();
  PointIcp::Options po;
  po.source_voxel_size = 0.3;
  auto point = PointIcp::Create(po).value();
  const PointCloud target = drive_.Scan(20, true);
  const PointCloud source = drive_.Scan(21, true);
  VertexNormalMap target_map, source_map;
  proj.ComputeVertexNormalMap(target, &target_map);
  proj.ComputeVertexNormalMap(source, &source_map);
  ASSERT_TRUE(point.SetTarget(target.View()).ok());
  const Eigen::Isometry3d T_ref = drive_.RelativeLidar(20, 21);
  std::mt19937 rng(13);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int trial = 0; trial < 4; ++trial) {
    Vector6d xi;
    xi << 5.0 * M_PI / 180.0 * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized(),
        1.0 * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    const Eigen::Isometry3d init = T_ref * se3::Exp(xi);
    auto a = projective.Align(source_map, target_map, init);
    auto b = point.Align(source.View(), init);
    ASSERT_TRUE(a.ok() && b.ok());
    const PairError ea = Error(a->T_target_source, T_ref), eb = Error(b->T_target_source, T_ref);
    std::printf("offset trial %d: projective %.3f m %.3f deg (%s)  point %.3f m %.3f deg (%s)\n",
                trial, ea.trans_m, ea.rot_deg, IcpTerminationName(a->termination), eb.trans_m,
                eb.rot_deg, IcpTerminationName(b->termination));
    EXPECT_LT(ea.trans_m, 0.05) << "projective trial " << trial;
    EXPECT_LT(eb.trans_m, 0.05) << "point trial " << trial;
    EXPECT_LT(ea.rot_deg, 0.2) << "projective trial " << trial;
    EXPECT_LT(eb.rot_deg, 0.2) << "point trial " << trial;
  }
}

}  // namespace
}  // namespace slam_mms
