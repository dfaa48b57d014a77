#pragma once
// The end of slam_mms_run (RunMain): after the methods ran, the ground truth in each run's world
// frame, the metrics and map entropies, plots, the summary table, report.json and report.html;
// and the file helpers the run's messages use (disk use, the list of outputs).
//
// Thread safety: not thread-safe (writes into --out); the app's one thread calls it.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms_run/checkpoint.hpp"
#include "slam_mms_run/cli.hpp"
#include "slam_mms_run/geo_outputs.hpp"
#include "slam_mms_run/run_mode.hpp"

namespace slam_mms::app {

/// What the report of a run needs from RunMain.
struct ReportInput {
  const RunArgs& args;
  const DriveReader& reader;
  const std::filesystem::path& drive_dir;
  bool simulated_input = false;
  const std::filesystem::path& gt_dir;
  const std::string& gt_kind;  ///< "simulator", "oxts" or "none"
  Timestamp first_scan;
  double duration_s = 0.0;
  const std::string& options_json;
  const std::string& extrinsics_json;
  const GeoOutputOptions& geo;
  int num_threads = 1;
  bool stopped = false;  ///< A signal stopped the run.
  const std::vector<std::string>& warnings;
  const std::string& imu_noise;  ///< Where the IMU noise model came from; empty: the defaults.
};

/// Ground truth, metrics, plots, summary (printed), report.json and report.html; `before_outputs`
/// runs after the summary is printed and before the outputs are listed (the removal of the
/// simulated drive). The checkpoint is removed when the run is complete. The first error goes to
/// `*fatal` where it is still OK; what can be written is written.
void EvaluateAndReport(const ReportInput& in, std::vector<ModeRun>* runs, Checkpoint* checkpoint,
                       const std::function<void()>& before_outputs, Status* fatal);

/// Bytes and regular files under `dir`.
std::pair<uintmax_t, size_t> DiskUse(const std::filesystem::path& dir);
/// Regular files under `dir`, relative to it and sorted (report.json's "outputs").
std::vector<std::string> OutputFiles(const std::filesystem::path& dir);

}  // namespace slam_mms::app
