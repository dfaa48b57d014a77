#pragma once
// One mapping method run over a drive: slam_mms::RunDrive (the library's loop that feeds any
// DriveReader into a MappingSystem) with a progress bar, timing and peak memory. Unreadable scans
// are skipped with a warning naming the file; any other error stops the run and is kept in
// `status`, with the estimates computed so far still filled in.

#include <atomic>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/drive/drive_runner.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms/pipeline/map_point_stamps.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"

namespace slam_mms::app {

struct ModeRun {
  MappingMode mode = MappingMode::kFull;
  std::string name;  ///< MappingModeName(mode).
  Trajectory trajectory;
  std::vector<LocalizationResult> results;  ///< Per scan, level 1 (before level 2).
  PointCloud map;
  MapPointStamps map_stamps;  ///< Per map point: first time and scan (LAS GPS time, source ID).
  std::optional<GeodeticPoint> origin;
  std::vector<GnssAvailabilityInterval> availability;
  /// Start of the first scan fed to the system: GNSS outage windows are relative to it.
  std::optional<Timestamp> first_scan_start;
  double wall_s = 0.0;
  size_t scans_total = 0;
  size_t scans_processed = 0;  ///< Poses in the trajectory.
  size_t scans_unreadable = 0;
  int scans_skipped_by_system = 0;
  std::vector<std::string> skipped_scans;  ///< Source and reason of each skipped scan.
  double scans_per_s = 0.0;
  std::optional<double> peak_rss_mb;
  bool finished = false;      ///< Finish() completed.
  bool complete = false;      ///< Every scan fed and Finish() completed.
  bool stopped = false;       ///< Ended early by the stop flag (a signal).
  bool smoothed_pos = false;  ///< On a forward-backward smoothed POS (gnss_ins_smoothed, full).
  Status status;              ///< The fatal error, if any.
  /// The map's entropy when computed early (beside the writing of the files, MapEntropyOf);
  /// unset: EvaluateMethod computes it.
  std::optional<StatusOr<eval::MapEntropyResult>> map_entropy;
};

/// Runs `mode` with `options` (mode overridden) on `reader`; `pos`: the POS of full (--pos).
/// `tty`: progress bar vs plain lines. `stop` (may be null; set by the SIGINT/SIGTERM handler)
/// ends the run after the current scan, with what was fed finished (ModeRun::complete false).
/// `on_submap` (may be empty): DriveRunCallbacks::on_submap (the checkpoints); `on_finished`
/// (may be empty): DriveRunCallbacks::on_finished (the drive result).
ModeRun RunMode(MappingMode mode, const MappingSystem::Options& options, const DriveReader& reader,
                PosWorkflow pos, bool tty, const std::atomic<bool>* stop = nullptr,
                std::function<void(const MappingSystem&, int)> on_submap = {},
                std::function<void(const MappingSystem&)> on_finished = {});

/// Resets the kernel's peak-RSS counter (VmHWM) so the next mode's peak is its own; returns false
/// where /proc/self/clear_refs is not writable (the peak is then the process's).
bool ResetPeakRss();

}  // namespace slam_mms::app
