#pragma once
// Helpers of the drive-folder tests: a small synthetic KITTI raw drive (KittiRawWriter), text
// files, and bitwise comparisons of scans and streams.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <string>
#include <vector>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms/io/kitti_raw_writer.hpp"
#include "testing/log_capture.hpp"

namespace slam_mms::testing {

inline void WriteFile(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << text;
}

inline std::string ReadFile(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline OxtsRecord SyntheticOxts(std::mt19937_64& rng, int i) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  OxtsRecord r;
  r.lat_deg = 49.011 + 1e-6 * i + 1e-9 * u(rng);
  r.lon_deg = 8.423 + 2e-6 * i;
  r.alt_m = 112.5 + 0.01 * u(rng);
  r.roll_rad = 0.02 * u(rng);
  r.pitch_rad = 0.03 * u(rng);
  r.yaw_rad = 1.3 + 0.1 * u(rng);
  r.vn = 3.0 + u(rng);
  r.ve = 4.0 + u(rng);
  r.vu = 0.1 * u(rng);
  r.ax = 0.3 * u(rng);
  r.ay = 0.2 * u(rng);
  r.az = 9.81 + 0.1 * u(rng);
  r.wx = 0.01 * u(rng);
  r.wy = 0.01 * u(rng);
  r.wz = 0.1 * u(rng);
  r.pos_accuracy_m = 0.05 + 0.01 * std::abs(u(rng));
  r.navstat = kOxtsNavstatLocked;
  r.numsats = 7 + i % 5;
  r.posmode = i % 3 == 0 ? 6 : 4;
  r.velmode = r.orimode = 4;
  return r;
}

/// Writes a KITTI raw sync drive of `num_scans` scans (points on a ring of walls with random
/// noise, some at azimuth +-pi), 10 Hz OXTS and 100 Hz oxts_100hz/; returns the drive folder.
inline std::filesystem::path WriteSyntheticKittiDrive(const std::filesystem::path& root,
                                                      int num_scans, size_t points_per_scan) {
  const std::filesystem::path drive = root / "2011_01_01" / "2011_01_01_drive_0001_sync";
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  auto writer = KittiRawWriter::Create(drive);
  EXPECT_TRUE(writer.ok()) << writer.status().ToString();
  Eigen::Isometry3d T_lidar_body = Eigen::Isometry3d::Identity();
  T_lidar_body.linear() = so3::Exp(Eigen::Vector3d(0.01, -0.02, 0.03));
  T_lidar_body.translation() = Eigen::Vector3d(-0.81, 0.32, -0.8);
  EXPECT_TRUE(writer->WriteCalibration(T_lidar_body).ok());
  const Timestamp t0 = Timestamp::FromNanoseconds(1317042651106324297LL);
  for (int k = -50; k < 10 * num_scans + 50; ++k) {
    EXPECT_TRUE(writer->AddImuOxts(t0.PlusSeconds(0.01 * k + 0.0003), SyntheticOxts(rng, k)).ok());
  }
  for (int i = 0; i < num_scans; ++i) {
    Scan scan;
    scan.stamp_start = t0.PlusSeconds(0.1036 * i + 0.000000123 * i);
    scan.stamp_end = scan.stamp_start.PlusSeconds(0.1035);
    scan.stamp_trigger = scan.stamp_start.PlusSeconds(0.0517);
    for (size_t k = 0; k < points_per_scan; ++k) {
      const double a = 2.0 * M_PI * static_cast<double>(k) / static_cast<double>(points_per_scan);
      const float r = 5.0f + 20.0f * std::abs(u(rng));
      scan.cloud.Add(Eigen::Vector3f(r * static_cast<float>(std::cos(a)),
                                     r * static_cast<float>(std::sin(a)), -1.7f + u(rng)),
                     0.5f + 0.5f * u(rng));
    }
    scan.cloud.Add(Eigen::Vector3f(-7.0f, 0.0f, 0.5f), 0.25f);   // azimuth exactly pi
    scan.cloud.Add(Eigen::Vector3f(-7.0f, -0.0f, 0.5f), 0.25f);  // and -pi
    EXPECT_TRUE(writer->AddScan(scan).ok());
    EXPECT_TRUE(
        writer->AddOxts(scan.stamp_start.PlusSeconds(0.07), SyntheticOxts(rng, 1000 + i)).ok());
  }
  EXPECT_TRUE(writer->Finish().ok());
  return drive;
}

template <typename T>
bool BitwiseEqual(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0);
}

/// Scans i of both readers: same stamps and bitwise-identical points, intensities, times.
inline void ExpectSameScans(const DriveReader& a, const DriveReader& b) {
  ASSERT_EQ(a.NumScans(), b.NumScans());
  for (size_t i = 0; i < a.NumScans(); ++i) {
    SCOPED_TRACE("scan " + std::to_string(i));
    EXPECT_EQ(a.ScanStart(i), b.ScanStart(i));
    EXPECT_EQ(a.ScanEnd(i), b.ScanEnd(i));
    auto sa = a.ReadScan(i);
    auto sb = b.ReadScan(i);
    ASSERT_TRUE(sa.ok()) << sa.status().ToString();
    ASSERT_TRUE(sb.ok()) << sb.status().ToString();
    EXPECT_EQ(sa->index, sb->index);
    ASSERT_EQ(sa->cloud.size(), sb->cloud.size());
    EXPECT_TRUE(BitwiseEqual(sa->cloud.points(), sb->cloud.points()));
    EXPECT_TRUE(BitwiseEqual(sa->cloud.intensities(), sb->cloud.intensities()));
    EXPECT_TRUE(BitwiseEqual(sa->cloud.time_offsets_s(), sb->cloud.time_offsets_s()));
  }
}

inline void ExpectSameImu(const DriveStreams& a, const DriveStreams& b) {
  ASSERT_EQ(a.imu.size(), b.imu.size());
  for (size_t k = 0; k < a.imu.size(); ++k) {
    EXPECT_EQ(a.imu[k].stamp, b.imu[k].stamp);
    EXPECT_EQ(a.imu[k].accel_mps2, b.imu[k].accel_mps2);
    EXPECT_EQ(a.imu[k].gyro_radps, b.imu[k].gyro_radps);
  }
}

inline void ExpectSameGnssExactly(const DriveStreams& a, const DriveStreams& b) {
  ASSERT_EQ(a.gnss.size(), b.gnss.size());
  for (size_t k = 0; k < a.gnss.size(); ++k) {
    const GnssFix &x = a.gnss[k], &y = b.gnss[k];
    EXPECT_EQ(x.stamp, y.stamp);
    EXPECT_EQ(x.latitude_deg, y.latitude_deg);
    EXPECT_EQ(x.longitude_deg, y.longitude_deg);
    EXPECT_EQ(x.height_m, y.height_m);
    EXPECT_EQ(x.sigma_horizontal_m, y.sigma_horizontal_m);
    EXPECT_EQ(x.sigma_vertical_m, y.sigma_vertical_m);
    EXPECT_EQ(x.type, y.type);
    EXPECT_EQ(x.num_satellites, y.num_satellites);
  }
}

/// NMEA precision (FormatNmeaEpoch): 1e-7 minutes, 4 decimals, `stamp_tolerance_ns`.
inline void ExpectSameGnssNmea(const DriveStreams& a, const DriveStreams& b,
                               int64_t stamp_tolerance_ns) {
  ASSERT_EQ(a.gnss.size(), b.gnss.size());
  const double kDeg = 0.5e-7 / 60.0 + 1e-12;
  for (size_t k = 0; k < a.gnss.size(); ++k) {
    const GnssFix &x = a.gnss[k], &y = b.gnss[k];
    EXPECT_LE(std::llabs(x.stamp.nanoseconds() - y.stamp.nanoseconds()), stamp_tolerance_ns);
    EXPECT_NEAR(x.latitude_deg, y.latitude_deg, kDeg);
    EXPECT_NEAR(x.longitude_deg, y.longitude_deg, kDeg);
    EXPECT_NEAR(x.height_m, y.height_m, 0.5e-4 + 1e-9);
    EXPECT_NEAR(x.sigma_horizontal_m, y.sigma_horizontal_m, 0.5e-4 + 1e-12);
    EXPECT_NEAR(x.sigma_vertical_m, y.sigma_vertical_m, 0.5e-4 + 1e-12);
    EXPECT_EQ(x.type, y.type);
    EXPECT_EQ(x.num_satellites, y.num_satellites);
  }
}

inline void ExpectSameCalibrationAndInitialState(const DriveStreams& a, const DriveStreams& b) {
  EXPECT_TRUE(a.T_body_lidar.matrix() == b.T_body_lidar.matrix())
      << a.T_body_lidar.matrix() << "\nvs\n"
      << b.T_body_lidar.matrix();
  ASSERT_EQ(a.initial_state.has_value(), b.initial_state.has_value());
  if (a.initial_state) {
    EXPECT_EQ(a.initial_state->stamp, b.initial_state->stamp);
    const Eigen::Matrix3d dR =
        a.initial_state->T_world_body.linear().transpose() * b.initial_state->T_world_body.linear();
    EXPECT_LT(so3::Log(dR).norm(), 1e-12);
    EXPECT_EQ(a.initial_state->v_world_mps, b.initial_state->v_world_mps);
  }
  ASSERT_EQ(a.initial_attitude_sigma_rpy_rad.has_value(),
            b.initial_attitude_sigma_rpy_rad.has_value());
  if (a.initial_attitude_sigma_rpy_rad) {
    EXPECT_TRUE(
        a.initial_attitude_sigma_rpy_rad->isApprox(*b.initial_attitude_sigma_rpy_rad, 1e-12))
        << a.initial_attitude_sigma_rpy_rad->transpose() << " vs "
        << b.initial_attitude_sigma_rpy_rad->transpose();
  }
}

}  // namespace slam_mms::testing
