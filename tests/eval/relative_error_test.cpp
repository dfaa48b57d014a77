#include "slam_mms/eval/relative_error.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "slam_mms/core/lie.hpp"

namespace slam_mms::eval {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;

// Frames 1 m apart on a straight line along x, identity rotation: dist[i] = i exactly.
std::vector<Eigen::Isometry3d> StraightLine(int num_frames) {
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < num_frames; ++i) {
    poses.push_back(MakeIsometry(Eigen::Matrix3d::Identity(), Eigen::Vector3d(i, 0.0, 0.0)));
  }
  return poses;
}

TEST(RelativeErrorTest, ConstantScaleDrift) {
  // Estimated positions scaled by (1 + s): every segment from f to the first frame strictly beyond
  // f + L, i.e. f + L + 1, has translation error s (L + 1); t_err / L = s (L + 1) / L.
  const int n = 1001;  // path 1000 m
  const double s = 0.02;
  const std::vector<Eigen::Isometry3d> gt = StraightLine(n);
  std::vector<Eigen::Isometry3d> est = gt;
  for (Eigen::Isometry3d& T : est) T.translation() *= 1.0 + s;

  const StatusOr<RelativeErrorResult> r = ComputeRelativeError(gt, est);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_EQ(r->lengths_label, "kitti_100-800m");
  EXPECT_DOUBLE_EQ(r->ground_truth_path_length_m, 1000.0);

  double sum = 0.0;
  size_t count = 0;
  for (const SegmentLengthError& pl : r->per_length) {
    const double L = pl.length_m;
    // Starts f = 0, 10, 20, ... with f + L + 1 <= 1000.
    const size_t expected_count = static_cast<size_t>((999.0 - L) / 10.0) + 1;
    EXPECT_EQ(pl.num_segments, expected_count) << "L = " << L;
    EXPECT_NEAR(pl.t_rel_pct, 100.0 * s * (L + 1.0) / L, 1e-9) << "L = " << L;
    EXPECT_NEAR(pl.r_rel_deg_per_100m, 0.0, 1e-9);
    sum += expected_count * s * (L + 1.0) / L;
    count += expected_count;
  }
  EXPECT_EQ(r->num_segments, count);
  EXPECT_NEAR(r->t_rel_pct, 100.0 * sum / count, 1e-9);
  EXPECT_NEAR(r->r_rel_deg_per_100m, 0.0, 1e-9);
}

TEST(RelativeErrorTest, ConstantYawDrift) {
  // Estimate: true positions, heading drifting by c per frame (yaw_i = c i). For a segment f..l
  // (l = f + L + 1): rotation error c (l - f); translation error |Rz(c f) d - d| = 2 |d| sin(c f /
  // 2) with |d| = l - f (derivation: inv(delta_est) delta_gt = [Rl^T Rf, Rl^T (Rf d - d)]).
  const int n = 901;
  const double c = 1e-4;
  const std::vector<Eigen::Isometry3d> gt = StraightLine(n);
  std::vector<Eigen::Isometry3d> est = gt;
  for (int i = 0; i < n; ++i) est[i].linear() = FromRollPitchYaw(0.0, 0.0, c * i);

  const StatusOr<RelativeErrorResult> r = ComputeRelativeError(gt, est);
  ASSERT_TRUE(r.ok());
  double sum_t = 0.0, sum_r = 0.0;
  size_t count = 0;
  for (int f = 0; f < n; f += 10) {
    for (double L : {100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0}) {
      const int l = f + static_cast<int>(L) + 1;
      if (l > n - 1) continue;
      const double d = l - f;
      sum_r += c * (l - f) / L;
      sum_t += 2.0 * d * std::sin(c * f / 2.0) / L;
      ++count;
    }
  }
  EXPECT_EQ(r->num_segments, count);
  EXPECT_NEAR(r->r_rel_deg_per_100m, 100.0 * kRadToDeg * sum_r / count, 1e-9);
  EXPECT_NEAR(r->t_rel_pct, 100.0 * sum_t / count, 1e-9);
  // Per length 100 m: rotation error exactly c * 101 / 100 rad/m.
  EXPECT_NEAR(r->per_length[0].r_rel_deg_per_100m, 100.0 * kRadToDeg * c * 101.0 / 100.0, 1e-9);
}

TEST(RelativeErrorTest, SegmentEndsStrictlyBeyondTheLength) {
  RelativeErrorOptions o;
  o.segment_lengths_m = {100.0};
  // Path of exactly 100 m: no frame is strictly beyond 100 m from frame 0.
  StatusOr<RelativeErrorResult> r = ComputeRelativeError(StraightLine(101), StraightLine(101), o);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->num_segments, 0u);
  EXPECT_TRUE(std::isnan(r->t_rel_pct));
  EXPECT_TRUE(std::isnan(r->r_rel_deg_per_100m));
  // 101 m: exactly one segment, frame 0 to frame 101.
  r = ComputeRelativeError(StraightLine(102), StraightLine(102), o);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->num_segments, 1u);
  EXPECT_NEAR(r->t_rel_pct, 0.0, 1e-12);
  // 111 m: starts at 0 (ends 101) and 10 (ends 111); 20 would need frame 121.
  r = ComputeRelativeError(StraightLine(112), StraightLine(112), o);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->num_segments, 2u);
  // A start every 5 frames instead: 0, 5, 10.
  o.step_frames = 5;
  r = ComputeRelativeError(StraightLine(112), StraightLine(112), o);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->num_segments, 3u);
}

TEST(RelativeErrorTest, SegmentEndIsTheFirstFrameBeyondNotTheNearest) {
  // Uneven spacing: frames at x = 0, 9.9, 10.0, 30 (path 30 m); L = 10: from frame 0 the first
  // frame strictly beyond 10 m is frame 3 (x = 30), not frame 2 (x = 10 exactly). The estimate is
  // offset only at frame 3, so the error is visible only if the segment ends there.
  std::vector<Eigen::Isometry3d> gt;
  for (double x : {0.0, 9.9, 10.0, 30.0}) {
    gt.push_back(MakeIsometry(Eigen::Matrix3d::Identity(), Eigen::Vector3d(x, 0, 0)));
  }
  std::vector<Eigen::Isometry3d> est = gt;
  est[3].translation().y() += 1.0;
  RelativeErrorOptions o;
  o.segment_lengths_m = {10.0};
  const StatusOr<RelativeErrorResult> r = ComputeRelativeError(gt, est, o);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->num_segments, 1u);
  EXPECT_NEAR(r->t_rel_pct, 100.0 * 1.0 / 10.0, 1e-12);
}

TEST(RelativeErrorTest, TimestampedOverloadMatchesFrameOverload) {
  const int n = 301;
  Trajectory gt, est;
  const Timestamp t0 = Timestamp::FromNanoseconds(1000000000000LL);
  for (int i = 0; i < n; ++i) {
    const Eigen::Isometry3d T = MakeIsometry(FromRollPitchYaw(0, 0, 0.003 * i),
                                             Eigen::Vector3d(i * std::cos(0.001 * i), i * 0.1, 0));
    ASSERT_TRUE(gt.Add(t0.PlusSeconds(0.1 * i), T).ok());
    Eigen::Isometry3d Te = T;
    Te.translation() *= 1.01;
    ASSERT_TRUE(est.Add(t0.PlusSeconds(0.1 * i), Te).ok());
  }
  const StatusOr<RelativeErrorResult> a =
      ComputeRelativeError(est, gt, RelativeErrorOptions::ShortDrive());
  ASSERT_TRUE(a.ok());
  std::vector<Eigen::Isometry3d> g, e;
  for (int i = 0; i < n; ++i) {
    g.push_back(gt[i].T_world_body);
    e.push_back(est[i].T_world_body);
  }
  const StatusOr<RelativeErrorResult> b =
      ComputeRelativeError(g, e, RelativeErrorOptions::ShortDrive());
  ASSERT_TRUE(b.ok());
  EXPECT_EQ(a->lengths_label, "short_10-80m");
  EXPECT_GT(a->num_segments, 0u);
  EXPECT_EQ(a->num_segments, b->num_segments);
  EXPECT_NEAR(a->t_rel_pct, b->t_rel_pct, 1e-12);
  EXPECT_GT(a->t_rel_pct, 0.5);
}

TEST(RelativeErrorTest, CombiningSequencesIsThePlainMeanOverAllPairs) {
  // Sequence A: 2 % scale drift, 1001 frames; sequence B: 5 %, 301 frames (only 100/200 m fit).
  std::vector<Eigen::Isometry3d> gt_a = StraightLine(1001), est_a = gt_a;
  for (Eigen::Isometry3d& T : est_a) T.translation() *= 1.02;
  std::vector<Eigen::Isometry3d> gt_b = StraightLine(301), est_b = gt_b;
  for (Eigen::Isometry3d& T : est_b) T.translation() *= 1.05;
  const StatusOr<RelativeErrorResult> a = ComputeRelativeError(gt_a, est_a);
  const StatusOr<RelativeErrorResult> b = ComputeRelativeError(gt_b, est_b);
  ASSERT_TRUE(a.ok() && b.ok());
  // Concatenating B after A in one call would create segments across the seam; combine instead.
  const StatusOr<RelativeErrorResult> c = CombineRelativeErrors({*a, *b});
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(c->num_segments, a->num_segments + b->num_segments);
  double sum = 0.0;
  size_t n = 0;
  for (const auto* r : {&*a, &*b}) {
    const double s = r == &*a ? 0.02 : 0.05;
    for (const SegmentLengthError& pl : r->per_length) {
      sum += pl.num_segments * 100.0 * s * (pl.length_m + 1.0) / pl.length_m;
      n += pl.num_segments;
    }
  }
  EXPECT_NEAR(c->t_rel_pct, sum / n, 1e-9);
  EXPECT_EQ(c->per_length[0].num_segments,
            a->per_length[0].num_segments + b->per_length[0].num_segments);
  RelativeErrorResult other = *b;
  other.lengths_label = "short_10-80m";
  EXPECT_FALSE(CombineRelativeErrors({*a, other}).ok());
  EXPECT_FALSE(CombineRelativeErrors({}).ok());
}

TEST(RelativeErrorTest, OptionsAndInputValidation) {
  RelativeErrorOptions o;
  o.segment_lengths_m = {50.0, 25.0};
  EXPECT_EQ(o.LengthsLabel(), "custom_25-50m");
  o.segment_lengths_m = {50.0, -1.0};
  EXPECT_NE(o.Validate().message().find("segment_lengths_m[1]"), std::string::npos);
  o = RelativeErrorOptions();
  o.step_frames = 0;
  EXPECT_NE(o.Validate().message().find("step_frames"), std::string::npos);
  EXPECT_FALSE(ComputeRelativeError(StraightLine(10), StraightLine(9)).ok());
  EXPECT_FALSE(ComputeRelativeError(StraightLine(1), StraightLine(1)).ok());
}

}  // namespace
}  // namespace slam_mms::eval
