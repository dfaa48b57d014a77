// SensorBuffer (src/pipeline/sensor_buffer.hpp): MappingSystem's input stage on its own.

#include "pipeline/sensor_buffer.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>
#include <vector>

namespace slam_mms::internal {
namespace {

Timestamp T(double s) { return Timestamp::FromSeconds(100.0 + s); }

ImuSample Imu(double s) {
  ImuSample x;
  x.stamp = T(s);
  return x;
}

GnssFix Fix(double s) {
  GnssFix x;
  x.stamp = T(s);
  return x;
}

Scan MakeScan(double start, double end, int points = 3) {
  Scan s;
  s.stamp_start = T(start);
  s.stamp_end = T(end);
  for (int i = 0; i < points; ++i) s.cloud.Add(Eigen::Vector3f(1.0f + i, 0.0f, 0.0f));
  return s;
}

TEST(SensorBufferTest, EachStreamMustComeInTimeOrder) {
  SensorBuffer b;
  ASSERT_TRUE(b.AcceptImuTime(T(1.0)).ok());
  EXPECT_TRUE(b.AcceptImuTime(T(1.0)).ok());  // equal stamps are in order
  const Status older = b.AcceptImuTime(T(0.5));
  ASSERT_FALSE(older.ok());
  EXPECT_EQ(older.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(older.message().find("MappingSystem: IMU sample at " + T(0.5).ToKittiString() +
                                 " is older than the previous one at " + T(1.0).ToKittiString()),
            std::string::npos)
      << older.message();
  // A rejected record changes nothing: the previous time still holds.
  EXPECT_FALSE(b.AcceptImuTime(T(0.9)).ok());
  EXPECT_TRUE(b.AcceptImuTime(T(1.1)).ok());
  // The GNSS stream has its own order.
  EXPECT_TRUE(b.AcceptGnssTime(T(0.2)).ok());
  const Status gnss = b.AcceptGnssTime(T(0.1));
  ASSERT_FALSE(gnss.ok());
  EXPECT_NE(gnss.message().find("GNSS fix at"), std::string::npos) << gnss.message();
}

TEST(SensorBufferTest, HeldRecordsAreReleasedMergedInTimeOrderImuFirstOnTies) {
  SensorBuffer b;
  for (double s : {0.0, 0.1, 0.2, 0.3}) b.HoldImu(Imu(s));
  for (double s : {0.05, 0.2, 0.5}) b.HoldGnss(Fix(s));
  std::vector<std::string> order;
  auto imu = [&](const ImuSample& x) {
    order.push_back("i" + std::to_string(x.stamp.SecondsSince(T(0.0))).substr(0, 4));
    return OkStatus();
  };
  auto gnss = [&](const GnssFix& x) {
    order.push_back("g" + std::to_string(x.stamp.SecondsSince(T(0.0))).substr(0, 4));
    return OkStatus();
  };
  ASSERT_TRUE(b.ReleaseHeld(imu, gnss).ok());
  EXPECT_EQ(order, (std::vector<std::string>{"i0.00", "g0.05", "i0.10", "i0.20", "g0.20", "i0.30",
                                             "g0.50"}));
  order.clear();
  ASSERT_TRUE(b.ReleaseHeld(imu, gnss).ok());  // forgotten once released
  EXPECT_TRUE(order.empty());
}

TEST(SensorBufferTest, ReleaseStopsAtTheFirstError) {
  SensorBuffer b;
  for (double s : {0.0, 0.1, 0.2}) b.HoldImu(Imu(s));
  int calls = 0;
  const Status s = b.ReleaseHeld(
      [&](const ImuSample&) { return ++calls == 2 ? DataLossError("bad sample") : OkStatus(); },
      [](const GnssFix&) { return OkStatus(); });
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_EQ(calls, 2);
}

TEST(SensorBufferTest, ImuBetweenKeepsTheMarginOnBothSides) {
  SensorBuffer b;
  for (int k = 0; k <= 40; ++k) b.RecordImu(Imu(0.05 * k));  // 0 .. 2 s at 20 Hz
  const std::vector<ImuSample> w = b.ImuBetween(T(0.5), T(1.0));
  ASSERT_FALSE(w.empty());
  // [0.5 - 0.2, 1.0 + 0.2] = [0.3, 1.2]: 0.30 .. 1.20 in steps of 0.05 (a few ns of rounding in
  // the stamps may move an end sample by one).
  EXPECT_NEAR(w.front().stamp.SecondsSince(T(0.0)), 0.3, 0.05 + 1e-9);
  EXPECT_NEAR(w.back().stamp.SecondsSince(T(0.0)), 1.2, 0.05 + 1e-9);
  for (const ImuSample& s : w) {
    EXPECT_GE(s.stamp.SecondsSince(T(0.5)), -SensorBuffer::kImuWindowMarginS);
    EXPECT_GE(T(1.0).SecondsSince(s.stamp), -SensorBuffer::kImuWindowMarginS);
  }
  for (size_t i = 1; i < w.size(); ++i) EXPECT_TRUE(w[i - 1].stamp < w[i].stamp);
  EXPECT_TRUE(b.ImuBetween(T(10.0), T(11.0)).empty());
}

TEST(SensorBufferTest, ImuHistoryIsTrimmedBehindTheOldestScanStillToCome) {
  SensorBuffer b;
  for (int k = 0; k <= 100; ++k) b.RecordImu(Imu(0.1 * k));  // 0 .. 10 s
  b.scans().push_back(MakeScan(8.0, 8.1));
  b.TrimImuHistory(T(9.5));  // the queued scan at 8 s wins over the last processed one
  ASSERT_FALSE(b.imu_history().empty());
  EXPECT_GE(T(8.0).SecondsSince(b.imu_history().front().stamp), 0.0);
  EXPECT_LE(T(8.0).SecondsSince(b.imu_history().front().stamp), SensorBuffer::kImuHistoryS);
  EXPECT_GT(T(8.0).SecondsSince(b.imu_history().front().stamp), SensorBuffer::kImuHistoryS - 0.11);
  b.scans().clear();
  b.TrimImuHistory(T(9.5));  // none queued: behind the last processed scan
  EXPECT_LE(T(9.5).SecondsSince(b.imu_history().front().stamp), SensorBuffer::kImuHistoryS);
  EXPECT_EQ(b.imu_history().back().stamp, T(10.0));
}

TEST(SensorBufferTest, PosCoverageIsTheNewestInput) {
  SensorBuffer b;
  const Scan s = MakeScan(1.0, 1.1);
  EXPECT_FALSE(b.has_pos_input());
  EXPECT_FALSE(b.PosCovers(s));
  b.MarkPosInput(T(1.05));
  EXPECT_FALSE(b.PosCovers(s));
  b.MarkPosInput(T(1.2));
  b.MarkPosInput(T(0.5));  // an older input does not move it back
  EXPECT_EQ(b.last_pos_input(), T(1.2));
  EXPECT_TRUE(b.PosCovers(s));
}

TEST(SensorBufferTest, ScanAdmissionNamesTheReason) {
  SensorBuffer b;
  EXPECT_EQ(b.ScanRejection(MakeScan(1.0, 1.1, 0), false, Timestamp()), "no points");
  Scan nan = MakeScan(1.0, 1.1, 0);
  nan.cloud.Add(Eigen::Vector3f::Constant(std::numeric_limits<float>::quiet_NaN()));
  EXPECT_EQ(b.ScanRejection(nan, false, Timestamp()), "no finite point");
  EXPECT_EQ(b.ScanRejection(MakeScan(1.1, 1.0), false, Timestamp()),
            "stamp_end before stamp_start");
  EXPECT_FALSE(b.ScanRejection(MakeScan(1.0, 1.1), false, Timestamp()).has_value());
  // Not after the last processed scan, or after the newest queued one.
  auto r = b.ScanRejection(MakeScan(1.0, 1.1), true, T(1.0));
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(*r, "it starts at " + T(1.0).ToKittiString() + ", not after the previous scan at " +
                    T(1.0).ToKittiString());
  b.scans().push_back(MakeScan(2.0, 2.1));
  EXPECT_TRUE(b.ScanRejection(MakeScan(1.5, 1.6), true, T(1.0)).has_value());
  EXPECT_FALSE(b.ScanRejection(MakeScan(2.5, 2.6), true, T(1.0)).has_value());
}

}  // namespace
}  // namespace slam_mms::internal
