// DriveExtrinsics as KITTI calib_imu_to_velo.txt (FormatKittiImuToVelo / ReadKittiImuToVelo), the
// YAML lidar_time_offset_s key, and ReadExtrinsicsFile's choice by extension.
#include "slam_mms/io/kitti_calibration.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/io/extrinsics_yaml.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

void WriteText(const fs::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << text;
}

// A rotation about every axis and a lever arm with digits in every place.
DriveExtrinsics NonTrivialExtrinsics() {
  DriveExtrinsics e;
  e.T_body_lidar.linear() = so3::Exp(Eigen::Vector3d(0.0123456789, -0.0234567891, 1.2345678912));
  e.T_body_lidar.translation() = Eigen::Vector3d(0.81234567891, -0.31987654321, 0.79971234567);
  e.lidar_time_offset_s = -0.0213456789012345;
  return e;
}

class KittiCalibrationTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir("kitti_calibration"); }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

TEST_F(KittiCalibrationTest, RoundTripIsExactUpToTheSo3Projection) {
  const DriveExtrinsics e = NonTrivialExtrinsics();
  const fs::path file = dir_ / "calib_imu_to_velo.txt";
  ASSERT_TRUE(WriteKittiImuToVelo(e, file, "01-Jan-2026 10:00:00").ok());
  const std::string text = FormatKittiImuToVelo(e, "01-Jan-2026 10:00:00");
  EXPECT_THAT(text, HasSubstr("calib_time: 01-Jan-2026 10:00:00\nR: "));
  EXPECT_THAT(text, HasSubstr("\nlidar_time_offset_s: -0.0213456789012345"));
  auto back = ReadKittiImuToVelo(file);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_LT((back->T_body_lidar.matrix() - e.T_body_lidar.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(back->lidar_time_offset_s, e.lidar_time_offset_s);
  EXPECT_FALSE(back->t_body_antenna_m.has_value());
  // The file is KITTI's: R, T map body (IMU) points into the lidar frame.
  auto T_lidar_body = ReadKittiRigidCalibration(file);
  ASSERT_TRUE(T_lidar_body.ok()) << T_lidar_body.status().ToString();
  EXPECT_LT((T_lidar_body->matrix() - e.T_body_lidar.inverse().matrix()).cwiseAbs().maxCoeff(),
            1e-12);
}

TEST_F(KittiCalibrationTest, ZeroOffsetWritesNoOffsetLineAndReadsBackZero) {
  DriveExtrinsics e = NonTrivialExtrinsics();
  e.lidar_time_offset_s = 0.0;
  EXPECT_THAT(FormatKittiImuToVelo(e, "x"), ::testing::Not(HasSubstr("lidar_time_offset_s")));
  // A KITTI file as distributed (7 digits, other keys).
  const fs::path file = dir_ / "kitti.txt";
  WriteText(file,
            "calib_time: 25-May-2012 16:47:16\n"
            "R: 9.999976e-01 7.553071e-04 -2.035826e-03 -7.854027e-04 9.998898e-01 "
            "-1.482298e-02 2.024406e-03 1.482454e-02 9.998881e-01\n"
            "T: -8.086759e-01 3.195559e-01 -7.997231e-01\n");
  auto back = ReadKittiImuToVelo(file);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(back->lidar_time_offset_s, 0.0);
  EXPECT_NEAR(back->T_body_lidar.inverse().translation().x(), -8.086759e-01, 1e-12);
}

TEST_F(KittiCalibrationTest, MalformedFilesNameFileLineAndKey) {
  const std::string rt =
      "R: 1 0 0 0 1 0 0 0 1\n"
      "T: 0.1 0.2 0.3\n";
  const fs::path file = dir_ / "calib.txt";
  auto expect_error = [&](const std::string& text, const std::string& what) {
    SCOPED_TRACE(text);
    WriteText(file, text);
    auto r = ReadKittiImuToVelo(file);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.status().code(), StatusCode::kDataLoss);
    EXPECT_THAT(r.status().message(), HasSubstr(file.string() + what));
  };
  expect_error(rt + "lidar_time_offset_s: abc\n", ":3: key lidar_time_offset_s 'abc'");
  expect_error(rt + "lidar_time_offset_s: 0.1 0.2\n", ":3: key lidar_time_offset_s");
  expect_error(rt + "lidar_time_offset_s:\n", ":3: key lidar_time_offset_s");
  expect_error(rt + "lidar_time_offset_s: inf\n", ":3: key lidar_time_offset_s");
  expect_error("lidar_time_offset_s: 0.01\n" + rt + "lidar_time_offset_s: 0.02\n",
               ":4: key lidar_time_offset_s given twice (first on line 1)");
  expect_error("R: 1 0 0 0 1 0 0 0\nT: 0 0 0\n", ":1: key R has 8 numbers, expected 9");
  expect_error("R: 1 0 0 0 1 0 0 0 1\n", ": key T (3 numbers) missing");
  auto missing = ReadKittiImuToVelo(dir_ / "none.txt");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), StatusCode::kNotFound);
  EXPECT_THAT(missing.status().message(), HasSubstr("none.txt"));
  // The offset line alone is fine; a plain KITTI reader skips it.
  WriteText(file, rt + "lidar_time_offset_s: 1e-3\n");
  auto ok = ReadKittiImuToVelo(file);
  ASSERT_TRUE(ok.ok()) << ok.status().ToString();
  EXPECT_EQ(ok->lidar_time_offset_s, 1e-3);
  EXPECT_TRUE(ReadKittiRigidCalibration(file).ok());
}

TEST_F(KittiCalibrationTest, WriteToAnUnwritablePathIsUnavailable) {
  const Status s = WriteKittiImuToVelo(DriveExtrinsics(), dir_ / "no_such_dir" / "calib.txt");
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.code(), StatusCode::kUnavailable);
  EXPECT_THAT(s.message(), HasSubstr("no_such_dir"));
}

TEST_F(KittiCalibrationTest, YamlCarriesTheTimeOffsetExactly) {
  DriveExtrinsics e = NonTrivialExtrinsics();
  e.t_body_antenna_m = Eigen::Vector3d(0.1, -0.2, 0.75);
  const fs::path file = dir_ / "extrinsics.yaml";
  ASSERT_TRUE(WriteExtrinsicsYaml(e, file).ok());
  auto back = ReadExtrinsicsYaml(file);
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(back->lidar_time_offset_s, e.lidar_time_offset_s);
  EXPECT_EQ(back->T_body_lidar.matrix(), e.T_body_lidar.matrix());
  ASSERT_TRUE(back->t_body_antenna_m.has_value());
  EXPECT_EQ(*back->t_body_antenna_m, *e.t_body_antenna_m);
  // Without the key: 0, and a zero offset is not written.
  e.lidar_time_offset_s = 0.0;
  EXPECT_THAT(FormatExtrinsicsYaml(e), ::testing::Not(HasSubstr("lidar_time_offset_s")));
  auto zero = ParseExtrinsicsYaml(FormatExtrinsicsYaml(e), "z.yaml");
  ASSERT_TRUE(zero.ok()) << zero.status().ToString();
  EXPECT_EQ(zero->lidar_time_offset_s, 0.0);
  // Not a number: named with file:line and the key.
  auto bad = ParseExtrinsicsYaml(
      "T_body_lidar: {xyz: [0, 0, 0], rpy_deg: [0, 0, 0]}\nlidar_time_offset_s: soon\n", "b.yaml");
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.status().code(), StatusCode::kDataLoss);
  EXPECT_THAT(bad.status().message(), HasSubstr("b.yaml:2: lidar_time_offset_s 'soon'"));
  auto seq = ParseExtrinsicsYaml(
      "T_body_lidar: {xyz: [0, 0, 0], rpy_deg: [0, 0, 0]}\nlidar_time_offset_s: [1]\n", "c.yaml");
  ASSERT_FALSE(seq.ok());
  EXPECT_THAT(seq.status().message(), HasSubstr("c.yaml:2: lidar_time_offset_s"));
  // A second document (a line after a closed flow map) is an error, not dropped.
  auto two = ParseExtrinsicsYaml(
      "{T_body_lidar: {xyz: [0, 0, 0], rpy_deg: [0, 0, 0]}}\nlidar_time_offset_s: 0.1\n", "d.yaml");
  ASSERT_FALSE(two.ok());
  EXPECT_THAT(two.status().message(), HasSubstr("d.yaml:2: a second YAML document"));
}

// The statement that the IMU frame is the vehicle's (a KITTI OXTS mounting): written only where
// stated, read back as stated; absent = not stated; anything but true/false names file, line, key.
TEST_F(KittiCalibrationTest, YamlStatesWhetherTheImuFrameIsTheVehicles) {
  DriveExtrinsics e = NonTrivialExtrinsics();
  EXPECT_THAT(FormatExtrinsicsYaml(e), ::testing::Not(HasSubstr("imu_frame_is_vehicle_frame")));
  auto unstated = ParseExtrinsicsYaml(FormatExtrinsicsYaml(e), "u.yaml");
  ASSERT_TRUE(unstated.ok()) << unstated.status().ToString();
  EXPECT_FALSE(unstated->imu_frame_is_vehicle_frame.has_value());
  for (const bool stated : {true, false}) {
    e.imu_frame_is_vehicle_frame = stated;
    const std::string text = FormatExtrinsicsYaml(e);
    EXPECT_THAT(text, HasSubstr(std::string("\nimu_frame_is_vehicle_frame: ") +
                                (stated ? "true" : "false")));
    auto back = ParseExtrinsicsYaml(text, "s.yaml");
    ASSERT_TRUE(back.ok()) << back.status().ToString();
    ASSERT_TRUE(back->imu_frame_is_vehicle_frame.has_value());
    EXPECT_EQ(*back->imu_frame_is_vehicle_frame, stated);
    EXPECT_EQ(back->T_body_lidar.matrix(), e.T_body_lidar.matrix());
  }
  for (const std::string bad : {"yes", "1", "[true]", "", "True"}) {
    auto r = ParseExtrinsicsYaml(
        "T_body_lidar: {xyz: [0, 0, 0], rpy_deg: [0, 0, 0]}\nimu_frame_is_vehicle_frame: " + bad +
            "\n",
        "b.yaml");
    ASSERT_FALSE(r.ok()) << bad;
    EXPECT_EQ(r.status().code(), StatusCode::kDataLoss);
    EXPECT_THAT(r.status().message(), HasSubstr("b.yaml:2: imu_frame_is_vehicle_frame")) << bad;
  }
}

TEST_F(KittiCalibrationTest, ReadExtrinsicsFilePicksTheFormatByExtension) {
  const DriveExtrinsics e = NonTrivialExtrinsics();
  ASSERT_TRUE(WriteExtrinsicsYaml(e, dir_ / "a.yaml").ok());
  ASSERT_TRUE(WriteExtrinsicsYaml(e, dir_ / "b.YML").ok());
  ASSERT_TRUE(WriteKittiImuToVelo(e, dir_ / "calib_imu_to_velo.txt").ok());
  ASSERT_TRUE(WriteKittiImuToVelo(e, dir_ / "calib").ok());
  for (const char* name : {"a.yaml", "b.YML", "calib_imu_to_velo.txt", "calib"}) {
    SCOPED_TRACE(name);
    auto r = ReadExtrinsicsFile(dir_ / name);
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    EXPECT_LT((r->T_body_lidar.matrix() - e.T_body_lidar.matrix()).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_EQ(r->lidar_time_offset_s, e.lidar_time_offset_s);
  }
  // A KITTI file named .yaml is read as YAML (and fails as such), and vice versa.
  ASSERT_TRUE(WriteKittiImuToVelo(e, dir_ / "wrong.yaml").ok());
  EXPECT_FALSE(ReadExtrinsicsFile(dir_ / "wrong.yaml").ok());
  ASSERT_TRUE(WriteExtrinsicsYaml(e, dir_ / "wrong.txt").ok());
  auto wrong = ReadExtrinsicsFile(dir_ / "wrong.txt");
  ASSERT_FALSE(wrong.ok());
  EXPECT_THAT(wrong.status().message(), HasSubstr("wrong.txt"));
}

}  // namespace
}  // namespace slam_mms
