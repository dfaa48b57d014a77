// WriteGeoreferencedOutputs: the file set of each method and option, what the LAS carries from the
// map's stamps, and the option checks that run before any processing.
#include "slam_mms/drive/georeferenced_outputs.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "slam_mms/drive/drive_runner.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "slam_mms/io/map_io.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

std::set<std::string> Files(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.insert(e.path().filename().string());
  return names;
}

class GeoreferencedOutputsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    tmp_ = testing::MakeTempDir("georeferenced_outputs");
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> u(-150.0f, 150.0f);
    const int64_t t0 = int64_t{1317042651} * 1000000000;
    for (int k = 0; k < 10; ++k) {
      ASSERT_TRUE(traj_
                      .Add(Timestamp::FromNanoseconds(t0 + k * 100000000LL),
                           Eigen::Isometry3d(Eigen::Translation3d(k * 1.0, 0.0, 0.0)))
                      .ok());
    }
    for (int i = 0; i < 3000; ++i) {
      map_.Add(Eigen::Vector3f(u(rng), u(rng), u(rng) / 30.0f), 0.3f);
      stamps_.time_ns.push_back(t0 + (i % 10) * 100000000LL + i);
      stamps_.scan_index.push_back(70000 + i % 10);  // > 65535: the source ID wraps
    }
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(tmp_, ec);
  }
  fs::path tmp_;
  Trajectory traj_;
  PointCloud map_;
  MapPointStamps stamps_;
  const GeodeticPoint origin_{49.013141872681, 8.4378138518088, 114.06644439697};
};

TEST_F(GeoreferencedOutputsTest, FileSetPerMethodAndCrs) {
  GeoOutputOptions o;
  ASSERT_TRUE(WriteRunGeorefJson(origin_, o, tmp_).ok());
  ASSERT_TRUE(
      WriteGeoreferencedOutputs("full", MappingMode::kFull, traj_, map_, stamps_, origin_, o, tmp_)
          .ok());
  ASSERT_TRUE(WriteGeoreferencedOutputs("lidar_only", MappingMode::kLidarOnly, traj_, map_, stamps_,
                                        origin_, o, tmp_)
                  .ok());
  EXPECT_EQ(Files(tmp_),
            (std::set<std::string>{"georef.json", "full_wgs84.csv", "full_utm.csv", "map_full.las",
                                   "lidar_only_wgs84.csv", "lidar_only_utm.csv"}));
  auto las = ReadLas(tmp_ / "map_full.las");
  ASSERT_TRUE(las.ok());
  ASSERT_EQ(las->points_utm.size(), map_.size());
  std::set<uint16_t> sources(las->point_source_id.begin(), las->point_source_id.end());
  EXPECT_EQ(sources.size(), 10u);
  EXPECT_EQ(*sources.begin(), 70000 - 65536);
  // Adjusted GPS time of the first point: 1317042651 - 315964800 (GPS epoch) + 15 (leap s) - 1e9.
  EXPECT_NEAR(las->gps_time.front(), 1077866.0, 1e-6);

  // Another CRS, tiles, and a method whose origin is not georef.json's.
  const fs::path other = tmp_ / "other";
  fs::create_directories(other);
  o.crs = "EPSG:25832";
  o.las_tile_size_m = 100.0;
  o.run_origin = GeodeticPoint{49.0, 8.4, 100.0};
  ASSERT_TRUE(WriteGeoreferencedOutputs("gnss_ins", MappingMode::kGnssIns, traj_, map_, stamps_,
                                        origin_, o, other)
                  .ok());
  EXPECT_EQ(Files(other), (std::set<std::string>{"gnss_ins_wgs84.csv", "gnss_ins_epsg25832.csv",
                                                 "map_gnss_ins_tiles", "georef_gnss_ins.json"}));
  EXPECT_TRUE(fs::exists(other / "map_gnss_ins_tiles" / "index.json"));
  EXPECT_GE(Files(other / "map_gnss_ins_tiles").size(), 10u);

  // No origin: nothing written.
  const fs::path none = tmp_ / "none";
  fs::create_directories(none);
  ASSERT_TRUE(WriteGeoreferencedOutputs("full", MappingMode::kFull, traj_, map_, stamps_,
                                        std::nullopt, o, none)
                  .ok());
  EXPECT_TRUE(fs::is_empty(none));
}

TEST(GeoOutputOptionsTest, BadCrsOrTileSizeIsRefusedByName) {
  GeoOutputOptions o;
  EXPECT_TRUE(o.Validate().ok());
  o.crs = "EPSG:4326";
  EXPECT_THAT(o.Validate().message(), HasSubstr("--crs"));
  EXPECT_THAT(o.Validate().message(), HasSubstr("geographic"));
  o.crs = "EPSG:99999";
  EXPECT_THAT(o.Validate().message(), HasSubstr("unknown"));
  o.crs = "EPSG:32632";
  EXPECT_TRUE(o.Validate().ok());
  o.las_tile_size_m = -1.0;
  EXPECT_THAT(o.Validate().message(), HasSubstr("--las-tile-size"));
}

// Real KITTI 0013 (50 frames), gnss_ins: the WGS-84 CSV against the drive's own OXTS records,
// whose conventions are independent of ours (roll + = left side up, pitch + = front down, yaw from
// east counter-clockwise), and the LAS GPS times against the scans (2011: GPS = UTC + 15 s).
TEST(GeoreferencedOutputsKittiTest, Wgs84CsvAgreesWithOxtsAndLasTimesWithTheScans) {
  SLAM_MMS_REQUIRE_KITTI_RAW();
  const fs::path drive = ::slam_mms::testing::KittiRawDriveDir();
  auto reader = KittiDriveReader::Open(drive, KittiRawReader::Options());
  ASSERT_TRUE(reader.ok()) << reader.status().ToString();
  auto raw = KittiRawReader::Open(drive);
  ASSERT_TRUE(raw.ok());
  MappingSystem::Options o;
  o.mode = MappingMode::kGnssIns;
  o.T_body_lidar = (*reader)->streams().T_body_lidar;
  const DriveRun run = RunDrive(**reader, o);
  ASSERT_TRUE(run.status.ok()) << run.status.ToString();
  ASSERT_EQ(run.trajectory.size(), 50u);
  const ::slam_mms::testing::ScopedTempDir out_dir("georef_kitti");
  const fs::path& out = out_dir.path;
  ASSERT_TRUE(WriteGeoreferencedOutputs("gnss_ins", run.mode, run.trajectory, run.map,
                                        run.map_stamps, run.origin, GeoOutputOptions(), out)
                  .ok());
  std::ifstream in(out / "gnss_ins_wgs84.csv");
  std::string line;
  std::getline(in, line);
  const std::vector<StampedOxts>& oxts = raw->OxtsRecords();
  std::vector<double> horizontal, heading, pitch, roll;
  while (std::getline(in, line)) {
    std::vector<double> v;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) v.push_back(cell.empty() ? NAN : std::stod(cell));
    const auto t = static_cast<int64_t>(std::stoll(line.substr(0, line.find(','))));
    // OXTS linearly interpolated at the pose's time.
    auto it = std::lower_bound(oxts.begin(), oxts.end(), t, [](const StampedOxts& a, int64_t x) {
      return a.stamp.nanoseconds() < x;
    });
    if (it == oxts.begin() || it == oxts.end()) continue;
    const OxtsRecord& a = std::prev(it)->record;
    const OxtsRecord& b = it->record;
    const double w =
        static_cast<double>(t - std::prev(it)->stamp.nanoseconds()) /
        static_cast<double>(it->stamp.nanoseconds() - std::prev(it)->stamp.nanoseconds());
    const auto lerp = [w](double x, double y) { return x + w * (y - x); };
    const double dn = (v[2] - lerp(a.lat_deg, b.lat_deg)) * 111200.0;
    const double de = (v[3] - lerp(a.lon_deg, b.lon_deg)) * 111200.0 * std::cos(v[2] * M_PI / 180);
    horizontal.push_back(std::hypot(dn, de));
    const double oxts_heading = 90.0 - lerp(a.yaw_rad, b.yaw_rad) * 180.0 / M_PI;
    heading.push_back(std::abs(std::remainder(v[7] - oxts_heading, 360.0)));
    pitch.push_back(std::abs(v[6] + lerp(a.pitch_rad, b.pitch_rad) * 180.0 / M_PI));
    roll.push_back(std::abs(v[5] - lerp(a.roll_rad, b.roll_rad) * 180.0 / M_PI));
  }
  ASSERT_GT(horizontal.size(), 40u);
  const auto median = [](std::vector<double> x) {
    std::nth_element(x.begin(), x.begin() + x.size() / 2, x.end());
    return x[x.size() / 2];
  };
  std::printf(
      "KITTI 0013 gnss_ins vs OXTS (median): horizontal %.3f m, heading %.3f deg, pitch "
      "%.3f deg, roll %.3f deg\n",
      median(horizontal), median(heading), median(pitch), median(roll));
  EXPECT_LT(median(horizontal), 0.3);
  EXPECT_LT(median(heading), 0.5);
  EXPECT_LT(median(pitch), 0.3);  // a sign error would give ~2 x 0.5 deg (the drive's pitch)
  EXPECT_LT(median(roll), 0.3);

  auto las = ReadLas(out / "map_gnss_ins.las");
  ASSERT_TRUE(las.ok());
  ASSERT_EQ(las->points_utm.size(), run.map.size());
  const double first_s = run.trajectory.start().seconds();
  const double last_s = (*reader)->ScanEnd((*reader)->NumScans() - 1).seconds();
  for (size_t k = 0; k < las->gps_time.size(); k += 97) {
    const double utc_s = las->gps_time[k] + 1e9 - 15.0 + 315964800.0;
    ASSERT_GE(utc_s, first_s - 1e-5) << k;
    ASSERT_LE(utc_s, last_s + 1e-5) << k;
    ASSERT_LT(las->point_source_id[k], 50);
  }
}

}  // namespace
}  // namespace slam_mms
