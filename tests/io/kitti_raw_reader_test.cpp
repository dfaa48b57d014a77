// KittiRawReader on the real KITTI frames in ../shared/data (skipped where absent) and on malformed
// copies of them.
#include "slam_mms/io/kitti_raw_reader.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <GeographicLib/LocalCartesian.hpp>
#include <cmath>
#include <fstream>
#include <limits>
#include <mutex>
#include <sstream>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/io/kitti_timestamp.hpp"
#include "testing/log_capture.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::AllOf;
using ::testing::HasSubstr;

std::vector<std::string> Lines(const fs::path& file) {
  std::ifstream in(file);
  std::vector<std::string> lines;
  std::string l;
  while (std::getline(in, l)) lines.push_back(l);
  return lines;
}

void WriteLines(const fs::path& file, const std::vector<std::string>& lines) {
  std::ofstream out(file, std::ios::trunc);
  for (const auto& l : lines) out << l << "\n";
}

std::string Name(int i, const char* ext) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%010d%s", i, ext);
  return buf;
}

// Copies the first `n` frames of the real drive into <tmp>/2011_09_26/<drive> (calib in the date
// folder) and returns the drive folder.
fs::path MakeMiniDrive(const fs::path& tmp, int n) {
  const fs::path src = testing::KittiRawDriveDir();
  const fs::path date = tmp / "2011_09_26";
  const fs::path drive = date / src.filename();
  for (const char* calib :
       {"calib_imu_to_velo.txt", "calib_velo_to_cam.txt", "calib_cam_to_cam.txt"}) {
    fs::create_directories(date);
    fs::copy_file(src.parent_path() / calib, date / calib);
  }
  for (const char* sub : {"velodyne_points", "oxts"}) {
    fs::create_directories(drive / sub / "data");
    const char* ext = std::string(sub) == "oxts" ? ".txt" : ".bin";
    for (int i = 0; i < n; ++i) {
      fs::copy_file(src / sub / "data" / Name(i, ext), drive / sub / "data" / Name(i, ext));
    }
  }
  for (const char* ts : {"velodyne_points/timestamps.txt", "velodyne_points/timestamps_start.txt",
                         "velodyne_points/timestamps_end.txt", "oxts/timestamps.txt"}) {
    auto lines = Lines(src / ts);
    lines.resize(n);
    WriteLines(drive / ts, lines);
  }
  fs::copy_file(src / "oxts/dataformat.txt", drive / "oxts/dataformat.txt");
  return drive;
}

using testing::LogCapture;

// ------------------------------------------------------------------------------------------------
// Real data.

TEST(KittiRawReaderRealTest, FiftyScansWithAllPointsAndTimes) {
  SLAM_MMS_REQUIRE_KITTI_RAW();
  const fs::path drive = testing::KittiRawDriveDir();
  auto reader = KittiRawReader::Open(drive);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ(reader->layout(), KittiRawLayout::kSync);
  ASSERT_EQ(reader->NumScans(), 50u);

  const auto trig = Lines(drive / "velodyne_points/timestamps.txt");
  const auto starts = Lines(drive / "velodyne_points/timestamps_start.txt");
  const auto ends = Lines(drive / "velodyne_points/timestamps_end.txt");
  Timestamp previous_start;
  for (size_t i = 0; i < reader->NumScans(); ++i) {
    SCOPED_TRACE("scan " + std::to_string(i));
    auto scan = reader->ReadScan(i);
    ASSERT_TRUE(scan.ok()) << scan.status().ToString();
    const fs::path file = drive / "velodyne_points/data" / Name(static_cast<int>(i), ".bin");
    const auto raw = ReadKittiScanFile(file);
    ASSERT_TRUE(raw.ok());
    size_t non_finite = 0;
    for (size_t k = 0; k < raw->size(); ++k) {
      if (!raw->points()[k].allFinite() || !std::isfinite(raw->intensities()[k])) ++non_finite;
    }
    EXPECT_EQ(raw->size(), fs::file_size(file) / 16);
    EXPECT_EQ(scan->cloud.size(), fs::file_size(file) / 16 - non_finite);
    EXPECT_GT(scan->cloud.size(), 100000u);
    EXPECT_EQ(scan->index, static_cast<int64_t>(i));
    EXPECT_EQ(scan->stamp_trigger, *ParseKittiTimestamp(trig[i]));
    EXPECT_EQ(scan->stamp_start, *ParseKittiTimestamp(starts[i]));
    EXPECT_EQ(scan->stamp_end, *ParseKittiTimestamp(ends[i]));
    EXPECT_LE(scan->stamp_start, scan->stamp_trigger);
    EXPECT_LE(scan->stamp_trigger, scan->stamp_end);
    if (i > 0) {
      EXPECT_GT(scan->stamp_start, previous_start);
    }
    previous_start = scan->stamp_start;
    const double duration = scan->DurationSeconds();
    EXPECT_GT(duration, 0.09);
    EXPECT_LT(duration, 0.12);
    ASSERT_EQ(scan->cloud.time_offsets_s().size(), scan->cloud.size());
    float t_min = 1e9f, t_max = -1e9f;
    for (size_t k = 0; k < scan->cloud.size(); ++k) {
      const float t = scan->cloud.time_offsets_s()[k];
      const Eigen::Vector3f& p = scan->cloud.points()[k];
      t_min = std::min(t_min, t);
      t_max = std::max(t_max, t);
      ASSERT_GE(t, 0.0f);
      ASSERT_LE(t, static_cast<float>(duration) * (1.0f + 1e-6f));
      // Clockwise: points straight ahead (x > 0, y ~ 0) at mid-scan.
      if (p.x() > 5.0f && std::abs(p.y()) < 0.01f * p.x()) {
        ASSERT_NEAR(t, 0.5 * duration, 0.01 * duration);
      }
    }
    // A full revolution covers the whole span.
    EXPECT_LT(t_min, 0.01 * duration);
    EXPECT_GT(t_max, 0.99 * duration);
  }
  EXPECT_EQ(reader->TotalDroppedPoints(), 0u);  // KITTI 0013's first 50 scans are all finite.
}

TEST(KittiRawReaderRealTest, OxtsRecordsGnssAndImu) {
  SLAM_MMS_REQUIRE_KITTI_RAW();
  const fs::path drive = testing::KittiRawDriveDir();
  auto reader = KittiRawReader::Open(drive);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  const auto& oxts = reader->OxtsRecords();
  ASSERT_EQ(oxts.size(), 50u);
  EXPECT_FALSE(reader->HasImu100Hz());
  ASSERT_EQ(reader->ImuOxtsRecords().size(), 50u);
  const auto stamps = Lines(drive / "oxts/timestamps.txt");
  const auto fixes = reader->GnssFixes();
  const auto imu = reader->ImuSamples();
  ASSERT_EQ(fixes.size(), 50u);
  ASSERT_EQ(imu.size(), 50u);

  // Record 0 field by field against the file's text.
  const auto line0 = Lines(drive / "oxts/data/0000000000.txt").at(0);
  std::istringstream is(line0);
  std::vector<double> values;
  double v;
  while (is >> v) values.push_back(v);
  ASSERT_EQ(values.size(), 30u);
  const auto arr = oxts[0].record.ToArray();
  for (int f = 0; f < 30; ++f) EXPECT_EQ(arr[f], values[f]) << OxtsRecord::FieldName(f);

  GeographicLib::LocalCartesian enu(fixes[0].latitude_deg, fixes[0].longitude_deg,
                                    fixes[0].height_m);
  Eigen::Vector2d integrated = Eigen::Vector2d::Zero();
  Eigen::Vector2d displacement = Eigen::Vector2d::Zero();
  for (size_t i = 0; i < oxts.size(); ++i) {
    SCOPED_TRACE("record " + std::to_string(i));
    const OxtsRecord& r = oxts[i].record;
    EXPECT_EQ(oxts[i].stamp, *ParseKittiTimestamp(stamps[i]));
    EXPECT_EQ(fixes[i].stamp, oxts[i].stamp);
    EXPECT_EQ(fixes[i].latitude_deg, r.lat_deg);
    EXPECT_EQ(fixes[i].longitude_deg, r.lon_deg);
    EXPECT_EQ(fixes[i].height_m, r.alt_m);
    EXPECT_EQ(fixes[i].sigma_horizontal_m, r.pos_accuracy_m);
    EXPECT_EQ(fixes[i].type, OxtsFixType(r));
    EXPECT_EQ(r.navstat, 4);
    EXPECT_NE(fixes[i].type, GnssFixType::kNone);
    EXPECT_EQ(imu[i].accel_mps2, Eigen::Vector3d(r.ax, r.ay, r.az));
    EXPECT_EQ(imu[i].gyro_radps, Eigen::Vector3d(r.wx, r.wy, r.wz));
    EXPECT_NEAR(imu[i].accel_mps2.z(), 9.8, 0.6);  // specific force, body z up
    // Attitude: the level-frame velocity (vf, vl) rotated by yaw is the ENU (ve, vn).
    const Eigen::Matrix3d R = OxtsAttitude(r);
    const Eigen::Vector3d v_enu(r.ve, r.vn, r.vu);
    const Eigen::Vector3d v_body = R.transpose() * v_enu;
    EXPECT_NEAR(v_body.x(), std::hypot(r.ve, r.vn), 0.05 * std::hypot(r.ve, r.vn) + 0.05);
    EXPECT_NEAR(v_body.y(), 0.0, 0.3);
    // Positions through GeographicLib (exact ENU about fix 0); velocity integrated below.
    if (i > 0) {
      double e0, n0, u0, e1, n1, u1;
      enu.Forward(fixes[i - 1].latitude_deg, fixes[i - 1].longitude_deg, fixes[i - 1].height_m, e0,
                  n0, u0);
      enu.Forward(fixes[i].latitude_deg, fixes[i].longitude_deg, fixes[i].height_m, e1, n1, u1);
      const double dt = fixes[i].stamp.SecondsSince(fixes[i - 1].stamp);
      const OxtsRecord& r0 = oxts[i - 1].record;
      integrated += Eigen::Vector2d(0.5 * (r.ve + r0.ve), 0.5 * (r.vn + r0.vn)) * dt;
      displacement = Eigen::Vector2d(e1, n1);
      // Round trip through GeographicLib within its precision (nanometres).
      double lat, lon, h;
      enu.Reverse(e1, n1, u1, lat, lon, h);
      EXPECT_NEAR(lat, fixes[i].latitude_deg, 1e-12);
      EXPECT_NEAR(lon, fixes[i].longitude_deg, 1e-12);
      EXPECT_NEAR(h, fixes[i].height_m, 1e-6);
    }
  }
  // East/north displacement over the 4.9 s (about 55 m) equals the integrated reported velocity.
  // Step by step they differ by up to 0.3 m/s (the 10 Hz stamps jitter by 10 ms against the
  // records), so compare over the whole span; a swapped axis or a unit error is metres off.
  EXPECT_GT(displacement.norm(), 40.0);
  EXPECT_LT((displacement - integrated).norm(), 0.02 * displacement.norm())
      << "displacement " << displacement.transpose() << " integrated " << integrated.transpose();
}

TEST(KittiRawReaderRealTest, CalibrationAsInTheFile) {
  SLAM_MMS_REQUIRE_KITTI_RAW();
  auto reader = KittiRawReader::Open(testing::KittiRawDriveDir());
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ(reader->calibration_file(),
            testing::KittiRawDriveDir().parent_path() / "calib_imu_to_velo.txt");
  // calib_imu_to_velo.txt of 2011_09_26 (7 digits).
  Eigen::Matrix3d R;
  R << 9.999976e-01, 7.553071e-04, -2.035826e-03, -7.854027e-04, 9.998898e-01, -1.482298e-02,
      2.024406e-03, 1.482454e-02, 9.998881e-01;
  const Eigen::Vector3d T(-8.086759e-01, 3.195559e-01, -7.997231e-01);
  const Eigen::Isometry3d& T_lidar_body = reader->T_lidar_body();
  EXPECT_LT((T_lidar_body.linear() - R).cwiseAbs().maxCoeff(), 2e-6);
  EXPECT_EQ(T_lidar_body.translation(), T);
  // Projected onto SO(3).
  EXPECT_LT(
      (T_lidar_body.linear().transpose() * T_lidar_body.linear() - Eigen::Matrix3d::Identity())
          .cwiseAbs()
          .maxCoeff(),
      1e-12);
  EXPECT_NEAR(T_lidar_body.linear().determinant(), 1.0, 1e-12);
  EXPECT_TRUE(reader->T_body_lidar().isApprox(T_lidar_body.inverse()));
}

TEST(KittiRawReaderRealTest, FrameRangeAndOptions) {
  SLAM_MMS_REQUIRE_KITTI_RAW();
  KittiRawReader::Options options;
  options.first_frame = 10;
  options.last_frame = 19;
  auto reader = KittiRawReader::Open(testing::KittiRawDriveDir(), options);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  ASSERT_EQ(reader->NumScans(), 10u);
  EXPECT_EQ(reader->FrameIndex(0), 10);
  ASSERT_EQ(reader->OxtsRecords().size(), 10u);
  EXPECT_EQ(reader->OxtsRecords()[0].index, 10);
  auto scan = reader->ReadScan(0);
  ASSERT_TRUE(scan.ok());
  EXPECT_EQ(scan->index, 10);
  EXPECT_EQ(reader->ReadScan(10).status().code(), StatusCode::kOutOfRange);

  // Counter-clockwise gives t' = duration - t; vertical correction raises every point by 0.205 deg.
  KittiRawReader::Options other = options;
  other.spin = SpinDirection::kCounterClockwise;
  other.vertical_angle_correction = true;
  auto reader2 = KittiRawReader::Open(testing::KittiRawDriveDir(), other);
  ASSERT_TRUE(reader2.ok());
  auto scan2 = reader2->ReadScan(0);
  ASSERT_TRUE(scan2.ok());
  ASSERT_EQ(scan2->cloud.size(), scan->cloud.size());
  const double duration = scan->DurationSeconds();
  const double angle = 0.205 * M_PI / 180.0;
  for (size_t k = 0; k < scan->cloud.size(); k += 97) {
    const Eigen::Vector3d p = scan->cloud.points()[k].cast<double>();
    const Eigen::Vector3d q = scan2->cloud.points()[k].cast<double>();
    const double tp = scan->cloud.time_offsets_s()[k];
    const double tq = scan2->cloud.time_offsets_s()[k];
    // At exactly +-pi the two conventions both give 0 or 1; allow the seam.
    if (std::abs(std::atan2(p.y(), p.x())) < M_PI - 1e-3) {
      ASSERT_NEAR(tp + tq, duration, 1e-6);
    }
    ASSERT_NEAR(q.norm(), p.norm(), 1e-5);
    const double elev_p = std::atan2(p.z(), p.head<2>().norm());
    const double elev_q = std::atan2(q.z(), q.head<2>().norm());
    if (p.head<2>().norm() > 1.0) {
      ASSERT_NEAR(elev_q - elev_p, angle, 2e-6);
    }
    ASSERT_NEAR(std::atan2(q.y(), q.x()), std::atan2(p.y(), p.x()), 1e-5);
  }

  KittiRawReader::Options no_time = options;
  no_time.per_point_time = false;
  auto reader3 = KittiRawReader::Open(testing::KittiRawDriveDir(), no_time);
  ASSERT_TRUE(reader3.ok());
  auto scan3 = reader3->ReadScan(0);
  ASSERT_TRUE(scan3.ok());
  for (const float t : scan3->cloud.time_offsets_s()) ASSERT_EQ(t, 0.0f);

  KittiRawReader::Options outside;
  outside.first_frame = 45;
  outside.last_frame = 50;
  auto bad = KittiRawReader::Open(testing::KittiRawDriveDir(), outside);
  EXPECT_EQ(bad.status().code(), StatusCode::kOutOfRange);
  EXPECT_THAT(bad.status().message(), HasSubstr("frames [0, 49]"));
  outside.first_frame = 60;
  outside.last_frame = -1;
  EXPECT_EQ(KittiRawReader::Open(testing::KittiRawDriveDir(), outside).status().code(),
            StatusCode::kOutOfRange);
}

TEST(KittiRawReaderOptionsTest, ValidateNamesTheField) {
  KittiRawReader::Options o;
  EXPECT_TRUE(o.Validate().ok());
  o.first_frame = -2;
  EXPECT_THAT(o.Validate().message(), HasSubstr("Options::first_frame = -2"));
  o = {};
  o.first_frame = 5;
  o.last_frame = 3;
  EXPECT_THAT(o.Validate().message(), HasSubstr("Options::last_frame = 3"));
  o = {};
  o.imu_time_margin_s = -1.0;
  EXPECT_THAT(o.Validate().message(), HasSubstr("imu_time_margin_s"));
  EXPECT_EQ(KittiRawReader::Open("/nonexistent/drive").status().code(), StatusCode::kNotFound);
}

TEST(KittiRawReaderTest, AzimuthFraction) {
  EXPECT_NEAR(KittiAzimuthFraction(1, 0, SpinDirection::kClockwise), 0.5, 1e-15);
  EXPECT_NEAR(KittiAzimuthFraction(0, 1, SpinDirection::kClockwise), 0.25, 1e-15);   // left
  EXPECT_NEAR(KittiAzimuthFraction(0, -1, SpinDirection::kClockwise), 0.75, 1e-15);  // right
  EXPECT_NEAR(KittiAzimuthFraction(-1, 1e-9, SpinDirection::kClockwise), 0.0, 1e-9);
  EXPECT_NEAR(KittiAzimuthFraction(-1, -1e-9, SpinDirection::kClockwise), 1.0, 1e-9);
  EXPECT_NEAR(KittiAzimuthFraction(0, 1, SpinDirection::kCounterClockwise), 0.75, 1e-15);
}

// ------------------------------------------------------------------------------------------------
// Malformed copies.

class KittiRawMalformedTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!testing::HasKittiRaw()) GTEST_SKIP() << "real KITTI data not found";
    tmp_ = testing::MakeTempDir("kitti_malformed");
    drive_ = MakeMiniDrive(tmp_, 3);
  }
  void TearDown() override {
    if (!tmp_.empty()) fs::remove_all(tmp_);
  }
  fs::path tmp_;
  fs::path drive_;
};

TEST_F(KittiRawMalformedTest, IntactCopyReads) {
  auto reader = KittiRawReader::Open(drive_);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ(reader->NumScans(), 3u);
  for (size_t i = 0; i < 3; ++i) EXPECT_TRUE(reader->ReadScan(i).ok());
}

TEST_F(KittiRawMalformedTest, TruncatedBin) {
  const fs::path bin = drive_ / "velodyne_points/data/0000000001.bin";
  const auto size = fs::file_size(bin);
  fs::resize_file(bin, size - 5);
  auto reader = KittiRawReader::Open(drive_);
  ASSERT_TRUE(reader.ok());
  EXPECT_TRUE(reader->ReadScan(0).ok());
  const auto s = reader->ReadScan(1).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(bin.string()), HasSubstr(std::to_string(size - 5)),
                                 HasSubstr("not a multiple of 16")));
}

TEST_F(KittiRawMalformedTest, EmptyScan) {
  const fs::path bin = drive_ / "velodyne_points/data/0000000002.bin";
  fs::resize_file(bin, 0);
  auto reader = KittiRawReader::Open(drive_);
  ASSERT_TRUE(reader.ok());
  const auto s = reader->ReadScan(2).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(bin.string()), HasSubstr("no points")));
}

TEST_F(KittiRawMalformedTest, NonFinitePointsDroppedCountedAndLogged) {
  const fs::path bin = drive_ / "velodyne_points/data/0000000000.bin";
  const auto n = fs::file_size(bin) / 16;
  {
    std::fstream f(bin, std::ios::in | std::ios::out | std::ios::binary);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    f.seekp(16 * 10);
    f.write(reinterpret_cast<const char*>(&nan), 4);  // x of point 10
    f.seekp(16 * 20 + 8);
    f.write(reinterpret_cast<const char*>(&inf), 4);  // z of point 20
    f.seekp(16 * 30 + 12);
    f.write(reinterpret_cast<const char*>(&nan), 4);  // reflectance of point 30
  }
  LogCapture log;
  auto reader = KittiRawReader::Open(drive_);
  ASSERT_TRUE(reader.ok());
  auto scan = reader->ReadScan(0);
  ASSERT_TRUE(scan.ok()) << scan.status().ToString();
  EXPECT_EQ(scan->cloud.size(), n - 3);
  EXPECT_EQ(reader->TotalDroppedPoints(), 3u);
  for (size_t k = 0; k < scan->cloud.size(); ++k) {
    ASSERT_TRUE(scan->cloud.points()[k].allFinite());
    ASSERT_TRUE(std::isfinite(scan->cloud.intensities()[k]));
  }
  EXPECT_THAT(log.messages(), AllOf(HasSubstr("dropped 3 of"), HasSubstr(bin.string())));
}

TEST_F(KittiRawMalformedTest, BadOxtsNumber) {
  const fs::path file = drive_ / "oxts/data/0000000001.txt";
  auto lines = Lines(file);
  std::istringstream is(lines[0]);
  std::vector<std::string> tok;
  std::string t;
  while (is >> t) tok.push_back(t);
  tok[6] = "1.2.3";  // vn
  std::string line;
  for (const auto& s : tok) line += s + " ";
  WriteLines(file, {line});
  const auto s = KittiRawReader::Open(drive_).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(file.string() + ":1"), HasSubstr("field 7 (vn)"),
                                 HasSubstr("1.2.3")));
}

TEST_F(KittiRawMalformedTest, OxtsLineWith29Numbers) {
  const fs::path file = drive_ / "oxts/data/0000000002.txt";
  auto lines = Lines(file);
  const auto cut = lines[0].find_last_of(' ');
  WriteLines(file, {lines[0].substr(0, cut)});
  const auto s = KittiRawReader::Open(drive_).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(file.string() + ":1"), HasSubstr("has 29 numbers"),
                                 HasSubstr("field 30 (orimode) is missing")));
}

TEST_F(KittiRawMalformedTest, BackwardsTimestamp) {
  const fs::path file = drive_ / "velodyne_points/timestamps_start.txt";
  auto lines = Lines(file);
  std::swap(lines[1], lines[2]);
  WriteLines(file, lines);
  const auto s = KittiRawReader::Open(drive_).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(file.string() + ":3"), HasSubstr("goes backwards"),
                                 HasSubstr(lines[2])));
}

TEST_F(KittiRawMalformedTest, DuplicatedOxtsTimestamp) {
  const fs::path file = drive_ / "oxts/timestamps.txt";
  auto lines = Lines(file);
  lines[2] = lines[1];
  WriteLines(file, lines);
  const auto s = KittiRawReader::Open(drive_).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(file.string() + ":3"), HasSubstr("duplicated")));
}

TEST_F(KittiRawMalformedTest, UnparsableTimestamp) {
  const fs::path file = drive_ / "velodyne_points/timestamps.txt";
  auto lines = Lines(file);
  lines[1] = "2011-09-26 13:10:5x.261567322";
  WriteLines(file, lines);
  const auto s = KittiRawReader::Open(drive_).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), AllOf(HasSubstr(file.string() + ":2"), HasSubstr("second")));
}

TEST_F(KittiRawMalformedTest, MissingCalibration) {
  fs::remove(drive_.parent_path() / "calib_imu_to_velo.txt");
  const auto s = KittiRawReader::Open(drive_).status();
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_THAT(s.message(), HasSubstr("calib_imu_to_velo.txt not found"));
  KittiRawReader::Options o;
  o.allow_missing_calibration = true;
  auto reader = KittiRawReader::Open(drive_, o);
  ASSERT_TRUE(reader.ok());
  EXPECT_TRUE(reader->T_lidar_body().isApprox(Eigen::Isometry3d::Identity()));
}

TEST_F(KittiRawMalformedTest, BadCalibrationLine) {
  const fs::path file = drive_.parent_path() / "calib_imu_to_velo.txt";
  auto lines = Lines(file);
  lines[1] = "R: 9.999976e-01 7.553071e-04 -2.035826e-03 -7.854027e-04 9.998898e-01";
  WriteLines(file, lines);
  auto s = KittiRawReader::Open(drive_).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(),
              AllOf(HasSubstr(file.string() + ":2"), HasSubstr("key R has 5 numbers")));
  lines[1] = "R: 1 0 0 0 1 0 0 0 1";
  lines[2] = "T: 0.1 abc 0.3";
  WriteLines(file, lines);
  s = KittiRawReader::Open(drive_).status();
  EXPECT_THAT(s.message(),
              AllOf(HasSubstr(file.string() + ":3"), HasSubstr("key T value 2"), HasSubstr("abc")));
  lines[1] = "R: 1 0 0 0 1 0 0 0 2";
  lines[2] = "T: 0 0 0";
  WriteLines(file, lines);
  s = KittiRawReader::Open(drive_).status();
  EXPECT_THAT(s.message(), HasSubstr("not a rotation"));
  WriteLines(file, {lines[0], "R: 1 0 0 0 1 0 0 0 1"});
  s = KittiRawReader::Open(drive_).status();
  EXPECT_THAT(s.message(), HasSubstr("key T (3 numbers) missing"));
}

TEST_F(KittiRawMalformedTest, MissingScanFileAndCountMismatch) {
  fs::remove(drive_ / "velodyne_points/data/0000000001.bin");
  auto s = KittiRawReader::Open(drive_).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), HasSubstr("2 scan files but timestamps.txt has 3 lines"));
}

TEST_F(KittiRawMalformedTest, OxtsCountMismatch) {
  auto lines = Lines(drive_ / "oxts/timestamps.txt");
  lines.pop_back();
  WriteLines(drive_ / "oxts/timestamps.txt", lines);
  fs::remove(drive_ / "oxts/data/0000000002.txt");
  auto s = KittiRawReader::Open(drive_).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), HasSubstr("2 lines but the drive has 3 scans"));
}

TEST_F(KittiRawMalformedTest, EndBeforeStart) {
  const fs::path file = drive_ / "velodyne_points/timestamps_end.txt";
  auto ends = Lines(file);
  const auto starts = Lines(drive_ / "velodyne_points/timestamps_start.txt");
  ends[0] = starts[0];
  WriteLines(file, ends);
  auto s = KittiRawReader::Open(drive_).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(),
              AllOf(HasSubstr(file.string() + ":1"), HasSubstr("not after its start")));
}

}  // namespace
}  // namespace slam_mms
