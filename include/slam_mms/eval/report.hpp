#pragma once
// EvalReport: the contents of slam_mms_run's report.json (nlohmann-json, 2-space indent, doubles
// written so that they read back exactly, every metric not computed written as null). The issue-8
// keys stay as they were (other tools parse them); issue 22 added the others (marked +):
//
//   {"version": str,                        + library version (SLAM_MMS_VERSION_STRING)
//    "complete": bool,                      + false: the run stopped early (error, SIGINT)
//    "command_line": [str, ...],            + argv as given
//    "input": {"drive": str, "kind": "kitti_raw"|"folder"|"rosbag"|"simulated"|null (+),
//              "scans": int (= scans_processed), "scans_total": int|null (+),
//              "scans_processed": int (+), "duration_s": float,
//              "ground_truth": "simulator"|"oxts"|"none",
//              "skipped_scans": {"count": int, "scans": [{"source": str, "reason": str}]} (+)},
//    "gnss_outages": [[start_s, duration_s], ...],
//    "methods": {"full"|"gnss_ins"|"gnss_ins_smoothed"|"lidar_only": {
//        "ate_rmse_m": f, "ate_rmse_xyz_m": [f,f,f], "rot_rmse_deg": f, "rot_rmse_rpy_deg":
//        [f,f,f], "rot_mean_rpy_deg": [f,f,f] (signed), "t_rel_pct": f|null, "r_rel_deg_per_100m":
//        f|null, "max_pos_err_in_outage_m": f|null, "max_rot_err_in_outage_deg": f|null, "mme": f,
//        "nees": {...}|null, "scans_per_s": f, "peak_rss_mb": f,
//        "vs_oxts_velocity": {"ate_rmse_m": f|null, "rot_rmse_deg": f|null, "t_rel_pct": f|null,
//          "r_rel_deg_per_100m": f|null, "max_pos_err_in_outage_m": f|null}|null (+: an OXTS
//          ground truth's second reference, its velocities integrated: eval/oxts_reference.hpp)}},
//    "ground_truth_map": {"mme": f|null},
//    "options": {...}|null,                 + the effective MappingSystem options (config tree)
//    "georef": {...}|null,                  + the output CRS and origin (georef.json's object)
//    "warnings": [str, ...],                + what the run warned about (outage windows outside
//                                             the drive, a stop by a signal, ...)
//    "outputs": {"files": [str, ...]}}      + files written (only when the caller lists some)
//
// "options" and "georef" are JSON object texts the caller passes (EvalReport::options_json,
// georef_json) and that are parsed and embedded; text that is not a JSON object is an error.
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

/// A scan the run did not use (unreadable file, bad stamp, ...): written in
/// input.skipped_scans.scans.
struct SkippedScan {
  std::string source;  ///< The file or bag message (e.g. ".../0000000005.bin").
  std::string reason;  ///< Why (the reader's message).
};

struct ReportInput {
  std::string drive;  ///< Drive folder or name.
  /// "kitti_raw", "folder", "rosbag" or "simulated"; empty = unknown (null).
  std::string kind;
  int64_t scans = 0;         ///< Scans processed ("scans" and "scans_processed").
  int64_t scans_total = -1;  ///< Scans in the input's frame range; < 0 = unknown (null).
  double duration_s = 0.0;   ///< Drive duration covered [s].
  /// "simulator", "oxts" or "none" (a folder or bag without ground truth: metrics are null).
  std::string ground_truth = "simulator";
  std::vector<SkippedScan> skipped_scans;
  /// Where the IMU noise model came from (an imu_noise.yaml); empty: the filter's defaults (null).
  std::string imu_noise;
  /// KITTI raw input: how long before its OXTS record each IMU sample was stamped [s]
  /// (KittiRawReader::oxts_inertial_delay_s); absent for other inputs (null).
  std::optional<double> oxts_inertial_delay_s;
};

/// A method's trajectory against a second reference; nullopt is written as null.
struct ReferenceMetrics {
  std::optional<double> ate_rmse_m;
  std::optional<double> rot_rmse_deg;
  std::optional<double> t_rel_pct;
  std::optional<double> r_rel_deg_per_100m;
  std::optional<double> max_pos_err_in_outage_m;
};

/// The fields of ReferenceMetrics from results; a null pointer leaves its fields null (as
/// MakeMethodReport).
ReferenceMetrics MakeReferenceMetrics(const AteResult* ate, const RelativeErrorResult* relative,
                                      const OutageErrorResult* outage);

/// One method's numbers; nullopt is written as null.
struct MethodReport {
  std::optional<double> ate_rmse_m;
  std::optional<Eigen::Vector3d> ate_rmse_xyz_m;
  std::optional<double> rot_rmse_deg;
  std::optional<Eigen::Vector3d> rot_rmse_rpy_deg;
  std::optional<Eigen::Vector3d> rot_mean_rpy_deg;  ///< AteResult::rot_mean_rpy_deg (signed).
  std::optional<double> t_rel_pct;
  std::optional<double> r_rel_deg_per_100m;
  std::optional<double> max_pos_err_in_outage_m;
  std::optional<double> max_rot_err_in_outage_deg;
  std::optional<double> mme;
  /// The covariance's consistency (ComputeNees) for the POS methods with their absolute
  /// covariances (gnss_ins, gnss_ins_smoothed); null for the others.
  std::optional<NeesResult> nees;
  std::optional<double> scans_per_s;
  std::optional<double> peak_rss_mb;
  /// Where the ground truth is an OXTS's recorded positions: the same trajectory against the
  /// OXTS's velocities integrated from its first record (sharper over seconds, not absolute:
  /// eval/oxts_reference.hpp); null otherwise.
  std::optional<ReferenceMetrics> vs_oxts_velocity;
};

/// Fills the metric fields of a MethodReport from results; a null pointer leaves its fields null.
/// Relative errors with no segment (NaN) and outage results with no pose inside a window stay null.
MethodReport MakeMethodReport(const AteResult* ate, const RelativeErrorResult* relative,
                              const OutageErrorResult* outage, const MapEntropyResult* entropy,
                              const NeesResult* nees = nullptr);

struct EvalReport {
  ReportInput input;
  std::vector<OutageWindow> gnss_outages;
  /// Method name ("full", "gnss_ins", "gnss_ins_smoothed" or "lidar_only") and its numbers,
  /// written in this order.
  std::vector<std::pair<std::string, MethodReport>> methods;
  std::optional<double> ground_truth_map_mme;
  /// argv as given ("command_line").
  std::vector<std::string> command_line;
  /// The effective options as a JSON object text (slam_mms_run: app::OptionsToJson); empty = null.
  std::string options_json;
  /// The geo-reference as a JSON object text (georef.json's); empty = null.
  std::string georef_json;
  /// The boresight self-calibration (slam_mms_run --calibrate-extrinsics) as a JSON object text
  /// (docs/calibration.md); empty = null.
  std::string extrinsics_json;
  /// False where the run stopped before the end of the drive (error, interrupt).
  bool complete = true;
  /// The run's warnings, in order ("warnings": always written, [] when none).
  std::vector<std::string> warnings;
  /// Files written, relative to the output folder ("outputs": {"files": [...]}); empty = no
  /// "outputs" key.
  std::vector<std::string> outputs;
};

/// The method names report.json allows.
bool IsReportMethodName(const std::string& name);

/// report.json text. Fails where ground_truth is not "simulator"/"oxts"/"none", input.kind is not
/// one of the four kinds (or empty), a method name is not one of the allowed four or appears
/// twice, or options_json/georef_json is not empty and not a JSON object.
StatusOr<std::string> ReportToJson(const EvalReport& report);

/// Writes ReportToJson(report) to `path` (fails naming the path when it cannot be written).
Status WriteReportJson(const EvalReport& report, const std::filesystem::path& path);

/// Peak resident set size of this process [MB] (Linux /proc/self/status VmHWM); nullopt elsewhere.
std::optional<double> PeakRssMb();

}  // namespace slam_mms::eval
