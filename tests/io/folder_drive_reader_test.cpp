// FolderDriveReader + WriteDriveFolder: KITTI raw -> folder -> reader round trips (every scan
// format, CSV and NMEA GNSS, with and without a time field) on a synthetic drive and on the real
// KITTI frames; the real third-party PCD drive 0048; the format details (PCD/PLY variants, NMEA
// epochs, extrinsics forms, CSV optional columns). Malformed inputs: folder_malformed_test.cpp.
#include "slam_mms/io/folder_drive_reader.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "io/drive_folder_parsers.hpp"
#include "io/folder_test_util.hpp"
#include "io/nmea.hpp"
#include "slam_mms/io/drive_folder_writer.hpp"
#include "slam_mms/io/extrinsics_yaml.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "slam_mms/io/kitti_timestamp.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using Format = FolderWriteOptions::ScanFormat;
using Gnss = FolderWriteOptions::GnssFormat;

std::string FormatName(Format f) {
  switch (f) {
    case Format::kPcdBinary: return "pcd_binary";
    case Format::kPcdAscii: return "pcd_ascii";
    case Format::kPlyBinary: return "ply_binary";
    case Format::kPlyAscii: return "ply_ascii";
    default: return "bin";
  }
}

std::unique_ptr<FolderDriveReader> OpenFolder(const fs::path& dir,
                                              const FolderDriveReader::Options& options = {}) {
  auto r = FolderDriveReader::Open(dir, options);
  EXPECT_TRUE(r.ok()) << r.status().ToString();
  return r.ok() ? std::move(r).value() : nullptr;
}

// KITTI raw -> folder in every format -> FolderDriveReader: the same scans bit for bit (the
// azimuth time re-derived, or the written t field), IMU, GNSS, calibration and initial state.
void RoundTrip(const DriveReader& kitti, const fs::path& tmp, const std::vector<Format>& formats) {
  for (const Format format : formats) {
    for (const Gnss gnss : {Gnss::kCsv, Gnss::kNmea}) {
      for (const bool with_time : {false, true}) {
        if (format == Format::kBin && with_time) continue;
        if (gnss == Gnss::kNmea && with_time) continue;  // the GNSS path does not depend on it
        const std::string name =
            FormatName(format) + (gnss == Gnss::kNmea ? "_nmea" : "_csv") + (with_time ? "_t" : "");
        SCOPED_TRACE(name);
        FolderWriteOptions o;
        o.scan_format = format;
        o.gnss_format = gnss;
        o.write_point_time = with_time;
        const fs::path dir = tmp / name;
        ASSERT_TRUE(WriteDriveFolder(kitti, dir, o).ok());
        const auto folder = OpenFolder(dir);
        ASSERT_NE(folder, nullptr);
        EXPECT_EQ(folder->Describe(), "folder " + dir.string());
        testing::ExpectSameScans(kitti, *folder);
        testing::ExpectSameImu(kitti.streams(), folder->streams());
        if (gnss == Gnss::kCsv) {
          testing::ExpectSameGnssExactly(kitti.streams(), folder->streams());
        } else {
          testing::ExpectSameGnssNmea(kitti.streams(), folder->streams(), 500000);
          EXPECT_EQ(folder->num_bad_nmea_sentences(), 0u);
        }
        testing::ExpectSameCalibrationAndInitialState(kitti.streams(), folder->streams());
        EXPECT_EQ(folder->TotalDroppedPoints(), 0u);
      }
    }
  }
}

const std::vector<Format> kAllFormats = {Format::kPcdBinary, Format::kPcdAscii, Format::kPlyBinary,
                                         Format::kPlyAscii, Format::kBin};

TEST(FolderDriveReaderTest, SyntheticKittiRoundTripEveryFormat) {
  const fs::path tmp = testing::MakeTempDir("folder_roundtrip");
  const fs::path drive = testing::WriteSyntheticKittiDrive(tmp, 4, 3000);
  auto kitti = KittiDriveReader::Open(drive, KittiRawReader::Options());
  ASSERT_TRUE(kitti.ok()) << kitti.status().ToString();
  ASSERT_EQ((*kitti)->NumScans(), 4u);
  ASSERT_GT((*kitti)->streams().imu.size(), 40u);
  RoundTrip(**kitti, tmp, kAllFormats);
  fs::remove_all(tmp);
}

TEST(FolderDriveReaderTest, OptionsApplyAsForKitti) {
  // Frame range, counter-clockwise spin, vertical correction, no per-point time: the folder gives
  // what KittiRawReader gives with the same options.
  const fs::path tmp = testing::MakeTempDir("folder_options");
  const fs::path drive = testing::WriteSyntheticKittiDrive(tmp, 5, 500);
  auto plain = KittiDriveReader::Open(drive, KittiRawReader::Options());
  ASSERT_TRUE(plain.ok());
  ASSERT_TRUE(WriteDriveFolder(**plain, tmp / "f", FolderWriteOptions()).ok());
  KittiRawReader::Options ko;
  ko.first_frame = 1;
  ko.last_frame = 3;
  ko.spin = SpinDirection::kCounterClockwise;
  ko.vertical_angle_correction = true;
  FolderDriveReader::Options fo;
  fo.first_frame = 1;
  fo.last_frame = 3;
  fo.spin = SpinDirection::kCounterClockwise;
  fo.vertical_angle_correction = true;
  auto kitti = KittiDriveReader::Open(drive, ko);
  ASSERT_TRUE(kitti.ok());
  const auto folder = OpenFolder(tmp / "f", fo);
  ASSERT_NE(folder, nullptr);
  testing::ExpectSameScans(**kitti, *folder);
  ko.per_point_time = false;
  fo.per_point_time = false;
  kitti = KittiDriveReader::Open(drive, ko);
  ASSERT_TRUE(kitti.ok());
  testing::ExpectSameScans(**kitti, *OpenFolder(tmp / "f", fo));
  EXPECT_FALSE(FolderDriveReader::Open(tmp / "f",
                                       [] {
                                         FolderDriveReader::Options o;
                                         o.last_frame = 9;
                                         return o;
                                       }())
                   .ok());
  FolderDriveReader::Options bad;
  bad.nmea_utc_date = "2011-02-30";
  EXPECT_THAT(bad.Validate().message(), HasSubstr("nmea_utc_date"));
  fs::remove_all(tmp);
}

TEST(FolderDriveReaderTest, RealKittiRoundTripAndReadSpeed) {
  SLAM_MMS_REQUIRE_KITTI_RAW();
  const fs::path tmp = testing::MakeTempDir("folder_real");
  KittiRawReader::Options few;
  few.last_frame = 2;
  auto kitti = KittiDriveReader::Open(testing::KittiRawDriveDir(), few);
  ASSERT_TRUE(kitti.ok()) << kitti.status().ToString();
  RoundTrip(**kitti, tmp, kAllFormats);

  // All 50 real scans as binary PCD: bitwise equal, and the read speed (docs/drive_folder.md).
  auto all = KittiDriveReader::Open(testing::KittiRawDriveDir(), KittiRawReader::Options());
  ASSERT_TRUE(all.ok());
  ASSERT_TRUE(WriteDriveFolder(**all, tmp / "all_pcd", FolderWriteOptions()).ok());
  const auto folder = OpenFolder(tmp / "all_pcd");
  ASSERT_NE(folder, nullptr);
  testing::ExpectSameScans(**all, *folder);
  testing::ExpectSameImu((*all)->streams(), folder->streams());
  testing::ExpectSameGnssExactly((*all)->streams(), folder->streams());
  testing::ExpectSameCalibrationAndInitialState((*all)->streams(), folder->streams());
  for (const auto* reader : {static_cast<const DriveReader*>(folder.get()),
                             static_cast<const DriveReader*>(all->get())}) {
    size_t points = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (size_t i = 0; i < reader->NumScans(); ++i) points += reader->ReadScan(i)->cloud.size();
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const double scans_per_s = static_cast<double>(reader->NumScans()) / s;
    std::printf(
        "[read speed] %s: %zu scans, %zu points in %.3f s = %.1f scans/s (%.1fx the 10 Hz "
        "real time)\n",
        reader->Describe().c_str(), reader->NumScans(), points, s, scans_per_s, scans_per_s / 10.0);
  }
  fs::remove_all(tmp);
}

// ---- The real third-party PCD drive (PCL binary PCD with zero padding) -----------------------
TEST(FolderDriveReaderTest, RealThirdPartyPcdDrive0048) {
  const fs::path data = testing::SharedDataDir();
  const fs::path pcd_tar = data / "kitti_pcd" / "2011_09_26_drive_0048_pcd.tar.gz";
  const fs::path oxts_tar = data / "kitti_oxts" / "2011_09_26_drive_0048_sync.tar.gz";
  const fs::path calib = data / "kitti_raw" / "2011_09_26" / "calib_imu_to_velo.txt";
  if (!fs::exists(pcd_tar) || !fs::exists(oxts_tar) || !fs::exists(calib)) {
    GTEST_SKIP() << "real KITTI PCD/OXTS data not found under " << data
                 << " (set SLAM_MMS_SHARED_DATA to the shared/data folder to run this)";
  }
  const fs::path tmp = testing::MakeTempDir("folder_0048");
  for (const fs::path& tar : {pcd_tar, oxts_tar}) {
    const std::string cmd = "tar xzf '" + tar.string() + "' -C '" + tmp.string() + "'";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  const fs::path pcd_dir = tmp / "2011_09_26_drive_0048_pcd";
  const fs::path oxts_dir = tmp / "2011_09_26_drive_0048_sync" / "oxts";
  const fs::path dir = tmp / "folder";
  fs::create_directories(dir / "scans");

  // OXTS records -> imu.csv, gnss.csv; scan i: mid time 18 ms before OXTS stamp i, 103.5 ms long.
  std::ifstream stamps_in(oxts_dir / "timestamps.txt");
  std::string line, imu = "stamp_ns,ax,ay,az,wx,wy,wz\n",
                    gnss = "stamp_ns,lat_deg,lon_deg,height_m,sigma_e_m,sigma_n_m,sigma_u_m,fix\n",
                    scans = "file,stamp_start_ns,stamp_end_ns\n";
  std::vector<size_t> declared;
  const auto g = [](double v) {
    char b[40];
    std::snprintf(b, sizeof(b), "%.17g", v);
    return std::string(b);
  };
  for (int i = 0; std::getline(stamps_in, line); ++i) {
    auto stamp = ParseKittiTimestamp(line);
    ASSERT_TRUE(stamp.ok()) << line;
    char name[32];
    std::snprintf(name, sizeof(name), "%010d", i);
    const auto oxts_lines = testing::ReadFile(oxts_dir / "data" / (std::string(name) + ".txt"));
    auto rec = ParseOxtsLine(oxts_lines.substr(0, oxts_lines.find('\n')), name, 1);
    ASSERT_TRUE(rec.ok()) << rec.status().ToString();
    const ImuSample s = ToImuSample(*rec, *stamp);
    const GnssFix f = ToGnssFix(*rec, *stamp);
    const std::string ns = std::to_string(stamp->nanoseconds());
    imu += ns + "," + g(s.accel_mps2.x()) + "," + g(s.accel_mps2.y()) + "," + g(s.accel_mps2.z()) +
           "," + g(s.gyro_radps.x()) + "," + g(s.gyro_radps.y()) + "," + g(s.gyro_radps.z()) + "\n";
    gnss += ns + "," + g(f.latitude_deg) + "," + g(f.longitude_deg) + "," + g(f.height_m) + "," +
            g(f.sigma_horizontal_m) + "," + g(f.sigma_horizontal_m) + "," + g(f.sigma_vertical_m) +
            "," + io_internal::GnssFixCsvName(f.type) + "\n";
    const Timestamp start = stamp->PlusSeconds(-0.018 - 0.5 * 0.1035);
    scans += std::string(name) + ".pcd," + std::to_string(start.nanoseconds()) + "," +
             std::to_string(start.PlusSeconds(0.1035).nanoseconds()) + "\n";
    const fs::path pcd = pcd_dir / (std::string(name) + ".pcd");
    ASSERT_TRUE(fs::exists(pcd)) << pcd;
    fs::create_symlink(pcd, dir / "scans" / (std::string(name) + ".pcd"));
    // The declared count, read here independently of the library.
    const std::string bytes = testing::ReadFile(pcd);
    const size_t p = bytes.find("\nPOINTS ");
    ASSERT_NE(p, std::string::npos);
    declared.push_back(std::stoul(bytes.substr(p + 8)));
    const size_t data_start = bytes.find("DATA binary\n") + 12;
    if (i == 0) {
      EXPECT_GT(bytes.size(), data_start + 16 * declared.back()) << "no padding: the quirk is gone";
    }
  }
  ASSERT_EQ(declared.size(), 22u);
  testing::WriteFile(dir / "scans.csv", scans);
  testing::WriteFile(dir / "imu.csv", imu);
  testing::WriteFile(dir / "gnss.csv", gnss);
  auto T_lidar_body = ReadKittiRigidCalibration(calib);
  ASSERT_TRUE(T_lidar_body.ok());
  DriveExtrinsics e;
  e.T_body_lidar = T_lidar_body->inverse();
  ASSERT_TRUE(WriteExtrinsicsYaml(e, dir / "extrinsics.yaml").ok());

  const auto folder = OpenFolder(dir);
  ASSERT_NE(folder, nullptr);
  ASSERT_EQ(folder->NumScans(), 22u);
  EXPECT_EQ(folder->streams().imu.size(), 22u);
  EXPECT_EQ(folder->streams().gnss.size(), 22u);
  EXPECT_TRUE(folder->streams().T_body_lidar.isApprox(T_lidar_body->inverse(), 1e-15));
  for (size_t i = 0; i < 22; ++i) {
    auto scan = folder->ReadScan(i);
    ASSERT_TRUE(scan.ok()) << scan.status().ToString();
    EXPECT_GT(declared[i], 100000u);
    EXPECT_EQ(scan->cloud.size(), declared[i]) << "scan " << i;
    const auto& t = scan->cloud.time_offsets_s();
    EXPECT_GE(*std::min_element(t.begin(), t.end()), 0.0f);
    EXPECT_LE(*std::max_element(t.begin(), t.end()), 0.1035f + 1e-6f);
    EXPECT_NEAR(scan->stamp_end.SecondsSince(scan->stamp_start), 0.1035, 1e-12);
  }
  EXPECT_EQ(folder->TotalDroppedPoints(), 0u);
  fs::remove_all(tmp);
}

// ---- Format details ----------------------------------------------------------------------------
class FolderFormatTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("folder_format");
    fs::create_directories(dir_ / "scans");
    testing::WriteFile(dir_ / "imu.csv", "stamp_ns,ax,ay,az,wx,wy,wz\n");
    testing::WriteFile(dir_ / "extrinsics.yaml",
                       "T_body_lidar: {xyz: [0.5, 0, 1.2], rpy_deg: [0, 0, 90]}\n"
                       "t_body_antenna_m: [0.1, 0.2, 1.5]\nfoo: bar\n");
  }
  void TearDown() override { fs::remove_all(dir_); }
  // One scan `name` with `bytes`, 100 ms long.
  void OneScan(const std::string& name, const std::string& bytes) {
    testing::WriteFile(dir_ / "scans" / name, bytes);
    testing::WriteFile(dir_ / "scans.csv",
                       "file,stamp_start_ns,stamp_end_ns\n" + name + ",1000000000,1100000000\n");
  }
  fs::path dir_;
};

TEST_F(FolderFormatTest, PcdAsciiWithDoubleTimeNanAndExtraFields) {
  OneScan("a.pcd",
          "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb intensity time ring\nSIZE 8 8 8 4 2 8 2\n"
          "TYPE F F F U U F U\nCOUNT 1 1 1 1 1 1 1\nWIDTH 4\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
          "POINTS 4\nDATA ascii\n1.5 2 3 0 7 0.01 1\nnan 0 0 0 1 0.02 2\n\n"
          "4 5 6 0 65535 0.09 3\n-1 0 0 0 3 0.05 4\ntrailing junk is ignored\n");
  auto r = FolderDriveReader::Open(dir_, FolderDriveReader::Options());
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  auto scan = (*r)->ReadScan(0);
  ASSERT_TRUE(scan.ok()) << scan.status().ToString();
  ASSERT_EQ(scan->cloud.size(), 3u);
  EXPECT_EQ((*r)->TotalDroppedPoints(), 1u);
  EXPECT_EQ(scan->cloud.points()[0], Eigen::Vector3f(1.5f, 2.0f, 3.0f));
  EXPECT_EQ(scan->cloud.intensities()[1], 65535.0f);
  EXPECT_EQ(scan->cloud.time_offsets_s()[0], 0.01f);
  EXPECT_EQ(scan->cloud.time_offsets_s()[2], 0.05f);
  EXPECT_EQ(scan->stamp_trigger.nanoseconds(), 1050000000);
  // The extrinsics in the xyz + rpy_deg form, the lever arm.
  const auto& s = (*r)->streams();
  EXPECT_TRUE(s.T_body_lidar.linear().isApprox(
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix(), 1e-15));
  EXPECT_EQ(s.T_body_lidar.translation(), Eigen::Vector3d(0.5, 0, 1.2));
  ASSERT_TRUE(s.t_body_antenna_m.has_value());
  EXPECT_EQ(*s.t_body_antenna_m, Eigen::Vector3d(0.1, 0.2, 1.5));
  EXPECT_TRUE(s.gnss.empty());
}

TEST_F(FolderFormatTest, PlyBigEndianAndBinaryPcdPaddingAndNoIntensity) {
  // PLY big endian, double x y z, float t, no intensity; a face element after the vertices.
  std::string body;
  const auto put_be = [&body](const void* p, size_t n) {
    const char* c = static_cast<const char*>(p);
    for (size_t i = 0; i < n; ++i) body += c[n - 1 - i];
  };
  for (int i = 0; i < 3; ++i) {
    const double xyz[3] = {1.0 + i, -2.0, 0.125};
    for (double v : xyz) put_be(&v, 8);
    const float t = 0.03f * static_cast<float>(i);
    put_be(&t, 4);
  }
  OneScan("b.ply",
          "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\n"
          "property double y\nproperty double z\nproperty float t\nelement face 0\n"
          "property list uchar int vertex_indices\nend_header\n" +
              body);
  auto r = FolderDriveReader::Open(dir_, FolderDriveReader::Options());
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  auto scan = (*r)->ReadScan(0);
  ASSERT_TRUE(scan.ok()) << scan.status().ToString();
  ASSERT_EQ(scan->cloud.size(), 3u);
  EXPECT_EQ(scan->cloud.points()[2], Eigen::Vector3f(3.0f, -2.0f, 0.125f));
  EXPECT_EQ(scan->cloud.intensities()[2], 0.0f);
  EXPECT_EQ(scan->cloud.time_offsets_s()[2], 0.06f);

  // Binary PCD with 1000 zero bytes of padding, uint8 intensity, int16 extra field.
  std::string pcd =
      "VERSION .7\nFIELDS x y z intensity ring\nSIZE 4 4 4 1 2\nTYPE F F F U I\n"
      "WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n";
  for (int i = 0; i < 2; ++i) {
    const float xyz[3] = {10.0f * static_cast<float>(i + 1), 0.0f, 1.0f};
    pcd.append(reinterpret_cast<const char*>(xyz), 12);
    pcd += static_cast<char>(200 + i);
    pcd += std::string(2, '\x01');
  }
  pcd += std::string(1000, '\0');
  OneScan("c.pcd", pcd);
  r = FolderDriveReader::Open(dir_, FolderDriveReader::Options());
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  scan = (*r)->ReadScan(0);
  ASSERT_TRUE(scan.ok()) << scan.status().ToString();
  ASSERT_EQ(scan->cloud.size(), 2u);
  EXPECT_EQ(scan->cloud.intensities()[1], 201.0f);
  // No time field: azimuth time, as KittiAzimuthFraction (azimuth 0 -> half the sweep).
  EXPECT_FLOAT_EQ(
      scan->cloud.time_offsets_s()[0],
      static_cast<float>(0.1 * KittiAzimuthFraction(10.0, 0.0, SpinDirection::kClockwise)));
}

TEST(FolderNmeaTest, EpochsDatesGstAndChecksums) {
  using io_internal::NmeaSentence;
  // GGA before RMC in one epoch (receivers do that), GST before its GGA, a midnight rollover, a
  // sentence with a wrong checksum, one without a position, other types ignored.
  std::string text =
      NmeaSentence("GPGGA,235959.50,4900.0000000,N,00825.0000000,E,4,12,0.8,100.0,M,47.5,M,,") +
      NmeaSentence("GPRMC,235959.50,A,4900.0000,N,00825.0000,E,0.0,0.0,310111,,,A") +
      NmeaSentence("GPGST,000000.50,,,,,0.012,0.016,0.030") +
      NmeaSentence("GPGGA,000000.50,4900.0000000,S,00825.0000000,W,5,09,,100.0,M,,M,,") +
      NmeaSentence("GPGSV,3,1,12,01,40,083,46") +
      "$GPGGA,000001.00,4900.0,N,00825.0,E,1,05,,1.0,M,0.0,M,,*00\r\n" +
      NmeaSentence("GPGGA,000001.50,,,,,0,00,,,M,,M,,") + "\n";
  auto nmea = io_internal::ParseNmeaGnss(text, "log.nmea", {});
  ASSERT_TRUE(nmea.ok()) << nmea.status().ToString();
  ASSERT_EQ(nmea->fixes.size(), 2u);
  EXPECT_EQ(nmea->num_bad, 1u);
  ASSERT_EQ(nmea->bad.size(), 1u);
  EXPECT_THAT(nmea->bad[0], HasSubstr("log.nmea:6: checksum 00 wrong"));
  EXPECT_EQ(nmea->num_without_position, 1u);
  EXPECT_EQ(nmea->num_ignored, 1u);
  const GnssFix& a = nmea->fixes[0];
  const GnssFix& b = nmea->fixes[1];
  EXPECT_EQ(a.stamp.ToKittiString(), "2011-01-31 23:59:59.500000000");
  EXPECT_EQ(b.stamp.ToKittiString(), "2011-02-01 00:00:00.500000000");
  EXPECT_EQ(a.height_m, 147.5);
  EXPECT_EQ(b.height_m, 100.0);
  EXPECT_EQ(a.type, GnssFixType::kRtkFixed);
  EXPECT_EQ(b.type, GnssFixType::kRtkFloat);
  EXPECT_EQ(a.num_satellites, 12);
  EXPECT_DOUBLE_EQ(b.latitude_deg, -49.0);
  EXPECT_DOUBLE_EQ(b.longitude_deg, -8.0 - 25.0 / 60.0);
  EXPECT_DOUBLE_EQ(b.sigma_horizontal_m, std::sqrt(0.5 * (0.012 * 0.012 + 0.016 * 0.016)));
  EXPECT_EQ(b.sigma_vertical_m, 0.030);
  EXPECT_EQ(nmea->num_without_gst, 1u);  // fix a: defaults by type
  EXPECT_EQ(a.sigma_horizontal_m, 0.02);
  EXPECT_EQ(nmea->fix_lines, (std::vector<int>{1, 4}));

  // The writer at 9 decimals round-trips the stamp exactly, also over a carry into the next day.
  GnssFix f = b;
  f.stamp = Timestamp::FromNanoseconds(1296518399999999999LL);  // 2011-01-31 23:59:59.999999999
  nmea = io_internal::ParseNmeaGnss(io_internal::FormatNmeaEpoch(f, 9), "w.nmea", {});
  ASSERT_TRUE(nmea.ok()) << nmea.status().ToString();
  EXPECT_EQ(nmea->fixes.at(0).stamp, f.stamp);
  nmea = io_internal::ParseNmeaGnss(io_internal::FormatNmeaEpoch(f, 3), "w.nmea", {});
  ASSERT_TRUE(nmea.ok()) << nmea.status().ToString();
  EXPECT_EQ(nmea->fixes.at(0).stamp.ToKittiString(), "2011-02-01 00:00:00.000000000");

  // Fuzz regression: a year past int64 nanoseconds (2262) overflowed the stamp; now a bad
  // sentence, and the GGA after it has no date.
  nmea = io_internal::ParseNmeaGnss(
      NmeaSentence("GPZDA,101500.10,13,09,4040,00,00") +
          NmeaSentence("GPGGA,101500.10,4806.0,N,01130.0,E,5,12,0.9,472.260,M,48.0,M,,"),
      "y.nmea", {});
  EXPECT_THAT(nmea.status().message(), HasSubstr("y.nmea:2: GGA at 10:15:00.100000000 comes "
                                                 "before any date"));

  // A date from the options for a log without RMC/ZDA.
  io_internal::NmeaOptions with_date;
  ASSERT_TRUE(io_internal::CivilToDays(2020, 5, 17, &with_date.utc_date_days.emplace()));
  nmea = io_internal::ParseNmeaGnss(
      NmeaSentence("GNGGA,120000,4900.0,N,00825.0,E,2,08,,5.0,M,1.0,M,,"), "d.nmea", with_date);
  ASSERT_TRUE(nmea.ok()) << nmea.status().ToString();
  EXPECT_EQ(nmea->fixes.at(0).stamp.ToKittiString(), "2020-05-17 12:00:00.000000000");
  EXPECT_EQ(nmea->fixes.at(0).type, GnssFixType::kDifferential);
}

TEST(FolderCsvTest, CommentsBlankLinesAndOptionalColumns) {
  const std::string pos =
      "# external POS\n\nstamp_ns,lat_deg,lon_deg,height_m,roll_deg,pitch_deg,yaw_deg,"
      "sigma_e_m,sigma_n_m,sigma_u_m\n"
      "100, 49.0, 8.4, 110.5, 1, 2, 90, 0.01, 0.02, 0.03\n# a comment\n"
      "200,49.0,8.4,110.5,0,0,-90,0.01,0.02,0.03\n";
  std::vector<PosRecord> records;
  std::vector<std::string> sources;
  ASSERT_TRUE(io_internal::ParsePosCsv(pos, "pos.csv", &records, &sources).ok());
  ASSERT_EQ(records.size(), 2u);
  EXPECT_EQ(sources[1], "pos.csv:6");
  EXPECT_FALSE(records[0].sigma_rpy_rad.has_value());
  ASSERT_TRUE(records[0].sigma_enu_m.has_value());
  EXPECT_EQ(*records[0].sigma_enu_m, Eigen::Vector3d(0.01, 0.02, 0.03));
  OxtsRecord o;
  o.roll_rad = M_PI / 180.0;
  o.pitch_rad = 2.0 * M_PI / 180.0;
  o.yaw_rad = M_PI / 2.0;
  EXPECT_TRUE(records[0].R_enu_body.isApprox(OxtsAttitude(o), 1e-15));
  // A sigma group must be complete.
  std::vector<PosRecord> bad;
  EXPECT_THAT(io_internal::ParsePosCsv("stamp_ns,lat_deg,lon_deg,height_m,roll_deg,pitch_deg,"
                                       "yaw_deg,sigma_roll_deg\n",
                                       "pos.csv", &bad, &sources)
                  .message(),
              HasSubstr("only 1 of the columns sigma_roll_deg,sigma_pitch_deg,sigma_yaw_deg"));
}

TEST(FolderWriterTest, PosAndOptionsValidation) {
  // A KITTI drive has no external POS: a folder written from a folder with pos.csv keeps it.
  const fs::path tmp = testing::MakeTempDir("folder_pos");
  const fs::path drive = testing::WriteSyntheticKittiDrive(tmp, 2, 100);
  auto kitti = KittiDriveReader::Open(drive, KittiRawReader::Options());
  ASSERT_TRUE(kitti.ok());
  ASSERT_TRUE(WriteDriveFolder(**kitti, tmp / "a", FolderWriteOptions()).ok());
  const Timestamp t = (*kitti)->ScanStart(0);
  testing::WriteFile(tmp / "a" / "pos.csv",
                     "stamp_ns,lat_deg,lon_deg,height_m,roll_deg,pitch_deg,yaw_deg,sigma_roll_deg,"
                     "sigma_pitch_deg,sigma_yaw_deg\n" +
                         std::to_string(t.nanoseconds()) +
                         ",49.1,8.5,100.25,0.5,-0.25,33.3,0.1,"
                         "0.1,0.3\n");
  const auto a = OpenFolder(tmp / "a");
  ASSERT_NE(a, nullptr);
  ASSERT_EQ(a->streams().pos.size(), 1u);
  ASSERT_TRUE(WriteDriveFolder(*a, tmp / "b", FolderWriteOptions()).ok());
  const auto b = OpenFolder(tmp / "b");
  ASSERT_NE(b, nullptr);
  ASSERT_EQ(b->streams().pos.size(), 1u);
  const PosRecord &p = a->streams().pos[0], &q = b->streams().pos[0];
  EXPECT_EQ(p.stamp, q.stamp);
  EXPECT_EQ(p.latitude_deg, q.latitude_deg);
  EXPECT_LT(so3::Log(p.R_enu_body.transpose() * q.R_enu_body).norm(), 1e-12);
  ASSERT_TRUE(q.sigma_rpy_rad.has_value());
  EXPECT_TRUE(p.sigma_rpy_rad->isApprox(*q.sigma_rpy_rad, 1e-15));
  EXPECT_FALSE(q.sigma_enu_m.has_value());
  testing::ExpectSameScans(*a, *b);

  // Options and an existing folder.
  FolderWriteOptions o;
  o.scan_format = FolderWriteOptions::ScanFormat::kBin;
  o.write_point_time = true;
  EXPECT_THAT(o.Validate().message(), HasSubstr("write_point_time"));
  EXPECT_EQ(WriteDriveFolder(**kitti, tmp / "a", FolderWriteOptions()).code(),
            StatusCode::kInvalidArgument);
  FolderWriteOptions overwrite;
  overwrite.overwrite = true;
  EXPECT_TRUE(WriteDriveFolder(**kitti, tmp / "a", overwrite).ok());
  EXPECT_FALSE(fs::exists(tmp / "a" / "pos.csv"));
  fs::remove_all(tmp);
}

}  // namespace
}  // namespace slam_mms
