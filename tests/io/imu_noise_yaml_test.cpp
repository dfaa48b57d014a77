// imu_noise.yaml: datasheet units and SI, the round trip, errors naming file/line/key/field, and
// the readers that pick the file up (KITTI raw drive, drive folder, the folder writer).
#include "slam_mms/io/imu_noise_yaml.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "io/folder_test_util.hpp"
#include "slam_mms/io/drive_folder_writer.hpp"
#include "slam_mms/io/folder_drive_reader.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

constexpr double kDeg = M_PI / 180.0;

// An RT3003-like datasheet in its own units.
const char* kDatasheet =
    "model: OXTS RT3003\n"
    "angle_random_walk_deg_per_sqrt_h: 0.2\n"
    "velocity_random_walk_mps_per_sqrt_h: 0.03\n"
    "gyro_bias_instability_deg_per_h: 2\n"
    "gyro_bias_correlation_time_s: 300\n"
    "accel_bias_instability_ug: 10\n"
    "accel_bias_correlation_time_s: 300\n"
    "gyro_bias_repeatability_deg_per_h: 5\n"
    "accel_bias_repeatability_ug: 50\n";

TEST(ImuNoiseYamlTest, DatasheetUnitsToSi) {
  StatusOr<ImuNoiseSpec> s = ParseImuNoiseYaml(kDatasheet, "a.yaml");
  ASSERT_TRUE(s.ok()) << s.status().ToString();
  EXPECT_EQ(s->model, "OXTS RT3003");
  EXPECT_NEAR(s->gyro_noise_density, 0.2 * kDeg / 60.0, 1e-18);  // 5.82e-5 rad/s/sqrt(Hz)
  EXPECT_NEAR(s->accel_noise_density, 0.03 / 60.0, 1e-18);       // 5e-4 m/s^2/sqrt(Hz)
  EXPECT_NEAR(s->gyro_bias_instability, 2.0 * kDeg / 3600.0, 1e-18);
  EXPECT_NEAR(s->accel_bias_instability, 10 * 9.80665e-6, 1e-18);
  EXPECT_NEAR(s->gyro_turn_on_bias_sigma, 5.0 * kDeg / 3600.0, 1e-18);
  EXPECT_NEAR(s->accel_turn_on_bias_sigma, 50 * 9.80665e-6, 1e-18);
  EXPECT_EQ(s->gyro_bias_correlation_time_s, 300.0);
  // Gauss-Markov -> random walk of the same growth over one correlation time.
  EXPECT_NEAR(s->GyroBiasRandomWalk(), 2.0 * kDeg / 3600.0 * std::sqrt(2.0 / 300.0), 1e-18);
  EXPECT_NEAR(s->AccelBiasInitialSigma(), std::hypot(50.0, 10.0) * 9.80665e-6, 1e-15);
}

TEST(ImuNoiseYamlTest, WrittenFileReadsBackBitForBit) {
  StatusOr<ImuNoiseSpec> s = ParseImuNoiseYaml(kDatasheet, "a.yaml");
  ASSERT_TRUE(s.ok());
  s->model = "name: with \"quotes\" # and a hash";
  const fs::path tmp = testing::MakeTempDir("imu_noise_yaml");
  ASSERT_TRUE(WriteImuNoiseYaml(*s, tmp / "imu_noise.yaml").ok());
  StatusOr<ImuNoiseSpec> back = ReadImuNoiseYaml(tmp / "imu_noise.yaml");
  ASSERT_TRUE(back.ok()) << back.status().ToString();
  EXPECT_EQ(back->model, s->model);
  EXPECT_EQ(back->gyro_noise_density, s->gyro_noise_density);
  EXPECT_EQ(back->accel_noise_density, s->accel_noise_density);
  EXPECT_EQ(back->gyro_bias_instability, s->gyro_bias_instability);
  EXPECT_EQ(back->accel_bias_instability, s->accel_bias_instability);
  EXPECT_EQ(back->gyro_bias_correlation_time_s, s->gyro_bias_correlation_time_s);
  EXPECT_EQ(back->accel_bias_correlation_time_s, s->accel_bias_correlation_time_s);
  EXPECT_EQ(back->gyro_turn_on_bias_sigma, s->gyro_turn_on_bias_sigma);
  EXPECT_EQ(back->accel_turn_on_bias_sigma, s->accel_turn_on_bias_sigma);
  // The datasheet values are there for a reader of the file.
  EXPECT_THAT(testing::ReadFile(tmp / "imu_noise.yaml"),
              HasSubstr("#   angle_random_walk_deg_per_sqrt_h: 0.2\n"));
  fs::remove_all(tmp);
}

TEST(ImuNoiseYamlTest, ErrorsNameFileLineKeyAndField) {
  auto error = [](const std::string& text) {
    StatusOr<ImuNoiseSpec> s = ParseImuNoiseYaml(text, "imu.yaml");
    EXPECT_FALSE(s.ok()) << text;
    return s.ok() ? std::string() : s.status().ToString();
  };
  const std::string base = kDatasheet;
  // Both keys of one quantity.
  EXPECT_THAT(error(base + "gyro_noise_density: 1e-4\n"),
              HasSubstr("imu.yaml:10: gyro_noise_density gives the same quantity as "
                        "angle_random_walk_deg_per_sqrt_h"));
  // A value that is not a number, with its line.
  std::string bad = base;
  bad.replace(bad.find("_s: 300") + 4, 3, "abc");
  EXPECT_THAT(error(bad), HasSubstr("imu.yaml:5: gyro_bias_correlation_time_s 'abc' is not a "
                                    "finite number"));
  // A required key missing.
  std::string missing = base;
  missing.erase(missing.find("accel_bias_instability_ug"),
                std::string("accel_bias_instability_ug: 10\n").size());
  EXPECT_THAT(
      error(missing),
      HasSubstr("imu.yaml: key accel_bias_instability_ug (or accel_bias_instability) missing"));
  // Out of range: the field named.
  std::string negative = base;
  negative.replace(negative.find("0.03"), 4, "-0.03");
  EXPECT_THAT(error(negative),
              HasSubstr("ImuNoiseSpec::accel_noise_density = -0.0005; must be > 0"));
  EXPECT_THAT(error("[1, 2]"), HasSubstr("imu.yaml: an IMU noise file must be a YAML map"));
  EXPECT_THAT(error("a: [1,\n"), HasSubstr("imu.yaml:"));
  // A second document is not dropped silently (yaml-cpp's Load would keep only the first).
  EXPECT_THAT(error("{}\ngyro_noise_density: 1e-4\n"),
              HasSubstr("imu.yaml:2: a second YAML document"));
  EXPECT_THAT(error("model: a\n---\nmodel: b\n"), HasSubstr("imu.yaml:3: a second YAML document"));
  EXPECT_EQ(ReadImuNoiseYaml("/nonexistent/imu_noise.yaml").status().code(), StatusCode::kNotFound);
}

TEST(ImuNoiseYamlTest, KittiAndFolderReadersStateItAndTheWriterKeepsIt) {
  const fs::path tmp = testing::MakeTempDir("imu_noise_readers");
  const fs::path drive = testing::WriteSyntheticKittiDrive(tmp, 3, 2000);
  {
    auto kitti = KittiDriveReader::Open(drive, KittiRawReader::Options());
    ASSERT_TRUE(kitti.ok()) << kitti.status().ToString();
    EXPECT_FALSE((*kitti)->streams().imu_noise.has_value());  // KITTI's own drives state none
  }
  testing::WriteFile(drive / "imu_noise.yaml", kDatasheet);
  auto kitti = KittiDriveReader::Open(drive, KittiRawReader::Options());
  ASSERT_TRUE(kitti.ok()) << kitti.status().ToString();
  ASSERT_TRUE((*kitti)->streams().imu_noise.has_value());
  EXPECT_EQ((*kitti)->streams().imu_noise->model, "OXTS RT3003");
  EXPECT_EQ((*kitti)->streams().imu_noise_source, (drive / "imu_noise.yaml").string());

  const fs::path folder = tmp / "folder";
  ASSERT_TRUE(WriteDriveFolder(**kitti, folder, FolderWriteOptions()).ok());
  auto f = FolderDriveReader::Open(folder, FolderDriveReader::Options());
  ASSERT_TRUE(f.ok()) << f.status().ToString();
  ASSERT_TRUE((*f)->streams().imu_noise.has_value());
  EXPECT_EQ((*f)->streams().imu_noise->gyro_noise_density,
            (*kitti)->streams().imu_noise->gyro_noise_density);
  EXPECT_EQ((*f)->streams().imu_noise->accel_turn_on_bias_sigma,
            (*kitti)->streams().imu_noise->accel_turn_on_bias_sigma);

  // A bad file fails the open, naming it.
  testing::WriteFile(folder / "imu_noise.yaml", "angle_random_walk_deg_per_sqrt_h: x\n");
  auto bad = FolderDriveReader::Open(folder, FolderDriveReader::Options());
  ASSERT_FALSE(bad.ok());
  EXPECT_THAT(bad.status().ToString(), HasSubstr((folder / "imu_noise.yaml").string() + ":1"));
  fs::remove_all(tmp);
}

}  // namespace
}  // namespace slam_mms
