// KittiRawWriter -> KittiRawReader round trips (sync layout with oxts_100hz/), writer validation,
// and the extract layout (text scans, 100 Hz OXTS with lost records).
#include "slam_mms/io/kitti_raw_writer.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <random>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

const Timestamp kT0 = Timestamp::FromNanoseconds(1317042651106324297LL);

OxtsRecord RandomRecord(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::array<double, OxtsRecord::kNumFields> v{};
  for (int i = 0; i < 25; ++i) v[i] = u(rng) * 10.0;
  v[0] = 49.0 + 0.01 * u(rng);
  v[1] = 8.4 + 0.01 * u(rng);
  v[25] = 4;
  v[26] = 8;
  v[27] = 6;
  v[28] = 6;
  v[29] = 0;
  return OxtsRecord::FromArray(v);
}

Scan RandomScan(std::mt19937_64& rng, int i, size_t n) {
  std::uniform_real_distribution<float> u(-50.0f, 50.0f);
  std::uniform_real_distribution<float> r(0.0f, 1.0f);
  Scan scan;
  scan.stamp_start = kT0.PlusSeconds(0.1036 * i);
  scan.stamp_end = scan.stamp_start.PlusSeconds(0.1035);
  for (size_t k = 0; k < n; ++k) scan.cloud.Add(Eigen::Vector3f(u(rng), u(rng), u(rng)), r(rng));
  return scan;
}

Eigen::Isometry3d RandomRigid(std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 0.5);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = so3::Exp(Eigen::Vector3d(g(rng), g(rng), g(rng)));
  T.translation() = Eigen::Vector3d(g(rng), g(rng), g(rng));
  return T;
}

TEST(KittiRawWriterTest, RoundTripThroughReader) {
  const fs::path tmp = testing::MakeTempDir("kitti_writer");
  const fs::path drive = tmp / "2011_01_01" / "2011_01_01_drive_0001_sync";
  std::mt19937_64 rng(11);
  constexpr int kScans = 5;
  std::vector<Scan> scans;
  std::vector<OxtsRecord> oxts, imu;
  std::vector<Timestamp> imu_stamps;
  const Eigen::Isometry3d T_lidar_body = RandomRigid(rng);
  {
    auto writer = KittiRawWriter::Create(drive.string() + "/");
    ASSERT_TRUE(writer.ok()) << writer.status().ToString();
    EXPECT_EQ(writer->drive_dir(), drive);
    ASSERT_TRUE(writer->WriteCalibration(T_lidar_body).ok());
    // 100 Hz IMU from 2 s before to 2 s after the scans (the reader keeps +- 1 s).
    for (int k = -200; k < 10 * kScans + 200; ++k) {
      imu_stamps.push_back(kT0.PlusSeconds(0.01 * k + 0.0003));
      imu.push_back(RandomRecord(rng));
      ASSERT_TRUE(writer->AddImuOxts(imu_stamps.back(), imu.back()).ok());
    }
    for (int i = 0; i < kScans; ++i) {
      scans.push_back(RandomScan(rng, i, 1000 + 10 * i));
      ASSERT_TRUE(writer->AddScan(scans.back()).ok());
      oxts.push_back(RandomRecord(rng));
      ASSERT_TRUE(writer->AddOxts(scans.back().stamp_start.PlusSeconds(0.05), oxts.back()).ok());
    }
    EXPECT_EQ(writer->NumScans(), 5u);
    EXPECT_EQ(writer->NumOxts(), 5u);
    ASSERT_TRUE(writer->Finish().ok());
    EXPECT_FALSE(writer->AddScan(scans[0]).ok());  // after Finish
  }
  EXPECT_TRUE(fs::exists(drive.parent_path() / "calib_velo_to_cam.txt"));
  EXPECT_TRUE(fs::exists(drive.parent_path() / "calib_cam_to_cam.txt"));
  EXPECT_TRUE(fs::exists(drive / "oxts/dataformat.txt"));
  EXPECT_TRUE(fs::exists(drive / "oxts_100hz/dataformat.txt"));
  EXPECT_EQ(fs::file_size(drive / "velodyne_points/data/0000000002.bin"), 16u * 1020u);

  // A trailing separator still finds the calibration in the parent folder.
  auto reader = KittiRawReader::Open(drive.string() + "/");
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ(reader->calibration_file(), drive.parent_path() / "calib_imu_to_velo.txt");
  EXPECT_EQ(reader->layout(), KittiRawLayout::kSync);
  ASSERT_EQ(reader->NumScans(), static_cast<size_t>(kScans));
  EXPECT_TRUE(reader->T_lidar_body().isApprox(T_lidar_body, 1e-8));
  for (int i = 0; i < kScans; ++i) {
    auto scan = reader->ReadScan(i);
    ASSERT_TRUE(scan.ok()) << scan.status().ToString();
    const Scan& w = scans[i];
    EXPECT_EQ(scan->stamp_start, w.stamp_start);
    EXPECT_EQ(scan->stamp_end, w.stamp_end);
    EXPECT_EQ(scan->stamp_trigger.nanoseconds(),
              (w.stamp_start.nanoseconds() + w.stamp_end.nanoseconds()) / 2);
    ASSERT_EQ(scan->cloud.size(), w.cloud.size());
    EXPECT_EQ(std::memcmp(scan->cloud.points().data(), w.cloud.points().data(),
                          w.cloud.size() * sizeof(Eigen::Vector3f)),
              0);
    EXPECT_EQ(scan->cloud.intensities(), w.cloud.intensities());
    for (size_t k = 0; k < w.cloud.size(); ++k) {
      const Eigen::Vector3f& p = w.cloud.points()[k];
      ASSERT_NEAR(scan->cloud.time_offsets_s()[k],
                  KittiAzimuthFraction(p.x(), p.y(), SpinDirection::kClockwise) * 0.1035, 1e-7);
    }
  }
  ASSERT_EQ(reader->OxtsRecords().size(), static_cast<size_t>(kScans));
  for (int i = 0; i < kScans; ++i) {
    EXPECT_EQ(reader->OxtsRecords()[i].stamp, scans[i].stamp_start.PlusSeconds(0.05));
    const auto a = reader->OxtsRecords()[i].record.ToArray();
    const auto b = oxts[i].ToArray();
    EXPECT_EQ(std::memcmp(a.data(), b.data(), sizeof(a)), 0);
  }
  EXPECT_TRUE(reader->HasImu100Hz());
  // Kept: stamps within [first start - 1 s, last end + 1 s].
  const Timestamp lo = scans.front().stamp_start.PlusSeconds(-1.0);
  const Timestamp hi = scans.back().stamp_end.PlusSeconds(1.0);
  std::vector<size_t> expected;
  for (size_t k = 0; k < imu_stamps.size(); ++k) {
    if (imu_stamps[k] >= lo && imu_stamps[k] <= hi) expected.push_back(k);
  }
  ASSERT_EQ(reader->ImuOxtsRecords().size(), expected.size());
  const auto samples = reader->ImuSamples();
  ASSERT_EQ(samples.size(), expected.size());
  for (size_t j = 0; j < expected.size(); ++j) {
    const auto& rec = reader->ImuOxtsRecords()[j];
    EXPECT_EQ(rec.stamp, imu_stamps[expected[j]]);
    EXPECT_EQ(rec.index, static_cast<int64_t>(expected[j]));
    EXPECT_EQ(samples[j].accel_mps2.z(), imu[expected[j]].az);
    EXPECT_EQ(samples[j].gyro_radps.x(), imu[expected[j]].wx);
  }
  const auto fixes = reader->GnssFixes();
  ASSERT_EQ(fixes.size(), static_cast<size_t>(kScans));
  EXPECT_EQ(fixes[0].type, GnssFixType::kRtkFixed);
  fs::remove_all(tmp);
}

TEST(KittiRawWriterTest, ValidatesInput) {
  const fs::path tmp = testing::MakeTempDir("kitti_writer_bad");
  const fs::path drive = tmp / "d" / "drive";
  std::mt19937_64 rng(5);
  auto writer = KittiRawWriter::Create(drive);
  ASSERT_TRUE(writer.ok());
  Scan s0 = RandomScan(rng, 0, 10);
  ASSERT_TRUE(writer->AddScan(s0).ok());
  EXPECT_THAT(writer->AddScan(s0).message(), HasSubstr("not after the previous scan"));
  Scan s1 = RandomScan(rng, 1, 10);
  s1.stamp_end = s1.stamp_start;
  EXPECT_THAT(writer->AddScan(s1).message(), HasSubstr("not after stamp_start"));
  s1 = RandomScan(rng, 1, 10);
  s1.cloud.points()[3].y() = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THAT(writer->AddScan(s1).message(), HasSubstr("point 3 is not finite"));
  s1 = RandomScan(rng, 1, 10);
  s1.stamp_trigger = s1.stamp_end.PlusSeconds(0.01);
  EXPECT_THAT(writer->AddScan(s1).message(), HasSubstr("outside [stamp_start, stamp_end]"));
  s1.cloud.clear();
  s1.stamp_trigger = Timestamp();
  EXPECT_THAT(writer->AddScan(s1).message(), HasSubstr("no points"));
  Eigen::Isometry3d bad = Eigen::Isometry3d::Identity();
  bad.linear() *= 2.0;
  EXPECT_FALSE(writer->WriteCalibration(bad).ok());
  OxtsRecord r = RandomRecord(rng);
  ASSERT_TRUE(writer->AddOxts(kT0, r).ok());
  EXPECT_THAT(writer->AddOxts(kT0, r).message(), HasSubstr("not after the previous record"));
  ASSERT_TRUE(writer->AddScan(RandomScan(rng, 1, 10)).ok());
  // 2 scans, 1 OXTS record.
  const Status finish = writer->Finish();
  EXPECT_EQ(finish.code(), StatusCode::kFailedPrecondition);
  EXPECT_THAT(finish.message(), HasSubstr("1 OXTS records for 2 scans"));
  // Existing non-empty folder.
  auto again = KittiRawWriter::Create(drive);
  EXPECT_EQ(again.status().code(), StatusCode::kInvalidArgument);
  KittiRawWriter::Options o;
  o.overwrite = true;
  again = KittiRawWriter::Create(drive, o);
  ASSERT_TRUE(again.ok());
  EXPECT_FALSE(fs::exists(drive / "velodyne_points/data/0000000000.bin"));
  fs::remove_all(tmp);
}

TEST(KittiRawWriterTest, DriveWithoutOxtsReads) {
  const fs::path tmp = testing::MakeTempDir("kitti_writer_nooxts");
  const fs::path drive = tmp / "d" / "drive";
  std::mt19937_64 rng(9);
  {
    auto writer = KittiRawWriter::Create(drive);
    ASSERT_TRUE(writer.ok());
    ASSERT_TRUE(writer->WriteCalibration(Eigen::Isometry3d::Identity()).ok());
    for (int i = 0; i < 3; ++i) ASSERT_TRUE(writer->AddScan(RandomScan(rng, i, 50)).ok());
  }  // the destructor finishes
  auto reader = KittiRawReader::Open(drive);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ(reader->NumScans(), 3u);
  EXPECT_TRUE(reader->OxtsRecords().empty());
  EXPECT_TRUE(reader->ImuSamples().empty());
  fs::remove_all(tmp);
}

// Extract layout: text scans, 100 Hz OXTS at irregular times with lost records (blank lines).
TEST(KittiRawReaderExtractTest, TextScansAndIrregularOxts) {
  const fs::path tmp = testing::MakeTempDir("kitti_extract");
  const fs::path drive = tmp / "2011_09_26_drive_0001_extract";
  fs::create_directories(drive / "velodyne_points/data");
  fs::create_directories(drive / "oxts/data");
  {
    std::ofstream calib(drive / "calib_imu_to_velo.txt");  // in the drive folder itself
    calib << "calib_time: x\nR: 1 0 0 0 1 0 0 0 1\nT: -0.81 0.32 -0.80\n";
  }
  std::ofstream ts(drive / "velodyne_points/timestamps.txt");
  std::ofstream ts_start(drive / "velodyne_points/timestamps_start.txt");
  std::ofstream ts_end(drive / "velodyne_points/timestamps_end.txt");
  for (int i = 0; i < 4; ++i) {
    const Timestamp s = kT0.PlusSeconds(0.1 * i);
    if (i == 2) {  // lost scan: blank lines
      ts << "\n";
      ts_start << "\n";
      ts_end << "\n";
      continue;
    }
    ts << s.PlusSeconds(0.05).ToKittiString() << "\n";
    ts_start << s.ToKittiString() << "\n";
    ts_end << s.PlusSeconds(0.1).ToKittiString() << "\n";
    char name[64];
    std::snprintf(name, sizeof(name), "%010d.txt", i);
    std::ofstream scan(drive / "velodyne_points/data" / name);
    scan << "1.5 0.0 -0.5 0.25\n-2.0 1e-3 0.1 0.5\n\n0 -3 1 0.75\n";
  }
  ts.close();
  ts_start.close();
  ts_end.close();
  std::ofstream ots(drive / "oxts/timestamps.txt");
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> jitter(-0.002, 0.002);
  int written = 0;
  for (int k = 0; k < 300; ++k) {
    const double t = -1.5 + 0.01 * k + jitter(rng) + (k > 150 ? 0.3 : 0.0);  // a 0.3 s gap
    if (k % 17 == 5) {                                                       // lost record
      ots << "\n";
      continue;
    }
    ots << kT0.PlusSeconds(t).ToKittiString() << "\n";
    char name[64];
    std::snprintf(name, sizeof(name), "%010d.txt", k);
    OxtsRecord r = RandomRecord(rng);
    r.az = k;  // marks the record
    std::ofstream(drive / "oxts/data" / name) << FormatOxtsLine(r) << "\n";
    ++written;
  }
  ots.close();

  auto reader = KittiRawReader::Open(drive);
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  EXPECT_EQ(reader->layout(), KittiRawLayout::kExtract);
  ASSERT_EQ(reader->NumScans(), 3u);
  EXPECT_EQ(reader->FrameIndex(2), 3);
  EXPECT_EQ(reader->calibration_file(), drive / "calib_imu_to_velo.txt");
  EXPECT_EQ(reader->T_lidar_body().translation(), Eigen::Vector3d(-0.81, 0.32, -0.80));
  auto scan = reader->ReadScan(2);
  ASSERT_TRUE(scan.ok()) << scan.status().ToString();
  EXPECT_EQ(scan->index, 3);
  ASSERT_EQ(scan->cloud.size(), 3u);
  EXPECT_EQ(scan->cloud.points()[1], Eigen::Vector3f(-2.0f, 1e-3f, 0.1f));
  EXPECT_EQ(scan->cloud.intensities()[2], 0.75f);
  EXPECT_NEAR(scan->cloud.time_offsets_s()[0], 0.05, 1e-7);   // straight ahead: mid-scan
  EXPECT_NEAR(scan->cloud.time_offsets_s()[2], 0.075, 1e-7);  // right: 3/4
  // OXTS: 100 Hz within [first start - 1 s, last end + 1 s], lost ones skipped, in order.
  const auto& recs = reader->OxtsRecords();
  ASSERT_GT(recs.size(), 100u);
  EXPECT_EQ(reader->ImuOxtsRecords().size(), recs.size());
  EXPECT_FALSE(reader->HasImu100Hz());
  const Timestamp lo = kT0.PlusSeconds(-1.0);
  const Timestamp hi = kT0.PlusSeconds(0.3 + 0.1 + 1.0);
  for (size_t j = 0; j < recs.size(); ++j) {
    EXPECT_GE(recs[j].stamp, lo);
    EXPECT_LE(recs[j].stamp, hi);
    EXPECT_NE(recs[j].index % 17, 5);
    EXPECT_EQ(recs[j].record.az, static_cast<double>(recs[j].index));
    if (j > 0) {
      EXPECT_GT(recs[j].stamp, recs[j - 1].stamp);
    }
  }
  // A text scan with a bad number names the line and field.
  std::ofstream(drive / "velodyne_points/data/0000000001.txt") << "1 2 3 0.5\n1 2 x 0.5\n";
  const auto s = reader->ReadScan(1).status();
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_THAT(s.message(), HasSubstr("0000000001.txt:2: field 3 (z)"));
  fs::remove_all(tmp);
}

}  // namespace
}  // namespace slam_mms
