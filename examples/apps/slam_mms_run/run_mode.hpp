#pragma once
// One mapping method run over a drive: builds a MappingSystem for the mode, initialises the POS
// from the first OXTS record, merges scans, IMU samples and GNSS fixes in time order into it, shows
// progress, finishes, and keeps the trajectory, map, origin and timing. Unreadable scans are
// skipped with a warning naming the file; any other error stops the run and is kept in `status`,
// with the estimates computed so far still filled in.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"

namespace slam_mms::app {

/// The drive's streams, read once and shared by every mode.
struct DriveInput {
  const KittiRawReader* reader = nullptr;
  std::vector<ImuSample> imu;
  std::vector<std::string> imu_source;  ///< File of each IMU sample (for error messages).
  std::vector<GnssFix> gnss;
  std::vector<std::string> gnss_source;
  std::optional<InsState> initial_pos;  ///< From the earliest OXTS record (attitude, velocity).
  std::string initial_pos_source;
};

/// Reads the streams of `reader` (which must outlive the result).
DriveInput MakeDriveInput(const KittiRawReader& reader);

struct ModeRun {
  MappingMode mode = MappingMode::kFull;
  std::string name;  ///< MappingModeName(mode).
  Trajectory trajectory;
  std::vector<LocalizationResult> results;  ///< Per scan, level 1 (before level 2).
  PointCloud map;
  std::optional<GeodeticPoint> origin;
  std::vector<GnssAvailabilityInterval> availability;
  /// Start of the first scan fed to the system: GNSS outage windows are relative to it.
  std::optional<Timestamp> first_scan_start;
  double wall_s = 0.0;
  size_t scans_total = 0;
  size_t scans_processed = 0;  ///< Poses in the trajectory.
  size_t scans_unreadable = 0;
  int scans_skipped_by_system = 0;
  double scans_per_s = 0.0;
  std::optional<double> peak_rss_mb;
  bool finished = false;  ///< Finish() completed.
  Status status;          ///< The fatal error, if any.
};

/// Runs `mode` with `options` (mode overridden) on `input`. `tty`: progress bar vs plain lines.
ModeRun RunMode(MappingMode mode, const MappingSystem::Options& options, const DriveInput& input,
                bool tty);

/// Resets the kernel's peak-RSS counter (VmHWM) so the next mode's peak is its own; returns false
/// where /proc/self/clear_refs is not writable (the peak is then the process's).
bool ResetPeakRss();

}  // namespace slam_mms::app
