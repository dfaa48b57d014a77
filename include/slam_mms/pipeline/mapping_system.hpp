#pragma once
// MappingSystem: the thin SDK facade of slam_mms (paper Fig. 2). Feed it sensor data in time order
// (or a whole drive offline), get per-scan results, call Finish(), then read the trajectory with
// covariances, the geo-referenced map and the surfel map.
//
//   auto system = MappingSystem::Create(options);          // StatusOr<std::unique_ptr<...>>
//   system->AddImu(imu); system->AddGnss(fix); system->AddScan(scan);   // any interleaving in time
//   system->Finish();
//   Trajectory trajectory = system->FinalTrajectory();      // T_world_body at each scan's start
//   PointCloud map = system->FinalMap();
//
// Modes (Options::mode):
//  - kFull: the SLAM-integrated system: level 1 (Localizer: de-skew, scan-to-submap surfel
//    registration, F_Odom from the POS while GNSS is valid, F_Prein from IMU preintegration while
//    it is lost) and level 2 (SubmapGraph: map-to-map registration, reckon, loop and GNSS factors).
//  - kGnssIns: the traditional MMS: scans placed with the POS (InsFilter) poses, no map feedback.
//  - kLidarOnly: the SuMa-like baseline: constant-velocity prediction, registration, loops; no GNSS
//    or IMU after the initial pose (the first POS pose anchors it so it can be compared in world).
//
// Time order: scans are processed once the POS covers their end time (the IMU/GNSS stream has
// passed stamp_end), so a streaming host may push a scan before the IMU samples it spans. Finish()
// processes what is still queued. Data older than what was processed is rejected with
// InvalidArgument naming the stream and both times (nothing already computed is lost).
//
// World frame: local ENU at the first valid GNSS fix (or Options::origin); Origin() returns it so
// outputs can be geo-referenced. Determinism: the same input, options and num_threads give the
// same trajectory, map and pose covariances, bit for bit, whatever the memory layout (checked over
// repeated runs of the real KITTI frames and simulated drives, with the heap disturbed; no sum
// depends on memory addresses). Another num_threads splits some sums differently (last digits). A
// solve stopped by a wall-time limit (max_solve_time_s) on a
// loaded machine can also end at another iteration.
//
// Ownership: owns every component; move-only through std::unique_ptr.
// Thread safety: not thread-safe; call from one thread. Internally up to Options::num_threads.

#include <functional>
#include <memory>
#include <optional>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/ins/ins_filter.hpp"
#include "slam_mms/pipeline/drive_result.hpp"
#include "slam_mms/pipeline/level2_options.hpp"
#include "slam_mms/pipeline/localization_result.hpp"
#include "slam_mms/pipeline/localizer.hpp"
#include "slam_mms/pipeline/map_point_stamps.hpp"
#include "slam_mms/surfel/surfel.hpp"

namespace slam_mms {

class MappingSystem {
 public:
  struct Options {
    MappingMode mode = MappingMode::kFull;
    /// T_body_lidar (KITTI: the inverse of calib_imu_to_velo.txt).
    Eigen::Isometry3d T_body_lidar = Eigen::Isometry3d::Identity();
    /// World origin; empty = the first valid GNSS fix.
    std::optional<GeodeticPoint> origin;
    /// GNSS outage windows [start_s, start_s + duration_s) relative to the first scan's start.
    std::vector<std::pair<double, double>> gnss_outages;
    InsFilter::Options ins;   ///< The POS (with ins.gnss: GnssPrior options, lever arm).
    Level1Options localizer;  ///< Level 1 (the Localizer).
    Level2Options level2;     ///< Level 2 and loop closure.
    /// Final map: points farther than this from the sensor are not kept [m].
    double map_max_range_m = 60.0;
    /// Final map voxel size [m] (the paper evaluates entropy on a 0.1 m grid).
    double map_voxel_m = 0.1;
    /// Level 1 takes the POS relative motion between scans (F_Odom) only where the POS moved as
    /// its IMU measured: a correction jump (GNSS back after an outage, float -> fixed) larger than
    /// this [m] or max_pos_jump_rad between two scans, or within a scan, switches that interval to
    /// IMU preintegration (F_Prein). Only checked where IMU samples cover the interval. > 0.
    double max_pos_jump_m = 0.06;
    double max_pos_jump_rad = 0.006;  ///< See max_pos_jump_m [rad], > 0.
    /// The one thread count of the system (the calling thread included), in [1, 64]: every stage
    /// of level 1 (de-skew, range image, ICP, window solve, surfel update, CPU render, background
    /// submap clouds), level 2's solve and registration, and the final map.
    int num_threads = 2;
    /// Model the IMU with the noise its input states (DriveStreams::imu_noise) where RunDrive
    /// and the apps apply an input to these options (ApplyInputModels in drive_runner.hpp);
    /// false: the ins / localizer.imu densities as set. Hosts that feed a MappingSystem
    /// themselves call SetImuNoise. On by default since session 42, with the stated initial
    /// attitude accuracy and the vehicle constraint below (docs/ins.md, "A land vehicle's POS";
    /// alone it made attitudes worse on the sweep's 10 s windows, session 19).
    bool use_stated_imu_noise = true;
    /// The non-holonomic constraint's 1-sigma [m/s] that ApplyInputModels sets as
    /// ins.nhc_sigma_mps where the input states that its IMU frame is the vehicle's
    /// (DriveStreams::imu_frame_is_vehicle_frame) and ins.nhc_sigma_mps is 0 (not set); 0:
    /// never. 0.05 m/s (the default since session 42) with the errors' correlation times of
    /// ins.nhc_*_correlation_time_s: a car's velocity off its axes at its IMU as 40 KITTI drives'
    /// OXTS records show it (docs/ins.md, "The constraint's correlated errors").
    double vehicle_nhc_sigma_mps = 0.05;
    [[nodiscard]] Status Validate() const;
    /// The IMU's noise from its datasheet (DriveStreams::imu_noise where the input states it) in
    /// both places it is modelled: the POS filter (ins) and level 1's preintegration
    /// (localizer.imu). See InsFilter::Options::SetImuNoise.
    void SetImuNoise(const ImuNoiseSpec& spec);
  };

  /// Validates the options and builds every component.
  static StatusOr<std::unique_ptr<MappingSystem>> Create(const Options& options);
  ~MappingSystem();
  MappingSystem(const MappingSystem&) = delete;
  MappingSystem& operator=(const MappingSystem&) = delete;

  // ---- input (time-ordered per stream) --------------------------------------------------------
  [[nodiscard]] Status AddImu(const ImuSample& sample);
  [[nodiscard]] Status AddGnss(const GnssFix& fix);
  /// Initial attitude and velocity from a POS record (KITTI OXTS) at state.stamp; optional, else
  /// the filter aligns from the first records it gets (see InsFilter). IMU samples after the stamp
  /// carry the attitude to the first usable GNSS fix, which sets the position. `sigma_rpy_rad`:
  /// the record's stated 1-sigma roll, pitch, yaw [rad] (InsFilter::InitializeAttitude); empty:
  /// options.ins.init_sigma_roll_pitch_rad / init_sigma_yaw_rad.
  [[nodiscard]] Status InitializePos(
      const InsState& state, const std::optional<Eigen::Vector3d>& sigma_rpy_rad = std::nullopt);
  /// An external POS solution instead of IMU + GNSS (AddImu/AddGnss then unused for the POS), e.g.
  /// a commercial INS's output or a post-processed smoothed POS (PosSmoother, RunDrive with
  /// DriveRunOptions::pos = kSmoothed). It is taken as valid also inside GNSS outages: level 1 uses
  /// F_Odom from it throughout (the jump check still applies where IMU samples are fed, which
  /// also keep F_Prein possible). GNSS fixes fed with AddGnss are not fused into the POS: each is
  /// decided by the GnssPrior (outage windows, fix type, innovation against the POS antenna
  /// position at the fix time) and a usable one becomes a level-2 GNSS factor (kFull), as with the
  /// internal filter; the availability then comes from them and triggers level 2 when GNSS
  /// returns after a long outage. Without fixes level 2 has no GNSS factors.
  [[nodiscard]] Status AddInsPose(const InsState& state);
  /// A raw scan (lidar frame, per-point time offsets, not de-skewed). A bad scan (empty, all
  /// points non-finite) is skipped with a warning and counted; the return is then OK.
  [[nodiscard]] Status AddScan(const Scan& scan);
  /// Processes queued scans, runs the final level-2 refinement. Idempotent.
  [[nodiscard]] Status Finish();

  // ---- output ---------------------------------------------------------------------------------
  /// Per-scan level-1 results so far, in processing order.
  const std::vector<LocalizationResult>& results() const;
  /// Called after every processed scan (e.g. progress); may be empty.
  void SetResultCallback(std::function<void(const LocalizationResult&)> callback);
  /// T_world_body at each processed scan's stamp_start with covariance: after Finish() the final
  /// (level-2 refined) poses, before it the current estimates.
  Trajectory FinalTrajectory() const;
  /// The map: de-skewed scan points at the final poses within map_max_range_m, voxel-downsampled to
  /// map_voxel_m, with intensity, in world.
  PointCloud FinalMap() const;
  /// The same, and per map point (`stamps`, may be null) the absolute time and scan index of the
  /// first point observed in its voxel (the LAS GPS time and point source ID): one more sort of
  /// the merged submap points.
  PointCloud FinalMap(MapPointStamps* stamps) const;
  /// The surfels (world frame; kFull and kLidarOnly): those of the current and the previous
  /// submap, plus the archived older ones when localizer.archive_surfels is set.
  std::vector<Surfel> SurfelMapSnapshot() const;
  /// WGS-84 origin of world (FailedPrecondition before it is known).
  StatusOr<GeodeticPoint> Origin() const;
  /// GNSS availability history (from the POS's GnssPrior).
  std::vector<GnssAvailabilityInterval> GnssAvailability() const;
  /// Scans skipped as bad input.
  int num_skipped_scans() const;
  /// Scan intervals where the POS jumped (see Options::max_pos_jump_m): F_Prein instead of F_Odom.
  int num_pos_jumps() const;
  /// The finished drive for the multi-drive adjustment (DriveResult): its submaps with their
  /// clouds and level 2's factors. After Finish(); kFull and kLidarOnly (FailedPrecondition
  /// otherwise). Reads spilled clouds back.
  StatusOr<DriveResult> ExportDriveResult() const;
  /// Level-2 statistics (loops found, solves).
  Level2Stats level2_stats() const;
  const Options& options() const;

 private:
  explicit MappingSystem(const Options& options);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
