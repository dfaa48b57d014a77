#pragma once
// Outputs of slam_mms_run: per-method trajectory and map files, the metrics of each method against
// the ground truth (eval), report.json (issue 8's exact schema) and the summary table. The PNG
// plots are in plot_outputs.hpp.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/eval/ground_truth.hpp"
#include "slam_mms/eval/outage_error.hpp"
#include "slam_mms/eval/report.hpp"
#include "slam_mms/eval/trajectory_error.hpp"
#include "slam_mms_run/run_mode.hpp"

namespace slam_mms::app {

/// <name>.tum, <name>.kitti, <name>_cov.csv, <name>_scans.csv, <name>_level1.tum; for the methods
/// with a map also map_<name>.ply/.pcd (local ENU). The geo-referenced files (WGS-84/projected CSV,
/// LAS) are WriteGeoOutputs' (geo_outputs.hpp). Returns the first failure (all are attempted).
Status WriteMethodFiles(const ModeRun& run, const std::filesystem::path& out_dir);

/// One method's metrics plus what the plots and the table need.
struct MethodEvaluation {
  std::string name;
  eval::MethodReport report;
  std::optional<eval::AteResult> ate;  ///< Absent without ground truth.
  std::string relative_label;          ///< "kitti_100-800m" or "short_10-80m".
  size_t relative_segments = 0;
  size_t outage_poses = 0;
  size_t mme_points = 0;
};

/// The map entropy EvaluateMethod reports for `map` (the paper's r, voxel and minimum).
StatusOr<eval::MapEntropyResult> MapEntropyOf(const PointCloud& map, int num_threads);

/// ATE, rotation RMSE, KITTI relative error (devkit lengths when the ground-truth path is at least
/// 400 m, else the short 10-80 m lengths, named so), outage errors (windows relative to
/// `reference`), map entropy (ModeRun::map_entropy where set); scans/s and peak RSS from the run.
/// `gt` may be null.
MethodEvaluation EvaluateMethod(const ModeRun& run, const eval::GroundTruth* gt,
                                const std::vector<eval::OutageWindow>& outages, Timestamp reference,
                                int num_threads);

/// ATE, rotation RMSE, relative error (lengths as EvaluateMethod) and the largest position error
/// in the outages of the run's trajectory against a second reference (an OXTS ground truth's
/// integrated velocities).
eval::ReferenceMetrics EvaluateAgainst(const ModeRun& run, const Trajectory& T_world_reference,
                                       const std::vector<eval::OutageWindow>& outages,
                                       Timestamp reference);

/// The methods side by side (ATE, rot RMSE, t_rel, max error in outages, MME, scans/s, RSS).
std::string SummaryTable(const std::vector<MethodEvaluation>& evals,
                         const std::optional<double>& gt_map_mme, const std::string& gt_kind);

}  // namespace slam_mms::app
