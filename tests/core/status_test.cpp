#include "slam_mms/core/status.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms {
namespace {

StatusOr<int> ParsePositive(int v) {
  if (v <= 0) return InvalidArgumentError("value = " + std::to_string(v) + "; must be > 0");
  return v;
}

Status Twice(int v, int* out) {
  SLAM_MMS_ASSIGN_OR_RETURN(const int x, ParsePositive(v));
  *out = 2 * x;
  return OkStatus();
}

TEST(StatusTest, CodesMessagesAndMacros) {
  EXPECT_TRUE(OkStatus().ok());
  const Status s = DataLossError("file.bin: size 17 is not a multiple of 16");
  EXPECT_FALSE(s.ok());
  EXPECT_EQ(s.ToString(), "DATA_LOSS: file.bin: size 17 is not a multiple of 16");
  EXPECT_EQ(s.WithContext("reading drive").message(),
            "reading drive: file.bin: size 17 is not a multiple of 16");
  int out = 0;
  EXPECT_TRUE(Twice(4, &out).ok());
  EXPECT_EQ(out, 8);
  const Status bad = Twice(-1, &out);
  EXPECT_EQ(bad.code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(bad.message(), "value = -1; must be > 0");
}

TEST(StatusTest, StatusOrFromOkStatusIsAnError) {
  StatusOr<int> v(OkStatus());
  EXPECT_FALSE(v.ok());
  EXPECT_EQ(v.status().code(), StatusCode::kInternal);
}

TEST(LoggingTest, SinkReceivesMessagesAboveLevelOnly) {
  std::vector<std::string> got;
  const LogSink previous = SetLogSink([&](LogLevel l, const std::string& m) {
    got.push_back(std::string(LogLevelName(l)) + ":" + m);
  });
  SetMinLogLevel(LogLevel::kInfo);
  SLAM_MMS_LOG(kDebug) << "hidden";
  SLAM_MMS_LOG(kWarning) << "skipping " << 3;
  SetLogSink(previous);
  SLAM_MMS_LOG(kWarning) << "after reset";
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0], "warning:skipping 3");
}

TEST(LoggingTest, LevelNamesParseBackAndNothingElseDoes) {
  for (LogLevel l : {LogLevel::kDebug, LogLevel::kInfo, LogLevel::kWarning, LogLevel::kError}) {
    LogLevel parsed = l == LogLevel::kDebug ? LogLevel::kError : LogLevel::kDebug;
    ASSERT_TRUE(ParseLogLevel(LogLevelName(l), &parsed)) << LogLevelName(l);
    EXPECT_EQ(parsed, l);
  }
  LogLevel untouched = LogLevel::kInfo;
  for (const char* bad : {"chatty", "", "Debug", "warn", "error "}) {
    EXPECT_FALSE(ParseLogLevel(bad, &untouched)) << "'" << bad << "'";
  }
  EXPECT_EQ(untouched, LogLevel::kInfo);
}

TEST(TimestampTest, SecondsAndKittiString) {
  const Timestamp t = Timestamp::FromNanoseconds(1317034945964389445LL);
  EXPECT_EQ(t.ToKittiString(), "2011-09-26 11:02:25.964389445");
  EXPECT_NEAR(t.PlusSeconds(0.1).SecondsSince(t), 0.1, 1e-12);
  EXPECT_EQ(Timestamp::FromSeconds(1.5).nanoseconds(), 1500000000LL);
}

TEST(PointCloudTest, ViewRoundTripAndNonFiniteRemoval) {
  struct HostPoint {
    double stamp;
    float x, y, z, i;
  };
  std::vector<HostPoint> host = {{0, 1, 2, 3, 0.5f}, {0, NAN, 0, 0, 0}, {0, 4, 5, 6, 0.25f}};
  PointCloudView view;
  view.xyz = &host[0].x;
  view.size = host.size();
  view.stride_bytes = sizeof(HostPoint);
  view.intensity = &host[0].i;
  view.intensity_stride_bytes = sizeof(HostPoint);
  PointCloud cloud = PointCloud::FromView(view);
  ASSERT_EQ(cloud.size(), 3u);
  EXPECT_EQ(cloud.RemoveNonFinite(), 1u);
  ASSERT_EQ(cloud.size(), 2u);
  EXPECT_EQ(cloud.points()[1], Eigen::Vector3f(4, 5, 6));
  EXPECT_EQ(cloud.intensities()[1], 0.25f);
  EXPECT_EQ(cloud.time_offsets_s()[1], 0.0f);
  const PointCloudView back = cloud.View();
  EXPECT_EQ(back.Point(0), Eigen::Vector3f(1, 2, 3));
  EXPECT_EQ(back.Intensity(0), 0.5f);
}

}  // namespace
}  // namespace slam_mms
