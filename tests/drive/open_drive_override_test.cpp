// OverrideExtrinsics and OpenDrive's --extrinsics: the calibration replaced, the antenna kept where
// not given, the scans moved onto the IMU clock by lidar_time_offset_s (points untouched), for a
// KITTI raw drive (over calib_imu_to_velo.txt) and a plain drive folder.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "io/folder_test_util.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/drive/open_drive.hpp"
#include "slam_mms/io/drive_folder_writer.hpp"
#include "slam_mms/io/extrinsics_yaml.hpp"
#include "slam_mms/io/kitti_calibration.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;

constexpr int kScans = 3;

class OpenDriveOverrideTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir("open_drive_override");
    drive_ = testing::WriteSyntheticKittiDrive(dir_, kScans, 200);
    extrinsics_.T_body_lidar.linear() = so3::Exp(Eigen::Vector3d(0.02, -0.01, 0.5));
    extrinsics_.T_body_lidar.translation() = Eigen::Vector3d(0.5, -0.25, 1.5);
    extrinsics_.lidar_time_offset_s = 0.0203456789;  // 20345678.9 ns -> 20345679 ns
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }

  std::unique_ptr<DriveReader> OpenKitti(const fs::path& extrinsics = {}) const {
    DriveSourceOptions o;
    o.extrinsics = extrinsics;
    auto r = OpenDrive(drive_, o);
    EXPECT_TRUE(r.ok()) << r.status().ToString();
    return r.ok() ? std::move(*r) : nullptr;
  }

  fs::path dir_, drive_;
  DriveExtrinsics extrinsics_;
};

// `shifted` is `base` with every scan stamp + offset_ns and the same points.
void ExpectShiftedScans(const DriveReader& base, const DriveReader& shifted, int64_t offset_ns) {
  ASSERT_EQ(base.NumScans(), shifted.NumScans());
  ASSERT_GT(base.NumScans(), 0u);
  for (size_t i = 0; i < base.NumScans(); ++i) {
    SCOPED_TRACE("scan " + std::to_string(i));
    EXPECT_EQ(shifted.ScanStart(i).nanoseconds(), base.ScanStart(i).nanoseconds() + offset_ns);
    EXPECT_EQ(shifted.ScanEnd(i).nanoseconds(), base.ScanEnd(i).nanoseconds() + offset_ns);
    EXPECT_EQ(shifted.ScanSource(i), base.ScanSource(i));
    auto a = base.ReadScan(i);
    auto b = shifted.ReadScan(i);
    ASSERT_TRUE(a.ok()) << a.status().ToString();
    ASSERT_TRUE(b.ok()) << b.status().ToString();
    EXPECT_EQ(b->stamp_start.nanoseconds(), a->stamp_start.nanoseconds() + offset_ns);
    EXPECT_EQ(b->stamp_end.nanoseconds(), a->stamp_end.nanoseconds() + offset_ns);
    EXPECT_EQ(b->stamp_trigger.nanoseconds(), a->stamp_trigger.nanoseconds() + offset_ns);
    EXPECT_EQ(b->stamp_start, shifted.ScanStart(i));
    EXPECT_EQ(b->index, a->index);
    EXPECT_TRUE(testing::BitwiseEqual(a->cloud.points(), b->cloud.points()));
    EXPECT_TRUE(testing::BitwiseEqual(a->cloud.intensities(), b->cloud.intensities()));
    // Per-point times are relative to stamp_start: unchanged.
    EXPECT_TRUE(testing::BitwiseEqual(a->cloud.time_offsets_s(), b->cloud.time_offsets_s()));
  }
}

TEST_F(OpenDriveOverrideTest, ShiftsScanStampsByTheOffsetAndReplacesTBodyLidar) {
  std::unique_ptr<DriveReader> base = OpenKitti();
  ASSERT_NE(base, nullptr);
  auto overridden = OverrideExtrinsics(OpenKitti(), extrinsics_);
  ASSERT_NE(overridden, nullptr);
  const int64_t offset_ns = 20345679;
  ExpectShiftedScans(*base, *overridden, offset_ns);
  EXPECT_EQ(overridden->streams().T_body_lidar.matrix(), extrinsics_.T_body_lidar.matrix());
  EXPECT_NE(base->streams().T_body_lidar.matrix(), extrinsics_.T_body_lidar.matrix());
  // The IMU/GNSS streams and the rest are the base's.
  ASSERT_EQ(overridden->streams().imu.size(), base->streams().imu.size());
  EXPECT_EQ(overridden->streams().imu.front().stamp, base->streams().imu.front().stamp);
  EXPECT_EQ(overridden->streams().gnss.size(), base->streams().gnss.size());
  EXPECT_EQ(overridden->Describe(), base->Describe());
  EXPECT_FALSE(overridden->ReadScan(kScans).ok());

  // A negative offset moves the other way; zero leaves the stamps alone.
  DriveExtrinsics negative = extrinsics_;
  negative.lidar_time_offset_s = -0.25;
  ExpectShiftedScans(*base, *OverrideExtrinsics(OpenKitti(), negative), -250000000);
  DriveExtrinsics zero = extrinsics_;
  zero.lidar_time_offset_s = 0.0;
  ExpectShiftedScans(*base, *OverrideExtrinsics(OpenKitti(), zero), 0);
}

TEST_F(OpenDriveOverrideTest, AntennaIsReplacedOnlyWhereGiven) {
  DriveExtrinsics with_antenna = extrinsics_;
  with_antenna.t_body_antenna_m = Eigen::Vector3d(0.1, -0.2, 0.75);
  auto first = OverrideExtrinsics(OpenKitti(), with_antenna);
  ASSERT_TRUE(first->streams().t_body_antenna_m.has_value());
  EXPECT_EQ(*first->streams().t_body_antenna_m, *with_antenna.t_body_antenna_m);
  // A calibration without antenna keeps the reader's.
  DriveExtrinsics without = extrinsics_;
  without.T_body_lidar.translation().x() += 1.0;
  without.lidar_time_offset_s = 0.0;
  auto second = OverrideExtrinsics(std::move(first), without);
  ASSERT_TRUE(second->streams().t_body_antenna_m.has_value());
  EXPECT_EQ(*second->streams().t_body_antenna_m, *with_antenna.t_body_antenna_m);
  EXPECT_EQ(second->streams().T_body_lidar.matrix(), without.T_body_lidar.matrix());
  // A new one replaces it.
  DriveExtrinsics other = without;
  other.t_body_antenna_m = Eigen::Vector3d(-1.0, 0.0, 1.0);
  auto third = OverrideExtrinsics(std::move(second), other);
  EXPECT_EQ(*third->streams().t_body_antenna_m, *other.t_body_antenna_m);
  // Both shifts add up (the first override's offset, then none).
  ExpectShiftedScans(*OpenKitti(), *third, 20345679);
}

TEST_F(OpenDriveOverrideTest, OpenDriveAppliesEitherFileFormatToAKittiRawDrive) {
  std::unique_ptr<DriveReader> base = OpenKitti();
  ASSERT_NE(base, nullptr);
  const fs::path calib = dir_ / "boresight_imu_to_velo.txt";
  ASSERT_TRUE(WriteKittiImuToVelo(extrinsics_, calib).ok());
  const fs::path yaml = dir_ / "boresight.yaml";
  ASSERT_TRUE(WriteExtrinsicsYaml(extrinsics_, yaml).ok());
  for (const fs::path& file : {calib, yaml}) {
    SCOPED_TRACE(file.string());
    std::unique_ptr<DriveReader> r = OpenKitti(file);
    ASSERT_NE(r, nullptr);
    EXPECT_LT((r->streams().T_body_lidar.matrix() - extrinsics_.T_body_lidar.matrix())
                  .cwiseAbs()
                  .maxCoeff(),
              1e-12);
    ExpectShiftedScans(*base, *r, 20345679);
  }
  // A bad file is named.
  testing::WriteFile(dir_ / "bad.txt", "R: 1 0 0\n");
  DriveSourceOptions o;
  o.extrinsics = dir_ / "bad.txt";
  auto bad = OpenDrive(drive_, o);
  ASSERT_FALSE(bad.ok());
  EXPECT_THAT(bad.status().message(), ::testing::HasSubstr("bad.txt:1"));
}

TEST_F(OpenDriveOverrideTest, OpenDriveOnAFolderKeepsItsAntennaWhereTheFileGivesNone) {
  DriveExtrinsics folder_calib = extrinsics_;
  folder_calib.lidar_time_offset_s = 0.0;
  folder_calib.t_body_antenna_m = Eigen::Vector3d(0.3, 0.0, 0.9);
  const fs::path folder = dir_ / "folder";
  ASSERT_TRUE(
      WriteDriveFolder(*OverrideExtrinsics(OpenKitti(), folder_calib), folder, FolderWriteOptions())
          .ok());
  DriveSourceOptions plain;
  auto base = OpenDrive(folder, plain);
  ASSERT_TRUE(base.ok()) << base.status().ToString();
  ASSERT_TRUE((*base)->streams().t_body_antenna_m.has_value());
  // The KITTI calib file carries no antenna.
  const fs::path calib = dir_ / "calib_imu_to_velo.txt";
  DriveExtrinsics e = extrinsics_;
  e.T_body_lidar.translation().z() = -0.5;
  ASSERT_TRUE(WriteKittiImuToVelo(e, calib).ok());
  DriveSourceOptions o;
  o.extrinsics = calib;
  auto r = OpenDrive(folder, o);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  ASSERT_TRUE((*r)->streams().t_body_antenna_m.has_value());
  EXPECT_EQ(*(*r)->streams().t_body_antenna_m, *folder_calib.t_body_antenna_m);
  EXPECT_NEAR((*r)->streams().T_body_lidar.translation().z(), -0.5, 1e-12);
  ExpectShiftedScans(**base, **r, 20345679);
}

// DriveSourceOptions::kitti_vertical_correction_deg: every point of a KITTI raw drive rotated
// up by the angle (range and azimuth kept), as KittiRawReader's own correction does; refused for
// a bag and for angles beyond 5 deg.
TEST_F(OpenDriveOverrideTest, KittiVerticalCorrectionRaisesEveryPointByTheAngle) {
  const double kDeg = 0.205;
  DriveSourceOptions o;
  o.kitti_vertical_correction_deg = kDeg;
  auto corrected = OpenDrive(drive_, o);
  ASSERT_TRUE(corrected.ok()) << corrected.status().ToString();
  std::unique_ptr<DriveReader> plain = OpenKitti();
  ASSERT_NE(plain, nullptr);
  auto a = plain->ReadScan(0);
  auto b = (*corrected)->ReadScan(0);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->cloud.size(), b->cloud.size());
  ASSERT_GT(a->cloud.size(), 0u);
  double max_err_deg = 0.0;
  for (size_t i = 0; i < a->cloud.size(); ++i) {
    const Eigen::Vector3d p = a->cloud.points()[i].cast<double>();
    const Eigen::Vector3d q = b->cloud.points()[i].cast<double>();
    EXPECT_NEAR(q.norm(), p.norm(), 1e-4);
    const double elevation_p = std::atan2(p.z(), p.head<2>().norm());
    const double elevation_q = std::atan2(q.z(), q.head<2>().norm());
    max_err_deg =
        std::max(max_err_deg, std::abs((elevation_q - elevation_p) * 180.0 / M_PI - kDeg));
  }
  EXPECT_LT(max_err_deg, 1e-3);
  o.kitti_vertical_correction_deg = 6.0;
  auto too_far = OpenDrive(drive_, o);
  ASSERT_FALSE(too_far.ok());
  EXPECT_EQ(too_far.status().code(), StatusCode::kInvalidArgument);
  DriveSourceOptions bag;
  bag.kind = DriveSourceKind::kRosbag;
  bag.kitti_vertical_correction_deg = kDeg;
  auto refused = OpenDrive(dir_ / "drive.bag", bag);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(refused.status().message(), ::testing::HasSubstr("kitti_vertical_correction_deg"));
}

}  // namespace
}  // namespace slam_mms
