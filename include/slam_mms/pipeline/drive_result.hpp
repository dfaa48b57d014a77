#pragma once
// DriveResult: a finished drive as the multi-drive adjustment needs it: every submap with its
// final pose, its scans' poses in the submap frame and its clouds (submap frame), every level-2
// factor as it was added (SubmapGraph::Factors()), the world origin and the GNSS availability.
// MappingSystem::ExportDriveResult() gives it after Finish(); the merge module writes and reads
// it (a versioned folder, merge/drive_result_io.hpp) and rebuilds the drives' graphs in one.
//
// Thread safety: value type.

#include <Eigen/Geometry>
#include <vector>

#include "slam_mms/backend/submap_graph.hpp"
#include "slam_mms/core/geodesy.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/ins/gnss_prior.hpp"

namespace slam_mms {

struct DriveSubmap {
  SubmapId id = 0;
  Timestamp start;
  Timestamp end;
  Eigen::Isometry3d T_world_submap = Eigen::Isometry3d::Identity();  ///< Final (level 2).
  /// The submap's scans: scan_id, stamp and T_submap_scan (T_world_scan as of the export).
  std::vector<SubmapScanPose> scans;
  std::vector<Matrix6d> cov_submap_scan;  ///< Per scan, rotation first (level 1).
  PointCloud map_cloud;                   ///< De-skewed, voxel-downsampled points, submap frame.
  PointCloud registration_cloud;          ///< The coarser cloud of map-to-map registration.
};

struct DriveResult {
  GeodeticPoint origin;  ///< WGS-84 origin of the drive's local ENU world.
  Eigen::Isometry3d T_body_lidar = Eigen::Isometry3d::Identity();
  std::vector<DriveSubmap> submaps;        ///< In id order.
  std::vector<SubmapGraphFactor> factors;  ///< Level 2's factors, as added.
  std::vector<GnssAvailabilityInterval> gnss_availability;

  /// T_world_body of every scan (T_world_submap * T_submap_scan) in time order; with
  /// `T_world_submap` (one per submap, in `submaps` order), at those submap poses instead.
  std::vector<std::pair<Timestamp, Eigen::Isometry3d>> ScanPoses(
      const std::vector<Eigen::Isometry3d>* T_world_submap = nullptr) const;
};

}  // namespace slam_mms
