// DeskewStage (step 1 of Localizer::ProcessScan) on a ring of timed points: a scan without motion
// is unchanged, a scan with POS poses is de-skewed by the POS motion even where its motion factor
// is not F_Odom (a submap reference), the range image is the de-skewed cloud's, and a bad time
// offset is refused.
#include "pipeline/deskew_stage.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace slam_mms::internal {
namespace {

constexpr int64_t kT0Ns = 1'317'000'000'000'000'000;
constexpr double kDurationS = 0.1;

Eigen::Isometry3d Forward(double x_m) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation().x() = x_m;
  return T;
}

/// A ring of 720 points 10 m around the sensor on two heights, fired over the scan by azimuth.
Scan RingScan() {
  Scan scan;
  scan.index = 3;
  scan.source = "ring";
  scan.stamp_start = Timestamp::FromNanoseconds(kT0Ns);
  scan.stamp_end = Timestamp::FromNanoseconds(kT0Ns + static_cast<int64_t>(kDurationS * 1e9));
  for (int i = 0; i < 720; ++i) {
    const double a = 2.0 * M_PI * (i % 360) / 360.0;
    const float z = i < 360 ? -1.0f : 1.0f;
    const float dt = static_cast<float>(kDurationS * (i % 360) / 359.0);
    scan.cloud.Add(Eigen::Vector3f(static_cast<float>(10.0 * std::cos(a)),
                                   static_cast<float>(10.0 * std::sin(a)), z),
                   1.0f, dt);
  }
  return scan;
}

class DeskewStageTest : public ::testing::Test {
 protected:
  void SetUp() override {
    options_.num_threads = 2;
    projection_ = RangeProjection::Create(options_.surfels.renderer.projection).value();
    stage_ = DeskewStage::Create(options_, projection_, Eigen::Isometry3d::Identity()).value();
  }

  Localizer::Options options_;
  RangeProjection projection_;
  DeskewStage stage_;
  MotionPrior prior_;  // no poses recorded: constant velocity is no motion
};

TEST_F(DeskewStageTest, AScanWithoutMotionIsUnchangedAndItsImageIsTheCloudsImage) {
  const Scan scan = RingScan();
  ScanStep step;
  step.pred.factor = MotionFactorType::kConstantVelocity;
  DeskewedScan out;
  LocalizationResult res;
  ScanMotionInput cv;
  ASSERT_TRUE(stage_.Deskew(scan, cv, prior_, Vector6d::Zero(), &step, &out, &res).ok());
  ASSERT_EQ(out.cloud.size(), scan.cloud.size());
  for (size_t i = 0; i < scan.cloud.size(); ++i) {
    EXPECT_LT((out.cloud.points()[i] - scan.cloud.points()[i]).norm(), 1e-5f) << i;
  }
  VertexNormalMap expected;
  projection_.ComputeVertexNormalMap(out.cloud, &expected);
  EXPECT_EQ(out.vnm.vertex, expected.vertex);
  EXPECT_EQ(out.vnm.normal, expected.normal);
  EXPECT_EQ(out.vnm.index, expected.index);
  EXPECT_GE(res.timings.deskew_ms, 0.0);
}

TEST_F(DeskewStageTest, PosPosesDeskewAScanWhoseFactorIsNotFOdom) {
  const Scan scan = RingScan();
  ScanMotionInput pos;
  pos.type = MotionFactorType::kOdometry;
  pos.T_world_body_pos_start = Forward(20.0);
  pos.T_world_body_pos_end = Forward(21.0);  // 1 m forward over the scan
  ScanStep step;
  step.is_reference = true;
  step.pred.factor = MotionFactorType::kNone;  // a submap reference: no motion factor
  DeskewedScan out;
  LocalizationResult res;
  ASSERT_TRUE(stage_.Deskew(scan, pos, prior_, Vector6d::Zero(), &step, &out, &res).ok());
  // The oracle: the de-skewer with the POS relative motion.
  auto deskewer = ScanDeskewer::Create(ScanDeskewer::Options()).value();
  PointCloud expected;
  ASSERT_TRUE(deskewer.Deskew(scan, Forward(1.0), Eigen::Isometry3d::Identity(), &expected).ok());
  ASSERT_EQ(out.cloud.size(), expected.size());
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_LT((out.cloud.points()[i] - expected.points()[i]).norm(), 1e-5f) << i;
  }
  // The last point fired (alpha = 1) moved by the whole metre.
  EXPECT_NEAR((out.cloud.points()[719] - scan.cloud.points()[719]).x(), 1.0f, 1e-4f);
}

TEST_F(DeskewStageTest, ATimeOffsetOutsideTheScanIsRefused) {
  Scan scan = RingScan();
  scan.cloud.Add(Eigen::Vector3f(5.0f, 0.0f, 0.0f), 1.0f, static_cast<float>(kDurationS + 0.01));
  ScanMotionInput pos;
  pos.type = MotionFactorType::kOdometry;
  pos.T_world_body_pos_end = Forward(1.0);
  ScanStep step;
  DeskewedScan out;
  LocalizationResult res;
  const Status st = stage_.Deskew(scan, pos, prior_, Vector6d::Zero(), &step, &out, &res);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("ring"), std::string::npos) << st.message();
}

}  // namespace
}  // namespace slam_mms::internal
