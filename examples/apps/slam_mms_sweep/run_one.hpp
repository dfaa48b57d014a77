#pragma once
// One run of the robustness sweep, in its own process (slam_mms_sweep --run-one DIR): simulates
// the run's window of a real KITTI motion into DIR/sim, runs each mapping method on it exactly as
// slam_mms_run does (RunMode, the library defaults or --config), evaluates each against the
// simulator's ground truth (EvaluateMethod, slam_mms_run's metrics), and writes DIR/result.json.
// A crash or hang therefore costs one run, never the sweep.
//
// DIR/spec.json holds the run (SpecToJson); DIR/result.json:
//   {"spec": {...}, "sim": {"scans", "path_m", "fraction_fixed", ..., "wall_s"},
//    "methods": {"<mode>": {"status", "complete", "finite", "scans_processed", "scans_total",
//        "skipped_scans", "ate_rmse_m", "rot_rmse_deg", "t_rel_pct", "r_rel_deg_per_100m",
//        "max_pos_err_m", "max_drift_from_start_m" (the largest position error once the first
//        poses are aligned: the method's own drift), "max_pos_err_in_outage_m",
//        "max_rot_err_in_outage_deg", "mme", "degenerate_fraction", "scans_per_s", "wall_s"}}}
// Metrics that do not exist (no segment, no pose in an outage) are null. "sim" also holds
// "calibration_file_error" ({"rot_deg", "xyz_m"}: the calibration file against the truth); where
// the config sets drive.estimate_extrinsics, "calibration" holds slam_mms_run's report.json
// "extrinsics" (correction, sigmas, which parameters were observable and applied, wall time),
// "error" against the truth and "run_with_estimate" (false, with "status", where it could not
// run). --real-one puts the same in "real"/"real_uncorrected" "calibration".
//
// The real-frame check (slam_mms_sweep --real-one DIR): lidar_only on the real KITTI frames,
// relative error over 10..50 m segments against the OXTS poses, into DIR/result.json as
//   {"real": {"drive", "kitti_vertical_correction_deg", "frames", "path_m", "t_rel_pct",
//   "r_rel_deg_per_100m", "t_rel_pct_by_length": {...}, "r_rel_deg_per_100m_by_length": {...},
//   "scans_per_s"}, "real_uncorrected": {the same}}.
// "real" reads the frames as the public peer does (KISS-ICP corrects every KITTI scan's vertical
// angle by kKittiVerticalCorrectionDeg); "real_uncorrected" as recorded, for the record.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms_sweep/plan.hpp"

namespace slam_mms::sweep {

/// KITTI's HDL-64E vertical-angle correction [deg] (DriveSourceOptions), the published value the
/// peer applies (KISS-ICP, CT-ICP); not fitted to the frames here.
inline constexpr double kKittiVerticalCorrectionDeg = 0.205;

/// What a child process needs besides the run.
struct RunSettings {
  std::vector<std::string> modes = {"gnss_ins", "gnss_ins_smoothed", "full", "lidar_only"};
  std::filesystem::path config;  ///< A slam_mms_run --config YAML; empty = library defaults.
  bool keep_drive = false;       ///< Keep DIR/sim.
  int num_threads = 2;           ///< Simulator and map-entropy threads.
};

nlohmann::json SpecToJson(const SweepRun& run, const RunSettings& settings);
Status SpecFromJson(const nlohmann::json& j, SweepRun* run, RunSettings* settings);

/// The child's work; returns the process exit status (0 = result.json written).
int RunOne(const std::filesystem::path& run_dir);

/// The real-frame lidar_only check; `drive_dir` = .../kitti_raw/2011_09_26/<drive>_sync.
int RealOne(const std::filesystem::path& run_dir, const std::filesystem::path& drive_dir,
            const std::filesystem::path& config);

}  // namespace slam_mms::sweep
