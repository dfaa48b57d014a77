// MotionInputBuilder (src/pipeline/motion_input_builder.hpp): level 1's motion input on its own.

#include "pipeline/motion_input_builder.hpp"

#include <gtest/gtest.h>

namespace slam_mms::internal {
namespace {

const Eigen::Vector3d kG(0.0, 0.0, -9.80665);

Timestamp T(double s) { return Timestamp::FromSeconds(500.0 + s); }

// A body standing still at `p` (the IMU measures the reaction to gravity).
InsState Still(double t, const Eigen::Vector3d& p) {
  InsState s;
  s.stamp = T(t);
  s.T_world_body.translation() = p;
  return s;
}

SensorBuffer StillImu(double from, double to) {
  SensorBuffer b;
  for (double t = from; t <= to + 1e-9; t += 0.01) {
    ImuSample s;
    s.stamp = T(t);
    s.accel_mps2 = -kG;
    b.RecordImu(s);
  }
  return b;
}

Scan ScanAt(double t) {
  Scan s;
  s.source = "scan";
  s.stamp_start = T(t);
  s.stamp_end = T(t + 0.1);
  return s;
}

MotionInputBuilder::Context Valid(double imu_from) {
  MotionInputBuilder::Context c;
  c.gnss_valid = true;
  c.g_world = kG;
  c.g_pos = kG;
  c.imu_from = T(imu_from);
  return c;
}

TEST(MotionInputBuilderTest, LidarOnlyIsConstantVelocity) {
  MotionInputBuilder b;
  MotionInputBuilder::Context c = Valid(0.0);
  c.lidar_only = true;
  const ScanMotionInput m =
      b.Build(ScanAt(1.0), Still(1.0, {}), Still(1.1, {}), c, StillImu(0.0, 2.0));
  EXPECT_EQ(m.type, MotionFactorType::kConstantVelocity);
  EXPECT_TRUE(m.imu.empty());
  EXPECT_EQ(m.v_world_pos, Eigen::Vector3d::Zero());
  // Its first scan carries the velocity it starts from, where the owner gives one.
  c.lidar_only_initial_v_world = Eigen::Vector3d(3.0, -1.0, 0.1);
  const ScanMotionInput first =
      b.Build(ScanAt(1.0), Still(1.0, {}), Still(1.1, {}), c, StillImu(0.0, 2.0));
  EXPECT_EQ(first.type, MotionFactorType::kConstantVelocity);
  EXPECT_EQ(first.v_world_pos, Eigen::Vector3d(3.0, -1.0, 0.1));
}

TEST(MotionInputBuilderTest, OdometryFromThePosWhileGnssHoldsIt) {
  MotionInputBuilder b;
  InsState s0 = Still(1.0, {1, 2, 3}), s1 = Still(1.1, {1, 2, 3});
  s0.v_world_mps << 0.5, 0, 0;
  s0.accel_bias_mps2 << 0.01, 0.02, 0.03;
  s0.gyro_bias_radps << 1e-4, 2e-4, 3e-4;
  const ScanMotionInput m = b.Build(ScanAt(1.0), s0, s1, Valid(0.9), StillImu(0.0, 2.0));
  ASSERT_EQ(m.type, MotionFactorType::kOdometry);
  EXPECT_TRUE(m.T_world_body_pos_start.isApprox(s0.T_world_body));
  EXPECT_TRUE(m.T_world_body_pos_end.isApprox(s1.T_world_body));
  EXPECT_EQ(m.v_world_pos, s0.v_world_mps);
  EXPECT_EQ(m.pos_bias.head<3>(), s0.accel_bias_mps2);
  EXPECT_EQ(m.pos_bias.tail<3>(), s0.gyro_bias_radps);
  EXPECT_EQ(m.g_world, kG);
  EXPECT_EQ(b.num_pos_jumps(), 0);
}

TEST(MotionInputBuilderTest, PreintegrationInOutagesAndConstantVelocityWithoutImu) {
  MotionInputBuilder b;
  MotionInputBuilder::Context c = Valid(0.9);
  c.gnss_valid = false;
  const SensorBuffer imu = StillImu(0.0, 2.0);
  const ScanMotionInput m = b.Build(ScanAt(1.0), Still(1.0, {}), Still(1.1, {}), c, imu);
  ASSERT_EQ(m.type, MotionFactorType::kPreintegration);
  // The samples since the previous scan's start to this scan's end, with the buffer's margin.
  ASSERT_FALSE(m.imu.empty());
  EXPECT_LE(m.imu.front().stamp.SecondsSince(T(0.9)), -SensorBuffer::kImuWindowMarginS + 0.011);
  EXPECT_GE(m.imu.back().stamp.SecondsSince(T(1.1)), SensorBuffer::kImuWindowMarginS - 0.011);
  // No POS at all: preintegration still (biases zero).
  const ScanMotionInput none =
      b.Build(ScanAt(1.0), StatusOr<InsState>(FailedPreconditionError("no POS")),
              StatusOr<InsState>(FailedPreconditionError("no POS")), Valid(0.9), imu);
  EXPECT_EQ(none.type, MotionFactorType::kPreintegration);
  // No IMU either: constant velocity.
  const ScanMotionInput cv =
      b.Build(ScanAt(1.0), Still(1.0, {}), Still(1.1, {}), c, SensorBuffer());
  EXPECT_EQ(cv.type, MotionFactorType::kConstantVelocity);
}

TEST(MotionInputBuilderTest, APosJumpBeyondItsImuSwitchesToPreintegration) {
  const SensorBuffer imu = StillImu(0.0, 3.0);
  // Standing still: the IMU says the body did not move.
  {
    MotionInputBuilder b(0.06, 0.006);
    b.SetPrevious(Still(0.9, {0, 0, 0}));
    const ScanMotionInput m =
        b.Build(ScanAt(1.0), Still(1.0, {0.03, 0, 0}), Still(1.1, {0.03, 0, 0}), Valid(0.9), imu);
    EXPECT_EQ(m.type, MotionFactorType::kOdometry) << "3 cm is within the 6 cm gate";
    EXPECT_EQ(b.num_pos_jumps(), 0);
  }
  {
    MotionInputBuilder b(0.06, 0.006);
    b.SetPrevious(Still(0.9, {0, 0, 0}));
    const ScanMotionInput m =
        b.Build(ScanAt(1.0), Still(1.0, {0.5, 0, 0}), Still(1.1, {0.5, 0, 0}), Valid(0.9), imu);
    EXPECT_EQ(m.type, MotionFactorType::kPreintegration);
    EXPECT_EQ(b.num_pos_jumps(), 1);
  }
  {  // A jump within the scan counts too.
    MotionInputBuilder b(0.06, 0.006);
    const ScanMotionInput m =
        b.Build(ScanAt(1.0), Still(1.0, {0, 0, 0}), Still(1.1, {0, 0.2, 0}), Valid(0.9), imu);
    EXPECT_EQ(m.type, MotionFactorType::kPreintegration);
    EXPECT_EQ(b.num_pos_jumps(), 1);
  }
  // Measured against the IMU: 0.5 m is what it is, whatever the gate.
  const auto jump =
      MotionInputBuilder::PosJump(Still(0.9, {0, 0, 0}), Still(1.0, {0.5, 0, 0}), imu, kG);
  ASSERT_TRUE(jump.has_value());
  EXPECT_NEAR(jump->first, 0.5, 1e-6);
  EXPECT_NEAR(jump->second, 0.0, 1e-9);
  // Where the IMU does not cover the interval, no jump can be measured.
  EXPECT_FALSE(MotionInputBuilder::PosJump(Still(10.0, {}), Still(10.1, {1, 0, 0}), imu, kG));
}

}  // namespace
}  // namespace slam_mms::internal
