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

#include <Eigen/Core>
#include <cstdint>
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
  /// The error of the calibration file the simulator writes (DriveSimulator::Options
  /// calib_error_rpy_deg / calib_error_xyz_m): the LiDAR boresight (roll, pitch, yaw about the
  /// body axes) [deg] and lever arm [m] the systems are told are this far off the truth. Zero
  /// unless PlanOptions::calib_error_sigma_* are set; drawn per run from its seed.
  Eigen::Vector3d calib_error_rpy_deg = Eigen::Vector3d::Zero();
  Eigen::Vector3d calib_error_xyz_m = Eigen::Vector3d::Zero();
  /// The IMU mounted rotated against the car (DriveSimulator::Options::imu_mount_error_rpy_deg)
  /// [deg]; zero unless PlanOptions::imu_mount_error_sigma_rpy_deg is set.
  Eigen::Vector3d imu_mount_error_rpy_deg = Eigen::Vector3d::Zero();
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
  /// A wrong calibration file on every run (the real drive's class: KITTI 0013's factory boresight
  /// is 0.8-1.7 deg off its OXTS attitude, docs/calibration.md): each run's error is drawn per
  /// axis from N(0, sigma) (CalibrationErrorDraw), the same for a run in a whole sweep and alone.
  /// Zero (default): the true calibration is written.
  Eigen::Vector3d calib_error_sigma_rpy_deg = Eigen::Vector3d::Zero();
  Eigen::Vector3d calib_error_sigma_xyz_m = Eigen::Vector3d::Zero();
  /// An IMU mounted off the car's axes on every run (KITTI 0013's OXTS heading is 1.4-1.6 deg off
  /// its direction of travel), drawn the same way. Zero (default): mounted along the car.
  Eigen::Vector3d imu_mount_error_sigma_rpy_deg = Eigen::Vector3d::Zero();
};

/// The calibration and mounting errors of the run with `seed`: per axis a normal draw of sigma,
/// cut at 3 sigma (and at the simulator's 10 deg / 1 m), from a generator of its own seeded by
/// `seed` (Box-Muller on std::mt19937_64, so that it is the same with any standard library);
/// drawn in the order boresight, lever arm, mount, whichever sigmas are zero.
void CalibrationErrorDraw(uint64_t seed, const Eigen::Vector3d& sigma_rpy_deg,
                          const Eigen::Vector3d& sigma_xyz_m,
                          const Eigen::Vector3d& sigma_mount_rpy_deg, Eigen::Vector3d* rpy_deg,
                          Eigen::Vector3d* xyz_m, Eigen::Vector3d* mount_rpy_deg);

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
