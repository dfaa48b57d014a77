#pragma once
// The robustness sweep's plan: which drive x seed x GNSS scenario x window runs, and what motion
// each window holds (issue 15). Drives are KITTI OXTS archives (<data>/kitti_oxts/*.tar.gz,
// listed in INDEX.tsv); a run simulates a drive along one window of a drive's real motion.
//
// Windows: run r of drive k (its line in INDEX.tsv) starts at a fraction {0, 1/2, 1}[(k + r) % 3]
// of the span the drive leaves for the window (its start, middle or end), so that the sweep mixes
// drives seen from standstill, at speed and near their end without anyone choosing per drive.
// Scenarios cycle over the drives the same way, seeds are 10 k + r + 1: a run is the same in a
// whole sweep and in `--drives` of its drive alone. The CI subset is the first run (in drive order)
// of each motion class.
//
// Thread safety: free functions and value types.

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/sim/reference_trajectory.hpp"

namespace slam_mms::sweep {

/// The GNSS conditions of a run (the simulator's options and the systems' outage windows).
enum class GnssScenario {
  kFixed,   ///< RTK fixed all the way (no urban-canyon degradation).
  kCanyon,  ///< RTK fixed where the sky is open, degraded by the buildings (the simulator default).
  kFloat,   ///< RTK float at best, no degradation.
  kSps,     ///< Single point at best, no degradation.
  kOutage,  ///< kCanyon plus a GNSS outage over the window's middle 40 %.
};
const char* GnssScenarioName(GnssScenario s);
bool ParseGnssScenario(const std::string& name, GnssScenario* s);

/// What the real motion does inside a window (from the OXTS positions and yaw at 10 Hz).
struct MotionStats {
  double path_m = 0.0;
  double mean_speed_mps = 0.0;
  double start_speed_mps = 0.0;  ///< Over the first 0.5 s of scans.
  double max_speed_mps = 0.0;
  double stationary_fraction = 0.0;  ///< Of the time below 0.3 m/s.
  double max_yaw_rate_dps = 0.0;     ///< Over 0.5 s differences.
  double total_turn_deg = 0.0;       ///< Sum of |yaw change|.
  /// Classes, "+"-joined: standing, stop-and-go, highway, start-at-speed, sharp-turn, campus
  /// (KITTI's 2011_09_28 recordings), city (none of the others), and not-a-car where the
  /// window's records are not a road car's motion (sim::FindImplausibleMotion: broken OXTS
  /// records, which the simulated car follows; not in the CI subset).
  std::string classes;
};

/// One run of the sweep.
struct SweepRun {
  std::string id;                  ///< "<date>_<drive>_r<run>_<scenario>", unique, a folder name.
  std::string drive;               ///< "2011_09_26_drive_0005_sync".
  std::filesystem::path oxts_dir;  ///< The unpacked drive folder.
  double oxts_start_s = 0.0;       ///< Window start after the first OXTS record (lead-in first).
  double duration_s = 0.0;         ///< Seconds of scans.
  uint64_t seed = 1;
  GnssScenario scenario = GnssScenario::kCanyon;
  /// The outage of kOutage, relative to the first scan: (start, duration) [s].
  std::optional<std::pair<double, double>> outage;
  MotionStats motion;
};

struct PlanOptions {
  std::filesystem::path oxts_archives;  ///< <data>/kitti_oxts
  std::filesystem::path unpack_dir;     ///< Where the archives are unpacked (kept, reused).
  std::vector<std::string> drives;      ///< Empty = all in INDEX.tsv (names with or w/o _sync).
  int max_drives = 0;                   ///< > 0: only the first N drives.
  int runs_per_drive = 1;
  double duration_s = 12.0;
  double lead_in_s = 1.0;
  std::vector<GnssScenario> scenarios = {GnssScenario::kFixed, GnssScenario::kCanyon,
                                         GnssScenario::kOutage, GnssScenario::kFloat,
                                         GnssScenario::kSps};
  bool ci_subset = false;  ///< Keep the first run of each motion class only.
};

/// The drives of INDEX.tsv (names as "<date>_drive_<nnnn>_sync"), in its order.
StatusOr<std::vector<std::string>> ListDrives(const std::filesystem::path& oxts_archives);

/// Unpacks <oxts_archives>/<drive>.tar.gz into unpack_dir (once) and returns the drive folder.
StatusOr<std::filesystem::path> UnpackDrive(const std::filesystem::path& oxts_archives,
                                            const std::string& drive,
                                            const std::filesystem::path& unpack_dir);

/// The motion of [start_s, start_s + duration_s] (seconds after the first sample) of a drive's
/// OXTS samples (sim::LoadOxtsPoseSamples); `drive` names it for the campus class. Fails on fewer
/// than 2 samples.
StatusOr<MotionStats> WindowMotion(const std::vector<sim::PoseSample>& samples,
                                   const std::string& drive, double start_s, double duration_s);

/// The runs (drives unpacked on the way). Fails on an unknown drive or an unreadable archive.
StatusOr<std::vector<SweepRun>> BuildPlan(const PlanOptions& options);

}  // namespace slam_mms::sweep
