#include "slam_mms/eval/outage_error.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "slam_mms/core/lie.hpp"

namespace slam_mms::eval {
namespace {

const Timestamp kRef = Timestamp::FromNanoseconds(5000000000LL);

// Errors at t = 0, 1, ..., 19 s after kRef: position error t/10 m, rotation error t/100 rad.
std::vector<PoseError> Ramp() {
  std::vector<PoseError> errors;
  for (int i = 0; i < 20; ++i) {
    PoseError e;
    e.stamp = kRef.PlusSeconds(i);
    e.position_error_m = 0.1 * i;
    e.rotation_error_rad = 0.01 * i;
    errors.push_back(e);
  }
  return errors;
}

TEST(OutageErrorTest, WindowsAreHalfOpenAndStatisticsExact) {
  // [5, 8) holds t = 5, 6, 7 (8 is excluded); [15, 25) holds 15..19.
  const std::vector<OutageWindow> windows = {{5.0, 3.0}, {15.0, 10.0}};
  const StatusOr<OutageErrorResult> r = ComputeOutageErrors(Ramp(), windows, kRef);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  ASSERT_EQ(r->windows.size(), 2u);
  const WindowError& w0 = r->windows[0];
  EXPECT_EQ(w0.num_poses, 3u);
  EXPECT_NEAR(w0.max_pos_err_m, 0.7, 1e-12);
  EXPECT_NEAR(w0.rms_pos_err_m, std::sqrt((0.25 + 0.36 + 0.49) / 3.0), 1e-12);
  EXPECT_NEAR(w0.max_rot_err_deg, 0.07 * 180.0 / M_PI, 1e-9);
  EXPECT_NEAR(w0.rms_rot_err_deg,
              std::sqrt((0.05 * 0.05 + 0.06 * 0.06 + 0.07 * 0.07) / 3.0) * 180.0 / M_PI, 1e-9);
  EXPECT_EQ(r->windows[1].num_poses, 5u);
  EXPECT_NEAR(r->windows[1].max_pos_err_m, 1.9, 1e-12);

  EXPECT_EQ(r->num_poses, 8u);
  EXPECT_NEAR(r->max_pos_err_m, 1.9, 1e-12);
  double sq = 0.0;
  for (int t : {5, 6, 7, 15, 16, 17, 18, 19}) sq += 0.01 * t * t;
  EXPECT_NEAR(r->rms_pos_err_m, std::sqrt(sq / 8.0), 1e-12);
}

TEST(OutageErrorTest, OverlappingWindowsCountPosesOnceInTheTotal) {
  const std::vector<OutageWindow> windows = {{0.0, 4.0}, {2.0, 4.0}};  // {0..3} and {2..5}
  const StatusOr<OutageErrorResult> r = ComputeOutageErrors(Ramp(), windows, kRef);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->windows[0].num_poses, 4u);
  EXPECT_EQ(r->windows[1].num_poses, 4u);
  EXPECT_EQ(r->num_poses, 6u);
}

TEST(OutageErrorTest, EmptyAndInvalidWindows) {
  const StatusOr<OutageErrorResult> none = ComputeOutageErrors(Ramp(), {}, kRef);
  ASSERT_TRUE(none.ok());
  EXPECT_EQ(none->num_poses, 0u);
  // A window with no pose inside.
  const StatusOr<OutageErrorResult> outside = ComputeOutageErrors(Ramp(), {{100.0, 5.0}}, kRef);
  ASSERT_TRUE(outside.ok());
  EXPECT_EQ(outside->windows[0].num_poses, 0u);
  EXPECT_EQ(ComputeOutageErrors(Ramp(), {{1.0, 0.0}}, kRef).status().code(),
            StatusCode::kInvalidArgument);
  EXPECT_FALSE(ComputeOutageErrors(Ramp(), {{std::nan(""), 1.0}}, kRef).ok());
}

TEST(OutageErrorTest, EndToEndFromAteErrors) {
  // A trajectory that is exact except for a 2 m lateral error between 10 s and 12 s.
  Trajectory gt, est;
  for (int i = 0; i <= 200; ++i) {
    const double t = 0.1 * i;
    const Eigen::Isometry3d T =
        MakeIsometry(Eigen::Matrix3d::Identity(), Eigen::Vector3d(5 * t, 0, 0));
    ASSERT_TRUE(gt.Add(kRef.PlusSeconds(t), T).ok());
    Eigen::Isometry3d Te = T;
    if (i >= 100 && i < 120) Te.translation().y() += 2.0;
    ASSERT_TRUE(est.Add(kRef.PlusSeconds(t), Te).ok());
  }
  const StatusOr<AteResult> ate = ComputeAte(est, gt);
  ASSERT_TRUE(ate.ok());
  const StatusOr<OutageErrorResult> in = ComputeOutageErrors(ate->errors, {{9.95, 2.0}}, kRef);
  ASSERT_TRUE(in.ok());
  EXPECT_EQ(in->num_poses, 20u);
  EXPECT_NEAR(in->rms_pos_err_m, 2.0, 1e-9);
  const StatusOr<OutageErrorResult> before = ComputeOutageErrors(ate->errors, {{0.0, 9.95}}, kRef);
  ASSERT_TRUE(before.ok());
  EXPECT_NEAR(before->max_pos_err_m, 0.0, 1e-9);
}

}  // namespace
}  // namespace slam_mms::eval
