#include "slam_mms/io/oxts_timing.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "slam_mms/io/oxts_record.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

// Attitude (roll, pitch, yaw) of a car weaving through turns, and its body rates.
Eigen::Vector3d Rpy(double t) {
  return {0.02 * std::sin(1.3 * t), 0.015 * std::sin(0.9 * t + 1.0), 0.4 * std::sin(0.35 * t)};
}
Eigen::Vector3d BodyRate(double t) {
  const double h = 1e-5;
  auto R = [](const Eigen::Vector3d& rpy) {
    OxtsRecord r;
    r.roll_rad = rpy.x();
    r.pitch_rad = rpy.y();
    r.yaw_rad = rpy.z();
    return OxtsAttitude(r);
  };
  return so3::Log(R(Rpy(t - h)).transpose() * R(Rpy(t + h))) / (2.0 * h);
}

// Records every `step` s for `duration` s whose rates are those of `lag` s earlier.
std::vector<StampedOxts> Records(double step, double duration, double lag) {
  std::vector<StampedOxts> out;
  for (int i = 0; i * step <= duration + 1e-9; ++i) {
    const double t = i * step;
    StampedOxts r;
    r.stamp = Timestamp::FromNanoseconds(1'300'000'000'000'000'000LL +
                                         static_cast<int64_t>(std::llround(t * 1e9)));
    r.index = i;
    const Eigen::Vector3d rpy = Rpy(t);
    r.record.roll_rad = rpy.x();
    r.record.pitch_rad = rpy.y();
    r.record.yaw_rad = rpy.z();
    const Eigen::Vector3d w = BodyRate(t - lag);
    r.record.wx = w.x();
    r.record.wy = w.y();
    r.record.wz = w.z();
    out.push_back(r);
  }
  return out;
}

TEST(OxtsTimingTest, FindsTheLagOfTheRatesAt10And100Hz) {
  for (const double step : {0.1, 0.01}) {
    for (const double lag : {0.0, 0.03, 0.055, -0.04}) {
      const OxtsInertialDelay e = EstimateOxtsInertialDelay(Records(step, 20.0, lag)).value();
      SCOPED_TRACE("step " + std::to_string(step) + ", lag " + std::to_string(lag));
      EXPECT_NEAR(e.delay_s, lag, 0.0026);
      EXPECT_EQ(e.clear, lag != 0.0);  // on time: nothing to gain
      EXPECT_GE(e.samples, static_cast<size_t>(18.0 / step));
      EXPECT_LE(e.rms_at_delay_radps, e.rms_at_zero_radps);
    }
  }
}

TEST(OxtsTimingTest, FewRecordsOrNoRotationAreNotClear) {
  // 8 records: fewer comparisons than OxtsInertialDelayOptions::min_samples.
  const OxtsInertialDelay few = EstimateOxtsInertialDelay(Records(0.1, 0.7, 0.05)).value();
  EXPECT_FALSE(few.clear);
  // A straight, level drive: the rates say nothing about time.
  std::vector<StampedOxts> still = Records(0.1, 10.0, 0.05);
  for (StampedOxts& r : still) r.record = OxtsRecord();
  const OxtsInertialDelay none = EstimateOxtsInertialDelay(still).value();
  EXPECT_FALSE(none.clear);
  EXPECT_EQ(EstimateOxtsInertialDelay(Records(0.1, 0.1, 0.0)).status().code(),
            StatusCode::kFailedPrecondition);
  OxtsInertialDelayOptions bad;
  bad.min_improvement = 1.0;
  EXPECT_EQ(EstimateOxtsInertialDelay(Records(0.1, 5.0, 0.0), bad).status().code(),
            StatusCode::kInvalidArgument);
}

TEST(OxtsTimingTest, KittiDrive0013RatesLagItsAttitudes) {
  SLAM_MMS_REQUIRE_KITTI_RAW();
  auto reader = KittiRawReader::Open(testing::KittiRawDriveDir());
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  ASSERT_TRUE(reader->oxts_inertial_delay_estimate().has_value());
  const OxtsInertialDelay& e = *reader->oxts_inertial_delay_estimate();
  std::printf(
      "KITTI 0013, %zu records: rates fit the attitudes %.0f ms later (RMS %.4f against "
      "%.4f rad/s)\n",
      e.samples, e.delay_s * 1e3, e.rms_at_delay_radps, e.rms_at_zero_radps);
  // 50-55 ms, as across KITTI's drives (docs/io.md); twice as good a fit or better.
  EXPECT_TRUE(e.clear);
  EXPECT_GE(e.delay_s, 0.04);
  EXPECT_LE(e.delay_s, 0.07);
  EXPECT_LT(2.0 * e.rms_at_delay_radps, e.rms_at_zero_radps);
  EXPECT_EQ(reader->oxts_inertial_delay_s(), e.delay_s);
  const std::vector<ImuSample> imu = reader->ImuSamples();
  ASSERT_FALSE(imu.empty());
  EXPECT_EQ(imu.front().stamp, reader->ImuOxtsRecords().front().stamp.PlusSeconds(-e.delay_s));
}

}  // namespace
}  // namespace slam_mms
