#pragma once
// Ground truth of a run (what slam_mms_run and the Python run_drive evaluate against), carried
// into the run's world frame (local ENU at MappingSystem::Origin()) through WGS-84, never by
// aligning trajectories (ARCHITECTURE.md, "Compare in one frame"):
// - simulated drives: DRIVE_DIR/ground_truth/ (poses_100hz.tum + scan_start.tum in the
//   simulator's ENU, scenario.json with its WGS-84 origin): positions sim ENU -> geodetic
//   (GeographicLib LocalCartesian at the sim origin) -> run ENU (LocalCartesian at the run origin);
//   attitudes rotated by R_run_sim, the rotation between the two ENU tangent frames;
// - otherwise, for a KITTI raw drive, the OXTS records (lat/lon/alt -> run ENU; roll/pitch/yaw are
//   relative to the local level frame at each record, rotated into run ENU the same way);
// - otherwise (a folder or bag without ground_truth/): kNotFound, the run has no metrics.
// The result is what eval::ComputeAte / ComputeRelativeError take as the ground truth of a
// trajectory in that world frame (report.json input.ground_truth = GroundTruth::kind).
//
// Errors: kNotFound where there is no ground truth; kDataLoss (naming the file and field) for a
// malformed scenario.json or TUM file. Thread safety: free functions; reads files only.

#include <filesystem>
#include <string>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/eval/oxts_reference.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/io/drive_reader.hpp"

namespace slam_mms::eval {

struct GroundTruth {
  std::string kind;  ///< "simulator", "oxts" or "oxts_velocity" (report.json input.ground_truth).
  Trajectory T_world_body;          ///< In the run's world frame.
  std::filesystem::path scene_map;  ///< The simulator's scene_points.ply ("" for OXTS).
  std::filesystem::path source;     ///< What it was read from (for messages).
};

/// True when `drive_dir`/ground_truth/ holds the simulator's files.
bool HasSimulatorGroundTruth(const std::filesystem::path& drive_dir);

/// The ground truth in the run ENU frame about `run_origin` (MappingSystem::Origin()):
/// `gt_dir`/ground_truth/ (simulator), else the OXTS records where `reader` is a
/// KittiDriveReader (the 100 Hz ones where the drive has them), else kNotFound. `gt_dir` is the
/// drive folder, or the folder holding a bag.
StatusOr<GroundTruth> LoadGroundTruth(const std::filesystem::path& gt_dir,
                                      const DriveReader& reader, const GeodeticPoint& run_origin);

/// The OXTS records of a KITTI raw drive (the 100 Hz ones where it has them; a simulated drive
/// has them too, beside its ground_truth/) as a reference in the run ENU frame, with recorded or
/// velocity-integrated positions (eval/oxts_reference.hpp; kind "oxts" or "oxts_velocity");
/// kNotFound for other drives.
StatusOr<GroundTruth> LoadOxtsGroundTruth(const DriveReader& reader,
                                          const GeodeticPoint& run_origin, OxtsPositions positions);

/// The WGS-84 origin in a simulator scenario.json ("origin_wgs84": {...}).
StatusOr<GeodeticPoint> ReadScenarioOrigin(const std::filesystem::path& scenario_json);

}  // namespace slam_mms::eval
