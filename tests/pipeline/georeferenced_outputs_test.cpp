// WriteGeoreferencedOutputs: the file set of each method and option, what the LAS carries from the
// map's stamps, and the option checks that run before any processing.
#include "slam_mms/pipeline/georeferenced_outputs.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <set>

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

}  // namespace
}  // namespace slam_mms
