#pragma once
// Ground truth of a run, carried into the run's world frame (local ENU at MappingSystem::Origin())
// through WGS-84, never by aligning trajectories (ARCHITECTURE.md, "Compare in one frame"):
// - simulated drives: DRIVE_DIR/ground_truth/ (poses_100hz.tum + scan_start.tum in the
//   simulator's ENU, scenario.json with its WGS-84 origin): positions sim ENU -> geodetic
//   (GeographicLib LocalCartesian at the sim origin) -> run ENU (LocalCartesian at the run origin);
//   attitudes rotated by R_run_sim, the rotation between the two ENU tangent frames;
// - otherwise, for a KITTI raw drive, the OXTS records (lat/lon/alt -> run ENU; roll/pitch/yaw are
//   relative to the local level frame at each record, rotated into run ENU the same way);
// - otherwise (a folder or bag without ground_truth/): kNotFound, the run has no metrics.

#include <Eigen/Geometry>
#include <filesystem>
#include <string>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/io/drive_reader.hpp"

namespace slam_mms::app {

struct GroundTruth {
  std::string kind;                 ///< "simulator" or "oxts" (report.json input.ground_truth).
  Trajectory T_world_body;          ///< In the run's world frame.
  std::filesystem::path scene_map;  ///< The simulator's scene_points.ply ("" for OXTS).
  std::filesystem::path source;     ///< What it was read from (for messages).
};

/// True when `drive_dir`/ground_truth/ holds the simulator's files.
bool HasSimulatorGroundTruth(const std::filesystem::path& drive_dir);

/// The ground truth in the run ENU frame about `run_origin`: `gt_dir`/ground_truth/ (simulator),
/// else the OXTS records where `reader` is a KittiDriveReader, else kNotFound.
StatusOr<GroundTruth> LoadGroundTruth(const std::filesystem::path& gt_dir,
                                      const DriveReader& reader, const GeodeticPoint& run_origin);

/// Rotation of the ENU tangent frame at (lat, lon) into ECEF.
Eigen::Matrix3d R_ecef_enu(double latitude_deg, double longitude_deg);

/// The WGS-84 origin in a simulator scenario.json ("origin_wgs84": {...}).
StatusOr<GeodeticPoint> ReadScenarioOrigin(const std::filesystem::path& scenario_json);

}  // namespace slam_mms::app
