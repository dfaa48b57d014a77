// OxtsRecord parsing/formatting, conversions, and KITTI timestamp parsing.
#include "slam_mms/io/oxts_record.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/io/kitti_timestamp.hpp"

namespace slam_mms {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

// The first record of KITTI 2011_09_26_drive_0013 (public example line).
constexpr const char* kLine =
    "49.013141872681 8.4378138518088 114.06644439697 -0.000229 0.009947 1.8456953267949 "
    "11.375996992995 -3.290687456108 11.842084178285 -0.083632098803428 0.040323535587709 "
    "-0.43999459306673 0.088955239453583 9.663174859472 -0.35754827095883 0.090143876653998 "
    "9.6666150394393 -0.0022083457830958 0.025055454998679 0.0062110895146255 "
    "-0.0021447310313027 0.025057189512882 0.006226415927148 0.14961617559609 "
    "0.031827660925679 4 8 4 4 0";

OxtsRecord RandomRecord(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::array<double, OxtsRecord::kNumFields> v{};
  for (int i = 0; i < 25; ++i) v[i] = u(rng) * std::pow(10.0, static_cast<int>(u(rng) * 8));
  v[0] = 90.0 * u(rng);
  v[1] = 180.0 * u(rng);
  for (int i = 25; i < 30; ++i) v[i] = std::floor(6.0 * (u(rng) + 1.0));
  return OxtsRecord::FromArray(v);
}

TEST(OxtsRecordTest, ParsesTheKittiLine) {
  auto r = ParseOxtsLine(kLine, "f.txt", 1);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_EQ(r->lat_deg, 49.013141872681);
  EXPECT_EQ(r->lon_deg, 8.4378138518088);
  EXPECT_EQ(r->alt_m, 114.06644439697);
  EXPECT_EQ(r->yaw_rad, 1.8456953267949);
  EXPECT_EQ(r->vn, 11.375996992995);
  EXPECT_EQ(r->ve, -3.290687456108);
  EXPECT_EQ(r->az, 9.663174859472);
  EXPECT_EQ(r->wu, 0.006226415927148);
  EXPECT_EQ(r->pos_accuracy_m, 0.14961617559609);
  EXPECT_EQ(r->vel_accuracy_mps, 0.031827660925679);
  EXPECT_EQ(r->navstat, 4);
  EXPECT_EQ(r->numsats, 8);
  EXPECT_EQ(r->posmode, 4);
  EXPECT_EQ(r->velmode, 4);
  EXPECT_EQ(r->orimode, 0);
  EXPECT_EQ(OxtsFixType(*r), GnssFixType::kDifferential);
}

TEST(OxtsRecordTest, FormatParseRoundTripIsBitExact) {
  std::mt19937_64 rng(42);
  for (int trial = 0; trial < 200; ++trial) {
    const OxtsRecord r = RandomRecord(rng);
    const std::string line = FormatOxtsLine(r);
    auto back = ParseOxtsLine(line, "x", 1);
    ASSERT_TRUE(back.ok()) << back.status().ToString() << " line: " << line;
    const auto a = r.ToArray();
    const auto b = back->ToArray();
    ASSERT_EQ(std::memcmp(a.data(), b.data(), sizeof(a)), 0) << line;
  }
}

TEST(OxtsRecordTest, ErrorsNameFileLineAndField) {
  auto s = ParseOxtsLine("1 2 3", "oxts/data/0000000007.txt", 3).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr("oxts/data/0000000007.txt:3"),
                                 HasSubstr("has 3 numbers"), HasSubstr("field 4 (roll)")));
  std::string line = kLine;
  line.replace(line.find("11.375996992995"), 15, "11.37x");
  s = ParseOxtsLine(line, "a.txt", 1).status();
  EXPECT_THAT(s.message(),
              AllOf(HasSubstr("a.txt:1"), HasSubstr("field 7 (vn)"), HasSubstr("'11.37x'")));
  s = ParseOxtsLine(std::string(kLine) + " 5", "a.txt", 1).status();
  EXPECT_THAT(s.message(), HasSubstr("more than 30"));
  line = kLine;
  line.replace(line.rfind(" 4 8 4 4 0"), 10, " 4.5 8 4 4 0");
  s = ParseOxtsLine(line, "a.txt", 1).status();
  EXPECT_THAT(s.message(), AllOf(HasSubstr("field 26 (navstat)"), HasSubstr("integer")));
  line = kLine;
  line.replace(0, 15, "nan");
  s = ParseOxtsLine(line, "a.txt", 1).status();
  EXPECT_THAT(s.message(), AllOf(HasSubstr("field 1 (lat)"), HasSubstr("not finite")));
  EXPECT_FALSE(ParseOxtsLine("", "a.txt", 1).ok());
}

TEST(OxtsRecordTest, FixTypeMapping) {
  OxtsRecord r;
  r.navstat = kOxtsNavstatLocked;
  const std::pair<int, GnssFixType> table[] = {
      {0, GnssFixType::kNone},     {1, GnssFixType::kNone},         {2, GnssFixType::kSingle},
      {3, GnssFixType::kSingle},   {4, GnssFixType::kDifferential}, {5, GnssFixType::kRtkFloat},
      {6, GnssFixType::kRtkFixed}, {7, GnssFixType::kDifferential}, {8, GnssFixType::kDifferential},
      {9, GnssFixType::kRtkFloat}, {10, GnssFixType::kNone},        {11, GnssFixType::kNone},
      {12, GnssFixType::kNone}};
  for (const auto& [mode, type] : table) {
    r.posmode = mode;
    EXPECT_EQ(OxtsFixType(r), type) << "posmode " << mode;
  }
  r.posmode = 6;
  r.navstat = 2;  // initialising
  EXPECT_EQ(OxtsFixType(r), GnssFixType::kNone);
}

TEST(OxtsRecordTest, GnssFixAndImuSample) {
  auto r = ParseOxtsLine(kLine, "f", 1);
  ASSERT_TRUE(r.ok());
  const Timestamp t = Timestamp::FromNanoseconds(1317042651175862102LL);
  const GnssFix fix = ToGnssFix(*r, t);
  EXPECT_EQ(fix.stamp, t);
  EXPECT_EQ(fix.latitude_deg, r->lat_deg);
  EXPECT_EQ(fix.longitude_deg, r->lon_deg);
  EXPECT_EQ(fix.height_m, r->alt_m);
  EXPECT_EQ(fix.sigma_horizontal_m, r->pos_accuracy_m);
  EXPECT_DOUBLE_EQ(fix.sigma_vertical_m, 1.5 * r->pos_accuracy_m);
  EXPECT_EQ(fix.num_satellites, 8);
  const ImuSample imu = ToImuSample(*r, t);
  EXPECT_EQ(imu.stamp, t);
  EXPECT_EQ(imu.accel_mps2, Eigen::Vector3d(r->ax, r->ay, r->az));
  EXPECT_EQ(imu.gyro_radps, Eigen::Vector3d(r->wx, r->wy, r->wz));
}

TEST(OxtsRecordTest, AttitudeIsRzRyRxAndInverts) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    OxtsRecord r;
    r.roll_rad = M_PI * u(rng);
    r.pitch_rad = 0.49 * M_PI * u(rng);
    r.yaw_rad = M_PI * u(rng);
    const Eigen::Matrix3d R = OxtsAttitude(r);
    EXPECT_TRUE(R.isApprox(FromRollPitchYaw(r.roll_rad, r.pitch_rad, r.yaw_rad), 1e-12));
    OxtsRecord back;
    SetOxtsAttitude(R, &back);
    EXPECT_NEAR(back.roll_rad, r.roll_rad, 1e-9);
    EXPECT_NEAR(back.pitch_rad, r.pitch_rad, 1e-9);
    EXPECT_NEAR(back.yaw_rad, r.yaw_rad, 1e-9);
  }
  // Conventions: yaw 0 = east (body x -> ENU x); positive pitch = front down; roll + = left up.
  OxtsRecord r;
  r.yaw_rad = M_PI / 2;
  EXPECT_TRUE((OxtsAttitude(r) * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY()));
  r = {};
  r.pitch_rad = 0.1;
  EXPECT_LT((OxtsAttitude(r) * Eigen::Vector3d::UnitX()).z(), 0.0);
  r = {};
  r.roll_rad = 0.1;
  EXPECT_GT((OxtsAttitude(r) * Eigen::Vector3d::UnitY()).z(), 0.0);
}

TEST(OxtsRecordTest, FieldNamesAndDataFormat) {
  EXPECT_STREQ(OxtsRecord::FieldName(0), "lat");
  EXPECT_STREQ(OxtsRecord::FieldName(13), "az");
  EXPECT_STREQ(OxtsRecord::FieldName(29), "orimode");
  const std::string text = std::string("\n") + OxtsDataFormatText();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 31);
  for (int i = 0; i < 30; ++i) {
    EXPECT_THAT(text, HasSubstr(std::string("\n") + OxtsRecord::FieldName(i) + ":"))
        << OxtsRecord::FieldName(i);
  }
}

// ------------------------------------------------------------------------------------------------
TEST(KittiTimestampTest, ParsesExactly) {
  auto t = ParseKittiTimestamp("2011-09-26 13:10:51.106324297");
  ASSERT_TRUE(t.ok()) << t.status().ToString();
  // date -u -d '2011-09-26 13:10:51' +%s = 1317042651
  EXPECT_EQ(t->nanoseconds(), 1317042651106324297LL);
  EXPECT_EQ(ParseKittiTimestamp(" 2011-09-26 13:10:51.1\r")->nanoseconds(), 1317042651100000000LL);
  EXPECT_EQ(ParseKittiTimestamp("1970-01-01 00:00:00")->nanoseconds(), 0);
  EXPECT_EQ(ParseKittiTimestamp("2000-02-29 00:00:00.000000001")->nanoseconds(),
            951782400000000001LL);
}

TEST(KittiTimestampTest, RoundTripsWithToKittiString) {
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<int64_t> u(0, 4102444800LL * 1000000000LL);  // 1970..2100
  for (int i = 0; i < 1000; ++i) {
    const Timestamp t = Timestamp::FromNanoseconds(u(rng));
    auto back = ParseKittiTimestamp(t.ToKittiString());
    ASSERT_TRUE(back.ok()) << t.ToKittiString();
    ASSERT_EQ(*back, t) << t.ToKittiString();
  }
}

TEST(KittiTimestampTest, RejectsMalformed) {
  for (const char* bad :
       {"", "2011-09-26", "2011-13-26 13:10:51.1", "2011-02-30 13:10:51.1", "2011-09-26 24:00:00",
        "2011-09-26 13:60:00", "2011-09-26 13:10:51.", "2011-09-26 13:10:51.1234567890",
        "2011-09-26 13:10:51.12a", "2011/09/26 13:10:51", "11-09-26 13:10:51"}) {
    auto t = ParseKittiTimestamp(bad);
    EXPECT_FALSE(t.ok()) << bad;
    EXPECT_EQ(t.status().code(), StatusCode::kInvalidArgument);
  }
  EXPECT_THAT(ParseKittiTimestamp("2011-13-26 13:10:51").status().message(),
              HasSubstr("month 13 out of 1..12"));
}

}  // namespace
}  // namespace slam_mms
