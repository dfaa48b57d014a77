// Bad input without the real data: a small synthetic drive written by KittiRawWriter, then damaged
// one way per test (issue 10's list). Each case checks the error code and that the message names
// the file, the line and the field. The FuzzRegression tests replay inputs that libFuzzer (fuzz/)
// found to trigger undefined behaviour, through the public file readers.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <mutex>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "slam_mms/io/kitti_raw_writer.hpp"
#include "slam_mms/io/kitti_timestamp.hpp"
#include "slam_mms/io/trajectory_io.hpp"
#include "testing/log_capture.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

constexpr int kNumScans = 3;
constexpr int kPointsPerScan = 64;

std::string Name(int i, const char* ext) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%010d%s", i, ext);
  return buf;
}

std::vector<std::string> Lines(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  std::string l;
  while (std::getline(in, l)) lines.push_back(l);
  return lines;
}

void WriteText(const fs::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << text;
}

void WriteLines(const fs::path& file, const std::vector<std::string>& lines) {
  std::string text;
  for (const auto& l : lines) text += l + "\n";
  WriteText(file, text);
}

void WriteFloats(const fs::path& file, const std::vector<float>& xyzr) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(xyzr.data()),
            static_cast<std::streamsize>(xyzr.size() * sizeof(float)));
}

OxtsRecord SomeOxts(int i) {
  OxtsRecord r;
  r.lat_deg = 48.5 + 1e-6 * i;
  r.lon_deg = 9.1;
  r.alt_m = 250.0;
  r.yaw_rad = 0.3;
  r.ve = 5.0;
  r.vf = 5.0;
  r.az = 9.81;
  r.pos_accuracy_m = 0.05;
  r.vel_accuracy_mps = 0.02;
  r.navstat = kOxtsNavstatLocked;
  r.numsats = 10;
  r.posmode = r.velmode = r.orimode = 6;
  return r;
}

using testing::LogCapture;

class MalformedDriveTest : public ::testing::Test {
 protected:
  void SetUp() override {
    tmp_ = testing::MakeTempDir("malformed_drive");
    drive_ = tmp_ / "2020_05_17" / "2020_05_17_drive_0001_sync";
    auto writer = KittiRawWriter::Create(drive_);
    ASSERT_TRUE(writer.ok()) << writer.status().ToString();
    Eigen::Isometry3d T_lidar_body = Eigen::Isometry3d::Identity();
    T_lidar_body.translation() = Eigen::Vector3d(-0.81, 0.32, -0.8);
    ASSERT_TRUE(writer->WriteCalibration(T_lidar_body).ok());
    const Timestamp t0 = Timestamp::FromNanoseconds(1589709600000000000LL);
    for (int i = 0; i < kNumScans; ++i) {
      Scan scan;
      scan.stamp_start = t0.PlusSeconds(0.1 * i);
      scan.stamp_end = scan.stamp_start.PlusSeconds(0.099);
      for (int k = 0; k < kPointsPerScan; ++k) {
        const double a = 2.0 * M_PI * k / kPointsPerScan;
        scan.cloud.Add(Eigen::Vector3f(10.0f * std::cos(a), 10.0f * std::sin(a), -1.7f), 0.5f);
      }
      ASSERT_TRUE(writer->AddScan(scan).ok());
      ASSERT_TRUE(writer->AddOxts(scan.stamp_start.PlusSeconds(0.05), SomeOxts(i)).ok());
    }
    ASSERT_TRUE(writer->Finish().ok());
    velo_ = drive_ / "velodyne_points";
    oxts_ = drive_ / "oxts";
    calib_ = drive_.parent_path() / "calib_imu_to_velo.txt";
  }
  void TearDown() override {
    if (!tmp_.empty()) fs::remove_all(tmp_);
  }
  Status OpenStatus(const KittiRawReader::Options& options = {}) {
    return KittiRawReader::Open(drive_, options).status();
  }
  Status ReadScanStatus(size_t i) {
    auto reader = KittiRawReader::Open(drive_);
    if (!reader.ok()) return reader.status();
    return reader->ReadScan(i).status();
  }
  std::string OxtsLine(int i) { return Lines(oxts_ / "data" / Name(i, ".txt")).at(0); }

  fs::path tmp_, drive_, velo_, oxts_, calib_;
};

TEST_F(MalformedDriveTest, IntactDriveReads) {
  auto reader = KittiRawReader::Open(drive_);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  ASSERT_EQ(reader->NumScans(), static_cast<size_t>(kNumScans));
  EXPECT_EQ(reader->OxtsRecords().size(), static_cast<size_t>(kNumScans));
  for (size_t i = 0; i < kNumScans; ++i) {
    auto scan = reader->ReadScan(i);
    ASSERT_TRUE(scan.ok()) << scan.status().ToString();
    EXPECT_EQ(scan->cloud.size(), static_cast<size_t>(kPointsPerScan));
  }
}

TEST_F(MalformedDriveTest, TruncatedBinNamesFileAndSize) {
  const fs::path bin = velo_ / "data" / Name(1, ".bin");
  fs::resize_file(bin, 16 * 10 + 7);
  const Status s = ReadScanStatus(1);
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(),
              AllOf(HasSubstr(bin.string()), HasSubstr("size 167 bytes is not a multiple of 16")));
  EXPECT_TRUE(ReadScanStatus(0).ok()) << "the other scans stay readable";
}

TEST_F(MalformedDriveTest, EmptyScanFileIsDataLoss) {
  const fs::path bin = velo_ / "data" / Name(2, ".bin");
  fs::resize_file(bin, 0);
  const Status s = ReadScanStatus(2);
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(bin.string()), HasSubstr("scan contains no points")));
}

TEST_F(MalformedDriveTest, NanAndInfPointsAreDroppedCountedAndLogged) {
  const fs::path bin = velo_ / "data" / Name(0, ".bin");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  WriteFloats(bin, {1, 2, 3, 0.5f, nan, 2, 3, 0.5f, 1, -inf, 3, 0.5f, 1, 2, 3, nan, 4, 5, 6, 0.1f});
  LogCapture log;
  auto reader = KittiRawReader::Open(drive_);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  auto scan = reader->ReadScan(0);
  ASSERT_TRUE(scan.ok()) << scan.status().ToString();
  EXPECT_EQ(scan->cloud.size(), 2u);
  EXPECT_EQ(reader->TotalDroppedPoints(), 3u);
  EXPECT_THAT(log.messages(), AllOf(HasSubstr(bin.string()), HasSubstr("dropped 3 of 5 points")));
}

TEST_F(MalformedDriveTest, AllPointsNonFiniteIsDataLoss) {
  const fs::path bin = velo_ / "data" / Name(0, ".bin");
  const float nan = std::numeric_limits<float>::quiet_NaN();
  WriteFloats(bin, {nan, 0, 0, 0, 0, nan, 0, 0});
  const Status s = ReadScanStatus(0);
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(bin.string()), HasSubstr("no finite point")));
}

TEST_F(MalformedDriveTest, OxtsLineWithTooFewFields) {
  const fs::path file = oxts_ / "data" / Name(1, ".txt");
  std::string line = OxtsLine(1);
  line = line.substr(0, line.rfind(' '));  // drop orimode
  WriteLines(file, {line});
  const Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(file.string() + ":1"), HasSubstr("has 29 numbers"),
                                 HasSubstr("field 30 (orimode) is missing")));
}

TEST_F(MalformedDriveTest, OxtsLineWithTooManyFields) {
  const fs::path file = oxts_ / "data" / Name(2, ".txt");
  WriteLines(file, {OxtsLine(2) + " 7"});
  const Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(file.string() + ":1"), HasSubstr("more than 30")));
}

TEST_F(MalformedDriveTest, OxtsUnparsableNumberNamesTheField) {
  const fs::path file = oxts_ / "data" / Name(0, ".txt");
  std::vector<std::string> tokens;
  std::istringstream is(OxtsLine(0));
  for (std::string t; is >> t;) tokens.push_back(t);
  tokens[7] = "3.2e";  // field 8 (ve)
  std::string line;
  for (const auto& t : tokens) line += (line.empty() ? "" : " ") + t;
  WriteLines(file, {line});
  const Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(file.string() + ":1"), HasSubstr("field 8 (ve)"),
                                 HasSubstr("'3.2e'")));
}

TEST_F(MalformedDriveTest, ScanTimestampGoingBackwardsNamesBothLines) {
  const fs::path file = velo_ / "timestamps_start.txt";
  auto lines = Lines(file);
  std::swap(lines[1], lines[2]);
  WriteLines(file, lines);
  const Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(file.string() + ":3"), HasSubstr("goes backwards"),
                                 HasSubstr("(line 2 has " + lines[1] + ")")));
}

TEST_F(MalformedDriveTest, DuplicatedScanTimestamp) {
  const fs::path file = velo_ / "timestamps.txt";
  auto lines = Lines(file);
  lines[2] = lines[1];
  WriteLines(file, lines);
  const Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(file.string() + ":3"), HasSubstr("duplicated")));
}

TEST_F(MalformedDriveTest, MissingCalibFileIsNotFoundUnlessAllowed) {
  fs::remove(calib_);
  const Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_THAT(s.message(),
              AllOf(HasSubstr("calib_imu_to_velo.txt not found"), HasSubstr(calib_.string())));
  KittiRawReader::Options o;
  o.allow_missing_calibration = true;
  LogCapture log;
  auto reader = KittiRawReader::Open(drive_, o);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_TRUE(reader->T_lidar_body().isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_THAT(log.messages(), HasSubstr("using identity T_lidar_body"));
}

TEST_F(MalformedDriveTest, MalformedCalibLineNamesLineAndKey) {
  WriteText(calib_, "calib_time: 17-May-2020\nR: 1 0 0 0 1 0 0 0 1\nT: 0.1 zero 0.3\n");
  Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(calib_.string() + ":3"), HasSubstr("key T value 2"),
                                 HasSubstr("'zero'")));
  WriteText(calib_, "R 1 0 0 0 1 0 0 0 1\n");
  s = OpenStatus();
  EXPECT_THAT(s.message(), AllOf(HasSubstr(calib_.string() + ":1"), HasSubstr("without 'key:'")));
}

TEST_F(MalformedDriveTest, ScansWithoutOxtsCoverage) {
  // Sync layout: one OXTS record per scan; a shorter oxts/timestamps.txt is an error...
  auto lines = Lines(oxts_ / "timestamps.txt");
  lines.pop_back();
  WriteLines(oxts_ / "timestamps.txt", lines);
  fs::remove(oxts_ / "data" / Name(kNumScans - 1, ".txt"));
  const Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), HasSubstr("2 lines but the drive has 3 scans"));
  // ... an OXTS file missing for a timestamp line too ...
  lines.push_back(Lines(velo_ / "timestamps.txt").back());
  WriteLines(oxts_ / "timestamps.txt", lines);
  EXPECT_THAT(OpenStatus().message(), HasSubstr("OXTS file 2 missing"));
  // ... and a drive without oxts/ reads with a warning and no records.
  fs::remove_all(oxts_);
  LogCapture log;
  auto reader = KittiRawReader::Open(drive_);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_TRUE(reader->OxtsRecords().empty());
  EXPECT_THAT(log.messages(), HasSubstr("no oxts/ folder; no GNSS/INS records"));
}

TEST_F(MalformedDriveTest, FrameRangeOutsideTheDrive) {
  KittiRawReader::Options o;
  o.first_frame = 1;
  o.last_frame = 7;
  const Status s = OpenStatus(o);
  EXPECT_EQ(s.code(), StatusCode::kOutOfRange);
  EXPECT_THAT(s.message(), AllOf(HasSubstr("frame range [1, 7]"), HasSubstr("frames [0, 2]")));
  o.first_frame = 5;
  o.last_frame = -1;
  EXPECT_EQ(OpenStatus(o).code(), StatusCode::kOutOfRange);
}

TEST_F(MalformedDriveTest, MissingFolderAndMissingScanFile) {
  EXPECT_EQ(KittiRawReader::Open(tmp_ / "nowhere").status().code(), StatusCode::kNotFound);
  fs::remove(velo_ / "data" / Name(1, ".bin"));
  const Status s = OpenStatus();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), HasSubstr("2 scan files but timestamps.txt has 3 lines"));
}

TEST(KittiRawReaderOptionsValidateTest, EachBadValueIsNamedWithItsRule) {
  struct Case {
    std::function<void(KittiRawReader::Options*)> set;
    const char* expected;
  };
  const std::vector<Case> cases = {
      {[](auto* o) { o->first_frame = -1; }, "Options::first_frame = -1; must be >= 0"},
      {[](auto* o) { o->last_frame = -3; }, "Options::last_frame = -3; must be >= 0 or -1 (all)"},
      {[](auto* o) { o->first_frame = 4, o->last_frame = 2; },
       "Options::last_frame = 2; must be >= first_frame = 4"},
      {[](auto* o) { o->vertical_correction_deg = std::nan(""); },
       "vertical_correction_deg = nan; must be finite and within [-5, 5] deg"},
      {[](auto* o) { o->vertical_correction_deg = 6.0; }, "within [-5, 5] deg"},
      {[](auto* o) { o->imu_time_margin_s = -0.5; }, "imu_time_margin_s = -0.5; must be >= 0"},
  };
  for (const Case& c : cases) {
    KittiRawReader::Options o;
    c.set(&o);
    const Status s = o.Validate();
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << c.expected;
    EXPECT_THAT(s.message(), HasSubstr(c.expected));
  }
  EXPECT_TRUE(KittiRawReader::Options().Validate().ok());
}

// ------------------------------------------------------------------------------------------------
// Inputs found by fuzz/ (libFuzzer + UBSan), replayed through the public readers.

TEST(FuzzRegressionTest, KittiTimestampYearOutsideInt64NanosecondsIsRejected) {
  // Was a signed overflow (secs * 1e9) in ParseKittiTimestamp.
  auto t = ParseKittiTimestamp("4040-05-17 10:00:00.000000000");
  EXPECT_EQ(t.status().code(), StatusCode::kInvalidArgument);
  EXPECT_THAT(t.status().message(), HasSubstr("year 4040 out of 1678..2261"));
  EXPECT_TRUE(ParseKittiTimestamp("2261-12-31 23:59:59.999999999").ok());
  EXPECT_TRUE(ParseKittiTimestamp("1678-01-01 00:00:00").ok());
}

TEST(FuzzRegressionTest, TumTimeOutsideInt64NanosecondsIsRejected) {
  // Were signed overflows in ParseSecondsExact (10-11 digit seconds) and a float-cast overflow in
  // the double fallback (Timestamp::FromSeconds(1e300)).
  const fs::path tmp = testing::MakeTempDir("fuzz_regression_tum");
  for (const char* t : {"9600000000", "99999999999.5", "1e300", "-2e10"}) {
    WriteText(tmp / "a.tum", std::string(t) + " 0 0 0 0 0 0 1\n");
    const Status s = ReadTrajectoryTum(tmp / "a.tum").status();
    EXPECT_EQ(s.code(), StatusCode::kDataLoss) << t;
    EXPECT_THAT(s.message(), AllOf(HasSubstr("a.tum:1: field 1 (t)"),
                                   HasSubstr("out of the int64 nanosecond range")))
        << t;
  }
  EXPECT_THAT(ParseSecondsExact("9223372036.0").status().message(), HasSubstr("int64"));
  EXPECT_TRUE(ParseSecondsExact("9223372035.999999999").ok());
  fs::remove_all(tmp);
}

TEST_F(MalformedDriveTest, FuzzRegressionVerticalCorrectionOfHugePointDropsIt) {
  // A finite point near FLT_MAX became Inf after the vertical-angle correction (found by
  // fuzz_kitti_scan); it is now dropped like a non-finite one.
  const float big = std::numeric_limits<float>::max();
  WriteFloats(velo_ / "data" / Name(0, ".bin"), {big, 1.0f, big, 0.5f, 10, 0, -1.7f, 0.5f});
  KittiRawReader::Options o;
  o.vertical_angle_correction = true;
  auto reader = KittiRawReader::Open(drive_, o);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  auto scan = reader->ReadScan(0);
  ASSERT_TRUE(scan.ok()) << scan.status().ToString();
  ASSERT_EQ(scan->cloud.size(), 1u);
  EXPECT_TRUE(scan->cloud.points()[0].allFinite());
  EXPECT_EQ(reader->TotalDroppedPoints(), 1u);
}

}  // namespace
}  // namespace slam_mms
