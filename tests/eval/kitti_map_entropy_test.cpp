// Mean map entropy on real data: maps of KITTI raw drive 0013 built from its OXTS poses are
// sharpest (lowest entropy) when the scans are de-skewed with the right per-point time model
// (ARCHITECTURE.md: clockwise -1.11 < no de-skew -1.09 < counter-clockwise -1.04). A metric that
// cannot rank these is useless for comparing methods, so this is the metric's sensitivity test.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "testing/test_data.hpp"

namespace slam_mms::eval {
namespace {

// OXTS record -> T_world_body in a local ENU frame at the first record (WGS-84 ellipsoid radii;
// exact to millimetres over the 60 m of this drive).
Trajectory OxtsTrajectory(const std::vector<StampedOxts>& records) {
  constexpr double a = 6378137.0, e2 = 6.69437999014e-3;
  const double lat0 = records.front().record.lat_deg * M_PI / 180.0;
  const double s = std::sin(lat0);
  const double n_radius = a / std::sqrt(1.0 - e2 * s * s);
  const double m_radius = a * (1.0 - e2) / std::pow(1.0 - e2 * s * s, 1.5);
  Trajectory t;
  for (const StampedOxts& r : records) {
    const double dlat = (r.record.lat_deg - records.front().record.lat_deg) * M_PI / 180.0;
    const double dlon = (r.record.lon_deg - records.front().record.lon_deg) * M_PI / 180.0;
    const Eigen::Vector3d p(n_radius * std::cos(lat0) * dlon, m_radius * dlat,
                            r.record.alt_m - records.front().record.alt_m);
    EXPECT_TRUE(t.Add(r.stamp, MakeIsometry(FromRollPitchYaw(r.record.roll_rad, r.record.pitch_rad,
                                                             r.record.yaw_rad),
                                            p))
                    .ok());
  }
  return t;
}

// The map of scans 1..num_scans with every point placed by the body pose at its own time.
// Scan 0 is left out: the OXTS records start at its trigger, after its first firings.
StatusOr<PointCloud> BuildMap(const KittiRawReader::Options& options, size_t num_scans,
                              double max_range_m) {
  SLAM_MMS_ASSIGN_OR_RETURN(KittiRawReader reader,
                            KittiRawReader::Open(slam_mms::testing::KittiRawDriveDir(), options));
  const Trajectory poses = OxtsTrajectory(reader.OxtsRecords());
  const Eigen::Isometry3d T_body_lidar = reader.T_body_lidar();
  PointCloud map;
  for (size_t i = 1; i <= std::min(num_scans, reader.NumScans() - 1); ++i) {
    SLAM_MMS_ASSIGN_OR_RETURN(const Scan scan, reader.ReadScan(i));
    for (size_t k = 0; k < scan.cloud.size(); ++k) {
      const Eigen::Vector3d p_lidar = scan.cloud.points()[k].cast<double>();
      if (p_lidar.norm() > max_range_m) continue;
      // Without per-point time every point takes the scan's KITTI stamp (trigger, about mid-scan).
      const Timestamp t = options.per_point_time
                              ? scan.stamp_start.PlusSeconds(scan.cloud.time_offsets_s()[k])
                              : scan.stamp_trigger;
      StatusOr<Eigen::Isometry3d> T_world_body = poses.Interpolate(t);
      if (!T_world_body.ok()) continue;
      map.Add((*T_world_body * T_body_lidar * p_lidar).cast<float>());
    }
  }
  return map;
}

TEST(KittiMapEntropyTest, RightDeskewGivesTheSharpestMap) {
  SLAM_MMS_REQUIRE_KITTI_RAW();
  constexpr size_t kScans = 10;
  constexpr double kMaxRange = 30.0;
  KittiRawReader::Options clockwise;  // the reader's default: clockwise per-point time
  KittiRawReader::Options none;
  none.per_point_time = false;
  KittiRawReader::Options counter;
  counter.spin = SpinDirection::kCounterClockwise;

  double h[3] = {0, 0, 0};
  const KittiRawReader::Options* variants[3] = {&clockwise, &none, &counter};
  const char* names[3] = {"clockwise", "no de-skew", "counter-clockwise"};
  for (int v = 0; v < 3; ++v) {
    const StatusOr<PointCloud> map = BuildMap(*variants[v], kScans, kMaxRange);
    ASSERT_TRUE(map.ok()) << map.status().ToString();
    const StatusOr<MapEntropyResult> r = ComputeMapEntropy(*map);
    ASSERT_TRUE(r.ok());
    h[v] = r->mean_map_entropy;
    std::printf(
        "drive 0013, %zu scans, range <= %.0f m, %s: %zu points, %zu voxels, %zu valid, "
        "MME %.4f, plane variance %.3e m^2\n",
        kScans, kMaxRange, names[v], r->num_input_points, r->num_evaluated_points,
        r->num_valid_points, r->mean_map_entropy, r->mean_plane_variance_m2);
  }
  EXPECT_LT(h[0], h[1]);
  EXPECT_LT(h[1], h[2]);
}

}  // namespace
}  // namespace slam_mms::eval
