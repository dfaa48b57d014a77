#pragma once
// PNG plots of slam_mms_run (trajectories, position error, GNSS status, map height) and
// report.html, from the runs and their evaluations (outputs.hpp).

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "slam_mms/eval/ground_truth.hpp"
#include "slam_mms/eval/outage_error.hpp"
#include "slam_mms/eval/report.hpp"
#include "slam_mms_run/outputs.hpp"
#include "slam_mms_run/run_mode.hpp"

namespace slam_mms::app {

/// trajectories.png and position_error.png (with a ground truth), gnss_status.png (methods with
/// scans), map_<name>_height.png (every method with a map but lidar_only). Logs failures.
void WritePlots(const std::vector<ModeRun>& runs, const std::vector<MethodEvaluation>& evals,
                const eval::GroundTruth* gt, const std::vector<eval::OutageWindow>& outages,
                Timestamp reference, const std::filesystem::path& out_dir);

/// The plots of `runs` that exist in out_dir, in report order, with their captions.
std::vector<std::pair<std::string, std::string>> PlotFilesOf(const std::vector<ModeRun>& runs,
                                                             const std::filesystem::path& out_dir);

/// A one-line description of an output file or folder name (e.g. "full_wgs84.csv"), knowing the
/// method names; "" when unknown.
std::string DescribeOutputFile(const std::string& name, const std::vector<std::string>& methods);

/// out_dir/report.html (eval::WriteHtmlReport): the run summary from `report` (input, duration,
/// scans processed/skipped, ground truth, GNSS outages, complete, command line), `warnings`
/// (main's) plus those the runs carry (skipped scans, errors, incomplete runs), the metrics table
/// of `evals`, the plots that exist in out_dir (PlotFilesOf), the georeference from
/// report.georef_json and the files in out_dir with one-line descriptions. Call it last, after
/// every other output is written (the file list is read from out_dir).
[[nodiscard]] Status WriteReportHtml(const eval::EvalReport& report,
                                     const std::vector<ModeRun>& runs,
                                     const std::vector<MethodEvaluation>& evals,
                                     const std::vector<std::string>& warnings,
                                     const std::filesystem::path& out_dir);

}  // namespace slam_mms::app
