#include "pipeline/scan_deskewer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "slam_mms/core/lie.hpp"

namespace slam_mms {
namespace {

// A static scene of points in the world; a sensor moving with a constant twist over 0.1 s records
// each point at its own time. De-skewing with the true motion must reproduce the points as seen
// from the scan-start pose.
struct SkewedScan {
  Scan scan;
  std::vector<Eigen::Vector3d> p_lstart_true;
};

SkewedScan MakeSkewedScan(const Eigen::Isometry3d& T_body_lidar, const Vector6d& body_twist,
                          double duration) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-20.0, 20.0);
  SkewedScan s;
  s.scan.stamp_start = Timestamp::FromNanoseconds(1'000'000'000);
  s.scan.stamp_end = s.scan.stamp_start.PlusSeconds(duration);
  s.scan.source = "synthetic";
  const Eigen::Isometry3d T_lidar_body = T_body_lidar.inverse();
  for (int i = 0; i < 5000; ++i) {
    const Eigen::Vector3d p_bstart(u(rng), u(rng), 0.1 * u(rng));  // scene in body-start frame
    const double dt = duration * i / 4999.0;
    const Eigen::Isometry3d T_bstart_b = se3::Exp((dt / duration) * body_twist);
    const Eigen::Vector3d p_lidar_t =
        (T_lidar_body * T_bstart_b.inverse()) * p_bstart;  // as recorded at time dt
    s.scan.cloud.Add(p_lidar_t.cast<float>(), 0.5f, static_cast<float>(dt));
    s.p_lstart_true.push_back(T_lidar_body * p_bstart);
  }
  return s;
}

TEST(ScanDeskewerTest, TrueMotionRestoresTheStartFrame) {
  Eigen::Isometry3d T_body_lidar =
      MakeIsometry(so3::Exp(Eigen::Vector3d(0.01, -0.02, 0.3)), Eigen::Vector3d(0.81, -0.32, 0.80));
  Vector6d twist;
  twist << 0.0, 0.0, 0.08, 1.5, 0.1, 0.0;  // 15 m/s, 46 deg/s yaw over 0.1 s
  const SkewedScan s = MakeSkewedScan(T_body_lidar, twist, 0.1);
  for (int knots : {0, 64}) {
    ScanDeskewer::Options opt;
    opt.num_knots = knots;
    auto deskewer = ScanDeskewer::Create(opt);
    ASSERT_TRUE(deskewer.ok());
    PointCloud out;
    ASSERT_TRUE(deskewer->Deskew(s.scan, se3::Exp(twist), T_body_lidar, &out).ok());
    ASSERT_EQ(out.size(), s.scan.cloud.size());
    double max_err = 0.0, max_skew = 0.0;
    for (size_t i = 0; i < out.size(); ++i) {
      max_err = std::max(max_err, (out.points()[i].cast<double>() - s.p_lstart_true[i]).norm());
      max_skew =
          std::max(max_skew, (s.scan.cloud.points()[i].cast<double>() - s.p_lstart_true[i]).norm());
      EXPECT_EQ(out.time_offsets_s()[i], 0.0f);
    }
    EXPECT_LT(max_err, 2e-3) << "knots " << knots;
    EXPECT_GT(max_skew, 1.0);  // the raw scan is badly skewed
  }
}

TEST(ScanDeskewerTest, RejectsOffsetsOutsideTheScanAndBadOptions) {
  const SkewedScan s = MakeSkewedScan(Eigen::Isometry3d::Identity(), Vector6d::Zero(), 0.1);
  Scan bad = s.scan;
  bad.cloud.time_offsets_s()[10] = 0.5f;
  PointCloud out;
  const Status st = ScanDeskewer().Deskew(bad, Eigen::Isometry3d::Identity(),
                                          Eigen::Isometry3d::Identity(), &out);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("point 10"), std::string::npos) << st.message();
  ScanDeskewer::Options opt;
  opt.num_threads = 0;
  EXPECT_EQ(ScanDeskewer::Create(opt).status().message(),
            "ScanDeskewer::Options::num_threads = 0; must be >= 1");
}

}  // namespace
}  // namespace slam_mms
