// eval::LoadGroundTruth and friends (eval/ground_truth.hpp): the simulator's ground_truth/ carried
// into a run's world frame through WGS-84 (not aligned), scenario.json errors, no ground truth for
// a reader that is not KITTI raw (kNotFound), and R_ecef_enu (core/geodesy.hpp).
#include "slam_mms/eval/ground_truth.hpp"

#include <gtest/gtest.h>

#include <GeographicLib/LocalCartesian.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "slam_mms/core/geodesy.hpp"
#include "testing/test_data.hpp"

namespace slam_mms::eval {
namespace {

namespace fs = std::filesystem;

// A reader with no scans that is not a KittiDriveReader.
class EmptyReader : public DriveReader {
 public:
  std::string Describe() const override { return "empty reader"; }
  size_t NumScans() const override { return 0; }
  Timestamp ScanStart(size_t) const override { return Timestamp(); }
  Timestamp ScanEnd(size_t) const override { return Timestamp(); }
  std::string ScanSource(size_t) const override { return ""; }
  StatusOr<Scan> ReadScan(size_t) const override { return NotFoundError("no scan"); }
  const DriveStreams& streams() const override { return streams_; }
  uint64_t TotalDroppedPoints() const override { return 0; }

 private:
  DriveStreams streams_;
};

constexpr double kLat = 49.011, kLon = 8.4237, kH = 112.5;

void WriteSimGroundTruth(const fs::path& drive) {
  fs::create_directories(drive / "ground_truth");
  std::ofstream(drive / "ground_truth/scenario.json")
      << "{\n  \"name\": \"test\",\n  \"origin_wgs84\": {\"latitude_deg\": " << kLat
      << ", \"longitude_deg\": " << kLon << ", \"height_m\": " << kH << "}\n}\n";
  // Two poses 100 m apart along east, yaw 90 deg at the second; one scan start in between.
  std::ofstream(drive / "ground_truth/poses_100hz.tum")
      << "1000.000000000 0 0 0 0 0 0 1\n1010.000000000 100 0 0 0 0 0.7071067811865476 "
         "0.7071067811865476\n";
  std::ofstream(drive / "ground_truth/scan_start.tum") << "1005.000000000 50 0 0 0 0 0 1\n";
}

TEST(GroundTruthTest, SimulatorGroundTruthInTheSimulatorFrameIsUnchanged) {
  const fs::path dir = testing::MakeTempDir("slam_mms_eval_gt_same");
  WriteSimGroundTruth(dir);
  ASSERT_TRUE(HasSimulatorGroundTruth(dir));
  const EmptyReader reader;
  StatusOr<GroundTruth> gt = LoadGroundTruth(dir, reader, GeodeticPoint{kLat, kLon, kH});
  ASSERT_TRUE(gt.ok()) << gt.status().ToString();
  EXPECT_EQ(gt->kind, "simulator");
  ASSERT_EQ(gt->T_world_body.size(), 3u);  // the scan start merged into the 100 Hz poses
  const auto& p = gt->T_world_body.poses();
  EXPECT_EQ(p[1].stamp.nanoseconds(), 1005'000'000'000);
  EXPECT_NEAR(p[1].T_world_body.translation().x(), 50.0, 1e-8);
  EXPECT_NEAR(p[2].T_world_body.translation().x(), 100.0, 1e-8);
  EXPECT_NEAR(p[2].T_world_body.translation().norm(), 100.0, 1e-8);
  EXPECT_TRUE(p[2].T_world_body.linear().isApprox(
      Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix(), 1e-12));
  EXPECT_TRUE(gt->scene_map.empty());
  fs::remove_all(dir);
}

TEST(GroundTruthTest, SimulatorGroundTruthIsCarriedThroughWgs84IntoAnotherOrigin) {
  const fs::path dir = testing::MakeTempDir("slam_mms_eval_gt_moved");
  WriteSimGroundTruth(dir);
  const GeodeticPoint run_origin{kLat + 0.01, kLon - 0.02, kH + 3.0};  // ~1.1 km N, ~1.5 km W
  const EmptyReader reader;
  StatusOr<GroundTruth> gt = LoadGroundTruth(dir, reader, run_origin);
  ASSERT_TRUE(gt.ok()) << gt.status().ToString();
  // Expected: the second pose's geodetic position in the run's ENU frame.
  const GeographicLib::LocalCartesian sim(kLat, kLon, kH);
  const GeographicLib::LocalCartesian run(run_origin.latitude_deg, run_origin.longitude_deg,
                                          run_origin.height_m);
  double lat, lon, h, x, y, z;
  sim.Reverse(100, 0, 0, lat, lon, h);
  run.Forward(lat, lon, h, x, y, z);
  const Eigen::Vector3d got = gt->T_world_body.poses()[2].T_world_body.translation();
  EXPECT_NEAR(got.x(), x, 1e-6);
  EXPECT_NEAR(got.y(), y, 1e-6);
  EXPECT_NEAR(got.z(), z, 1e-6);
  EXPECT_GT(got.x(), 1400.0);  // the run origin lies west of the simulator's
  EXPECT_LT(got.y(), -1000.0);
  // Attitude: rotated by the angle between the two tangent frames (about 0.02 deg here).
  const Eigen::Matrix3d R_run_sim =
      R_ecef_enu(run_origin.latitude_deg, run_origin.longitude_deg).transpose() *
      R_ecef_enu(kLat, kLon);
  EXPECT_TRUE(gt->T_world_body.poses()[0].T_world_body.linear().isApprox(R_run_sim, 1e-15));
  EXPECT_GT(Eigen::AngleAxisd(R_run_sim).angle(), 1e-4);
  fs::remove_all(dir);
}

TEST(GroundTruthTest, ScenarioErrorsNameTheFileAndField) {
  const fs::path dir = testing::MakeTempDir("slam_mms_eval_gt_bad");
  EXPECT_EQ(ReadScenarioOrigin(dir / "missing.json").status().code(), StatusCode::kNotFound);
  std::ofstream(dir / "a.json") << "{\"name\": 1}";
  StatusOr<GeodeticPoint> a = ReadScenarioOrigin(dir / "a.json");
  EXPECT_EQ(a.status().code(), StatusCode::kDataLoss);
  EXPECT_NE(a.status().message().find("origin_wgs84"), std::string::npos);
  std::ofstream(dir / "b.json")
      << "{\"origin_wgs84\": {\"latitude_deg\": 95, \"longitude_deg\": 1, \"height_m\": 0}}";
  EXPECT_EQ(ReadScenarioOrigin(dir / "b.json").status().code(), StatusCode::kDataLoss);
  std::ofstream(dir / "c.json")
      << "{\"origin_wgs84\": {\"latitude_deg\": 45, \"longitude_deg\": x, \"height_m\": 0}}";
  StatusOr<GeodeticPoint> c = ReadScenarioOrigin(dir / "c.json");
  EXPECT_NE(c.status().message().find("longitude_deg"), std::string::npos);
  fs::remove_all(dir);
}

TEST(GroundTruthTest, NoGroundTruthIsNotFound) {
  const fs::path dir = testing::MakeTempDir("slam_mms_eval_gt_none");
  EXPECT_FALSE(HasSimulatorGroundTruth(dir));
  const EmptyReader reader;
  StatusOr<GroundTruth> gt = LoadGroundTruth(dir, reader, GeodeticPoint{kLat, kLon, kH});
  EXPECT_EQ(gt.status().code(), StatusCode::kNotFound);
  EXPECT_NE(gt.status().message().find("empty reader"), std::string::npos);
  fs::remove_all(dir);
}

TEST(GeodesyTest, EnuAxesInEcef) {
  const Eigen::Matrix3d R = R_ecef_enu(0.0, 0.0);  // east = +y, north = +z, up = +x
  EXPECT_TRUE(R.col(0).isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_TRUE(R.col(1).isApprox(Eigen::Vector3d::UnitZ()));
  EXPECT_TRUE(R.col(2).isApprox(Eigen::Vector3d::UnitX()));
  const Eigen::Matrix3d R2 = R_ecef_enu(kLat, kLon);
  EXPECT_TRUE((R2.transpose() * R2).isApprox(Eigen::Matrix3d::Identity(), 1e-15));
  EXPECT_NEAR(R2.determinant(), 1.0, 1e-15);
}

}  // namespace
}  // namespace slam_mms::eval
