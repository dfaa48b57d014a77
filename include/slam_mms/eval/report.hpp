#pragma once
// EvalReport: the contents of slam_mms_run's report.json, written with EXACTLY the keys of the
// schema in issue 8 (other tools parse them); every metric not computed is written as null.
//
//   {"input": {"drive": str, "scans": int, "duration_s": float, "ground_truth":
//   "simulator"|"oxts"|"none"},
//    "gnss_outages": [[start_s, duration_s], ...],
//    "methods": {"full"|"gnss_ins"|"gnss_ins_smoothed"|"lidar_only": {
//        "ate_rmse_m": f, "ate_rmse_xyz_m": [f,f,f], "rot_rmse_deg": f, "rot_rmse_rpy_deg":
//        [f,f,f], "t_rel_pct": f|null, "r_rel_deg_per_100m": f|null, "max_pos_err_in_outage_m":
//        f|null, "max_rot_err_in_outage_deg": f|null, "mme": f, "scans_per_s": f, "peak_rss_mb":
//        f}},
//    "ground_truth_map": {"mme": f|null}}
//
// Thread safety: value types and free functions; safe to call concurrently on distinct objects.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/eval/outage_error.hpp"
#include "slam_mms/eval/relative_error.hpp"
#include "slam_mms/eval/trajectory_error.hpp"

namespace slam_mms::eval {

struct ReportInput {
  std::string drive;        ///< Drive folder or name.
  int64_t scans = 0;        ///< Scans processed.
  double duration_s = 0.0;  ///< Drive duration covered [s].
  /// "simulator", "oxts" or "none" (a folder or bag without ground truth: metrics are null).
  std::string ground_truth = "simulator";
};

/// One method's numbers; nullopt is written as null.
struct MethodReport {
  std::optional<double> ate_rmse_m;
  std::optional<Eigen::Vector3d> ate_rmse_xyz_m;
  std::optional<double> rot_rmse_deg;
  std::optional<Eigen::Vector3d> rot_rmse_rpy_deg;
  std::optional<double> t_rel_pct;
  std::optional<double> r_rel_deg_per_100m;
  std::optional<double> max_pos_err_in_outage_m;
  std::optional<double> max_rot_err_in_outage_deg;
  std::optional<double> mme;
  std::optional<double> scans_per_s;
  std::optional<double> peak_rss_mb;
};

/// Fills the metric fields of a MethodReport from results; a null pointer leaves its fields null.
/// Relative errors with no segment (NaN) and outage results with no pose inside a window stay null.
MethodReport MakeMethodReport(const AteResult* ate, const RelativeErrorResult* relative,
                              const OutageErrorResult* outage, const MapEntropyResult* entropy);

struct EvalReport {
  ReportInput input;
  std::vector<OutageWindow> gnss_outages;
  /// Method name ("full", "gnss_ins", "gnss_ins_smoothed" or "lidar_only") and its numbers,
  /// written in this order.
  std::vector<std::pair<std::string, MethodReport>> methods;
  std::optional<double> ground_truth_map_mme;
};

/// The method names report.json allows.
bool IsReportMethodName(const std::string& name);

/// report.json text. Fails where ground_truth is not "simulator"/"oxts", a method name is not one
/// of the allowed three or appears twice.
StatusOr<std::string> ReportToJson(const EvalReport& report);

/// Writes ReportToJson(report) to `path` (fails naming the path when it cannot be written).
Status WriteReportJson(const EvalReport& report, const std::filesystem::path& path);

/// Peak resident set size of this process [MB] (Linux /proc/self/status VmHWM); nullopt elsewhere.
std::optional<double> PeakRssMb();

}  // namespace slam_mms::eval
