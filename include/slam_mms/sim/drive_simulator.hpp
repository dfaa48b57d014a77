#pragma once
// DriveSimulator: writes a simulated drive in KITTI raw layout with true ground truth.
//
//   <out>/<date>/calib_imu_to_velo.txt (+ placeholder camera calibs)
//   <out>/<date>/<date>_drive_<id>_sync/
//       velodyne_points/{data/*.bin, timestamps.txt, timestamps_start.txt, timestamps_end.txt}
//       oxts/{data/*.txt, timestamps.txt, dataformat.txt}           10 Hz, record nearest each
//       trigger oxts_100hz/{data/*.txt, timestamps.txt, dataformat.txt}     100 Hz IMU/POS records
//       ground_truth/
//           poses_100hz.tum          T_world_body at every 100 Hz record (TUM, world = local ENU)
//           scan_start.tum, scan_trigger.tum, scan_end.tum   T_world_body at each scan's times
//           imu_truth.csv            true specific force / rate and the IMU biases (100 Hz)
//           gnss.csv                 GNSS state, true ENU error, reported sigma, blockage (100 Hz)
//           scene_points.ply         the scene surfaces as seen along the drive: every noise-free
//                                    return in world coordinates, one point per voxel
//           scenario.json            every parameter, the seed and the WGS-84 origin of `world`
//
// World: local ENU (x east, y north, z up) about the WGS-84 origin in scenario.json; body = IMU
// (x forward, y left, z up); lidar pose T_body_lidar = inverse(T_lidar_body) (calib_imu_to_velo,
// unless Options::calib_error_* make that file wrong on purpose). Options::lidar_time_offset_s
// delays the scan stamps written; the ground truth stays on the IMU clock.
// Trajectory times are absolute (the scenario's start time, or the real OXTS stamps).
//
// Ownership: move-only; owns the world. Thread safety: Run is not reentrant; const accessors may be
// used concurrently.

#include <Eigen/Geometry>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/sim/city_world.hpp"
#include "slam_mms/sim/gnss_simulator.hpp"
#include "slam_mms/sim/hdl64_lidar.hpp"
#include "slam_mms/sim/imu_simulator.hpp"
#include "slam_mms/sim/reference_trajectory.hpp"

namespace slam_mms::sim {

/// KITTI's calib_imu_to_velo.txt of 2011_09_26 (T_lidar_body: body/IMU points into the Velodyne).
Eigen::Isometry3d KittiTLidarBody();

class DriveSimulator {
 public:
  struct Options {
    /// "default" (the embedded urban drive, ~190 s), "demo" (one block with four turns and a
    /// revisit, ~60 s: the demo's drive) or "long" (a serpentine through new streets, as long as
    /// duration_s, which must then be > 0); ignored when oxts_drive_dir is set.
    std::string scenario = "default";
    /// Route variant of scenario "demo" or "default" (docs/simulator.md "Route variants"):
    /// -1 (default) = the scenario's route alone, the world generated along it, as before;
    /// K in [0, NumRouteVariants(scenario)) = variant K's route (K = 0: the same route), in a world
    /// generated along all the variants' whole routes (CityWorld::Build of several paths), so every
    /// variant of one seed drives through the same city, in the same world frame. Variant K
    /// starts K hours after start_time, draws its sensor noise (IMU, GNSS, INS, LiDAR) from
    /// sensor_seed() (K = 0: `seed`, as without variants; else derived from (seed, K)) and is
    /// written as drive K + 1 unless drive_id is set. Not with "long" or oxts_drive_dir.
    int route_variant = -1;
    /// An unpacked KITTI OXTS drive folder (<drive>_sync with oxts/): real motion.
    std::filesystem::path oxts_drive_dir;
    /// With oxts_drive_dir: seconds after the first OXTS record at which the simulated span (the
    /// lead-in, then the scans) begins (>= 0). Where > 0, records before it, and more than 5 s
    /// after the last scan where duration_s > 0, are not used (0: every record is fitted, as
    /// before). The world origin stays the first record's.
    double oxts_start_s = 0.0;
    /// With oxts_drive_dir: the true motion's positions follow the records' velocities (Rz(yaw)
    /// (vf, vl, vu), so the simulated car moves sideways only as much as the real one's recorded
    /// vl) and the records' positions only as closely as oxts_truth_position_sigma_m or their
    /// stated accuracy, whichever is looser: KITTI's position track jumps and drifts (float RTK,
    /// re-fixes) where its velocities do not (docs/simulator.md, "The true motion of an OXTS
    /// drive"). false: a spline through the recorded positions (the car then crabs where they
    /// jump). The attitudes are the records' either way.
    bool oxts_truth_follows_velocities = true;
    double oxts_truth_position_sigma_m = 1.0;  ///< > 0 [m]
    uint64_t seed = 1;
    double duration_s = 0.0;  ///< Seconds of scans from the first scan; 0 = the whole drive.
    double lead_in_s = 1.0;   ///< IMU/POS records before the first scan [s] (>= 0).
    /// WGS-84 origin of the world frame. Default Karlsruhe. With oxts_drive_dir and
    /// origin_from_oxts, the first OXTS record's position is the origin.
    double origin_latitude_deg = 49.011;
    double origin_longitude_deg = 8.4235;
    double origin_height_m = 112.0;
    bool origin_from_oxts = true;
    /// Output naming: "" = "2026_01_15" for scenarios, the OXTS drive's date for real motion;
    /// drive_id < 0 = 1 for scenarios (route_variant + 1 with a route variant), the OXTS drive's
    /// number.
    std::string date;
    int drive_id = -1;
    /// Scenario start time (UTC) "YYYY-MM-DD hh:mm:ss" for scripted scenarios (route variant K
    /// starts K hours later).
    std::string start_time = "2026-01-15 10:00:00";
    /// The true calibration the scans are simulated with (T_body_lidar = T_lidar_body.inverse()).
    Eigen::Isometry3d T_lidar_body = KittiTLidarBody();
    /// A wrong calibration file on purpose (for self-calibration tests): calib_imu_to_velo.txt is
    /// written with
    ///   T_body_lidar_written = [R_err * R_body_lidar | t_body_lidar + calib_error_xyz_m],
    /// R_err = Rz(yaw) Ry(pitch) Rx(roll) of calib_error_rpy_deg = (roll, pitch, yaw) [deg], a
    /// rotation about the body axes (each |.| <= 10 deg), and calib_error_xyz_m a lever-arm error
    /// in the body frame [m] (each |.| <= 1 m); the file holds T_body_lidar_written.inverse().
    /// scenario.json keeps the true T_lidar_body and adds T_lidar_body_written. Zero: the true
    /// calibration is written (WrittenTLidarBody).
    Eigen::Vector3d calib_error_rpy_deg = Eigen::Vector3d::Zero();
    Eigen::Vector3d calib_error_xyz_m = Eigen::Vector3d::Zero();
    /// The IMU (the body frame) mounted rotated against the car (roll, pitch, yaw [deg] about
    /// the car's axes, R_car_body = Rz(yaw) Ry(pitch) Rx(roll), each |.| <= 10 deg): the car
    /// keeps its motion (positions, velocities, its own attitude from the route or the records),
    /// the body's attitude is R_world_car * R_car_body. Everything the simulator writes follows
    /// the body: the ground truth, the IMU, the INS records (their vf/vl/vu then show a sideways
    /// velocity where the car has none) and the LiDAR through T_lidar_body. A system that holds
    /// the body's x axis along the travel (a non-holonomic constraint without misalignment
    /// states) is then wrong by this much. Zero (default): the IMU is mounted along the car.
    Eigen::Vector3d imu_mount_error_rpy_deg = Eigen::Vector3d::Zero();
    /// The LiDAR clock runs this much behind the IMU clock [s] (|.| <= 0.5): the scan stamps
    /// written (velodyne_points/timestamps*.txt) are the true times - lidar_time_offset_s, so that
    /// true = written + lidar_time_offset_s (DriveExtrinsics::lidar_time_offset_s's convention).
    /// The ground truth (ground_truth/*.tum) and the OXTS records stay on the true (IMU) clock.
    double lidar_time_offset_s = 0.0;
    double gravity_mps2 = 9.81;
    ReferenceTrajectory::FitOptions fit;
    CityWorld::Options world;  ///< world.seed is ignored: derived from `seed`.
    Hdl64Lidar::Options lidar;
    ImuSimulator::Options imu;
    GnssSimulator::Options gnss;
    /// INS attitude / velocity error of the OXTS records (1 sigma, Gauss-Markov).
    double ins_roll_pitch_sigma_rad = 5.2e-4;  ///< 0.03 deg
    double ins_yaw_sigma_rad = 1.7e-3;         ///< 0.1 deg
    double ins_velocity_sigma_mps = 0.02;
    /// KITTI-like (docs/io.md, "KITTI's OXTS timing"): the OXTS records' inertial outputs
    /// (velocities, accelerations, angular rates, so the IMU the library reads) describe the
    /// motion this long before the record's time [s], their positions and attitudes on time.
    /// 0 = on time (default); KITTI's recordings: about 0.05. In [0, 0.5].
    double oxts_inertial_lag_s = 0.0;
    int num_threads = 2;
    bool write_scene_cloud = true;
    double scene_cloud_voxel_m = 0.1;
    bool overwrite = true;

    [[nodiscard]] Status Validate() const;
  };

  struct Summary {
    std::filesystem::path date_dir, drive_dir;
    std::string drive_name;
    int num_scans = 0;
    size_t num_points = 0;
    int num_imu_records = 0;
    size_t num_scene_points = 0;
    double simulated_seconds = 0.0;  ///< First scan start to last scan end.
    double path_length_m = 0.0;      ///< Over the simulated span.
    double seconds_lidar = 0.0, seconds_writing = 0.0, seconds_total = 0.0;  ///< Wall time of Run.
    double fraction_fixed = 0.0, fraction_float = 0.0, fraction_sps = 0.0, fraction_none = 0.0;
    /// Run's `stop` flag ended the scans early: the drive written is complete and consistent but
    /// holds only the first num_scans scans (the IMU/POS records cover the whole span).
    bool stopped = false;
  };

  /// Progress: (scans done, scans total).
  using Progress = std::function<void(int, int)>;

  /// Loads or builds the trajectory and generates the world.
  [[nodiscard]] static StatusOr<DriveSimulator> Create(const Options& options);

  DriveSimulator(DriveSimulator&&) noexcept;
  DriveSimulator& operator=(DriveSimulator&&) noexcept;
  DriveSimulator(const DriveSimulator&) = delete;
  DriveSimulator& operator=(const DriveSimulator&) = delete;
  ~DriveSimulator();

  /// Simulates and writes the drive under `out_dir`. `stop` (may be null; e.g. set by a SIGINT
  /// handler) is polled before every scan: once set, no further scan is simulated, the files of
  /// the scans so far are finished, and Summary::stopped is true.
  [[nodiscard]] StatusOr<Summary> Run(const std::filesystem::path& out_dir,
                                      const Progress& progress = {},
                                      const std::atomic<bool>* stop = nullptr);

  const ReferenceTrajectory& trajectory() const;
  const CityWorld& world() const;
  const Options& options() const;  ///< With the origin, date and drive id resolved.
  /// Trajectory seconds of the first scan's start and the number of scans Run writes.
  double first_scan_s() const;
  int num_scans() const;
  double seconds_world_build() const;
  /// The seed of the sensor noise (IMU, GNSS, INS errors, LiDAR): Options::seed, or with a route
  /// variant K > 0 one derived from (seed, K), so each variant's noise is an independent draw.
  uint64_t sensor_seed() const;
  /// With oxts_drive_dir: the spans of the simulated motion whose records are not a road car's
  /// (FindImplausibleMotion; times like the trajectory's), each logged as a warning by Create and
  /// listed in scenario.json. The simulated car follows them.
  const std::vector<ImplausibleMotion>& implausible_motion() const;

 private:
  struct Impl;
  explicit DriveSimulator(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// The T_lidar_body DriveSimulator writes to calib_imu_to_velo.txt for options `o`: the true
/// o.T_lidar_body with o.calib_error_rpy_deg / o.calib_error_xyz_m applied (see Options); exactly
/// o.T_lidar_body where both are zero.
Eigen::Isometry3d WrittenTLidarBody(const DriveSimulator::Options& o);

}  // namespace slam_mms::sim
