#pragma once
// RunDrive: one mapping method over a whole drive from any DriveReader (KITTI raw, a plain drive
// folder, a ROS 1 bag). It builds a MappingSystem for the mode, starts the POS from the reader's
// initial state, merges the scans, IMU samples and GNSS fixes (or the external POS) in time order
// into it, finishes, and returns the trajectory, the map and what happened. This is the loop every
// app (slam_mms_run, slam_mms_bench_e2e) and the Python package run, so that they give the same
// trajectories from the same input.
//
// Time order: a scan enters once the IMU/GNSS streams have reached its end; at equal stamps IMU,
// then GNSS, then the scan. An unreadable scan (ReadScan error) is skipped with a warning naming
// its source, counted and listed; any other error stops the run and is returned in `status` with
// the estimates computed so far (nothing computed is lost). `stop` (e.g. set by a SIGINT handler)
// ends the run after the current scan: Finish() still runs on what was fed, `complete` is false.
//
// External POS (reader.streams().pos non-empty): the records are converted to world (local ENU at
// options.origin, else at the first record) and fed with AddInsPose instead of IMU + GNSS.
//
// Two POS workflows (ARCHITECTURE.md): streaming (DriveRunOptions::pos = kForward, the default,
// as a host calling MappingSystem live gets) and offline (kSmoothed, `slam_mms_run --pos smoothed`;
// not its default: on the demo drive and the real KITTI frames `full` is less accurate on today's
// smoothed POS, whose attitude is worse than the forward filter's, docs/results.md): PosSmoother
// runs the forward EKF over the whole IMU/GNSS stream with options.ins and the outage windows
// (relative to scan 0's start), then a Rauch-Tung-Striebel backward pass; the smoothed states (one
// per IMU sample and fix) are fed with AddInsPose, and the IMU samples and GNSS fixes are fed too:
// the IMU for the POS-jump check and preintegration, the raw fixes as level-2 GNSS factors (decided
// against the smoothed POS, withheld in the outage windows). Level 1 then takes F_Odom from the
// smoothed POS also inside outages (its relative motion there is the IMU's, with biases estimated
// from both ends). Mode kGnssInsSmoothed always runs offline (scans placed with the smoothed POS);
// kGnssIns is always the forward filter, kLidarOnly uses no POS. An input with its own external POS
// keeps it (it is a POS solution already) in every workflow.
//
// Boresight self-calibration (DriveRunOptions::estimate_extrinsics): before the method, the
// offline POS of the drive and CalibrateExtrinsics against it (CalibrateDriveExtrinsics), then the
// run with the estimated T_body_lidar and LiDAR clock offset (the reader's antenna kept); the
// estimate is in DriveRun::extrinsic_calibration. A streaming MappingSystem has no such pass: it
// needs the whole drive first.
//
// Thread safety: RunDrive may run concurrently with itself on distinct readers (or one reader whose
// ReadScan is thread-safe); callbacks are called on the calling thread.

#include <atomic>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/drive/extrinsic_calibrator.hpp"
#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"

namespace slam_mms {

/// What RunDrive returns: the estimates (also after an error or a stop) and the run's counts.
struct DriveRun {
  MappingMode mode = MappingMode::kFull;
  Trajectory trajectory;                    ///< T_world_body at each processed scan's start.
  std::vector<LocalizationResult> results;  ///< Per scan, level 1 (before level 2).
  PointCloud map;                           ///< MappingSystem::FinalMap().
  MapPointStamps map_stamps;                ///< Per map point: first time and scan (or empty).
  std::optional<GeodeticPoint> origin;      ///< World origin, where known.
  std::vector<GnssAvailabilityInterval> availability;
  /// Start of the first scan fed to the system: GNSS outage windows are relative to it.
  std::optional<Timestamp> first_scan_start;
  double wall_s = 0.0;              ///< Processing time, Create() to Finish() [s].
  size_t scans_total = 0;           ///< reader.NumScans().
  size_t scans_processed = 0;       ///< Poses in the trajectory.
  size_t scans_unreadable = 0;      ///< ReadScan errors (skipped).
  int scans_skipped_by_system = 0;  ///< Bad scans MappingSystem skipped (empty, no finite point).
  std::vector<std::string> skipped_scans;  ///< Source and reason of every skipped scan.
  bool finished = false;                   ///< Finish() completed.
  bool complete = false;      ///< Every scan was fed and Finish() completed (no error, no stop).
  bool smoothed_pos = false;  ///< The scans were placed on (kFull: F_Odom from) a smoothed POS.
  double smoothing_wall_s = 0.0;  ///< Of which the forward-backward pass over the drive [s].
  /// DriveRunOptions::estimate_extrinsics: what the run was made with (its wall time included in
  /// wall_s).
  std::optional<ExtrinsicCalibration> extrinsic_calibration;
  Status status;  ///< The fatal error, if any.
};

/// Which POS a run of kFull uses (see the file comment); kGnssIns/kGnssInsSmoothed fix their own.
enum class PosWorkflow { kForward = 0, kSmoothed = 1 };
const char* PosWorkflowName(PosWorkflow pos);  ///< "forward", "smoothed"
/// Parses "forward" / "smoothed".
bool ParsePosWorkflow(const std::string& name, PosWorkflow* pos);

/// Run options that are not MappingSystem options (the streaming API has no offline pass).
/// Config keys drive.* (slam_mms_run --config).
struct DriveRunOptions {
  PosWorkflow pos = PosWorkflow::kForward;  ///< For kFull.
  /// Boresight self-calibration before the run (see the file comment; slam_mms_run
  /// --calibrate-extrinsics, docs/calibration.md). Off until measured to help.
  bool estimate_extrinsics = false;
  /// Its options (its threads are MappingSystem::Options::num_threads).
  ExtrinsicCalibrationOptions extrinsic_calibration;
  /// InvalidArgument naming "DriveRunOptions::<field>" (or the calibration's field).
  [[nodiscard]] Status Validate() const;
};

struct DriveRunCallbacks {
  /// After every scan fed (processed or skipped): (scans fed so far, reader.NumScans()).
  std::function<void(size_t fed, size_t total)> on_scan;
  /// Polled before every scan; true ends the run cleanly (see the file comment).
  const std::atomic<bool>* stop = nullptr;
  /// Each time level 1 starts a new submap (so one more is finished), with the system (e.g. to
  /// write its FinalTrajectory() so far) and the submaps finished so far; may be empty.
  std::function<void(const MappingSystem& system, int submaps_finished)> on_submap;
  /// Once Finish() has completed (also after a stop), with the system (e.g. to export its
  /// DriveResult); may be empty.
  std::function<void(const MappingSystem& system)> on_finished;
};

/// True where `streams` state an IMU noise and options.use_stated_imu_noise is on: the run
/// models the IMU with it.
bool UsesStatedImuNoise(const MappingSystem::Options& options, const DriveStreams& streams);

/// True where ApplyInputModels turns the non-holonomic constraint on: the input states that its
/// IMU frame is the vehicle's (DriveStreams::imu_frame_is_vehicle_frame),
/// options.vehicle_nhc_sigma_mps > 0 and options.ins.nhc_sigma_mps is 0 (not set by the caller).
bool UsesVehicleConstraint(const MappingSystem::Options& options, const DriveStreams& streams);

/// `options` with what the input states about its sensors applied: the IMU noise
/// (MappingSystem::Options::SetImuNoise) where UsesStatedImuNoise, and the vehicle's
/// non-holonomic constraint (ins.nhc_sigma_mps = vehicle_nhc_sigma_mps) where
/// UsesVehicleConstraint; else `options` unchanged. RunDrive, ComputeOfflinePos and
/// CalibrateDriveExtrinsics apply it themselves; hosts that build a MappingSystem for a
/// DriveReader's streams call it first.
MappingSystem::Options ApplyInputModels(const MappingSystem::Options& options,
                                        const DriveStreams& streams);

/// Runs `options.mode` over `reader`. options.T_body_lidar is used as given (set it from
/// reader.streams().T_body_lidar); an options error is returned in DriveRun::status.
/// kGnssInsSmoothed and `run_options.pos` = kSmoothed need IMU, GNSS and an initial attitude
/// (reader.streams().initial_state), else FailedPrecondition in DriveRun::status.
DriveRun RunDrive(const DriveReader& reader, const MappingSystem::Options& options,
                  const DriveRunCallbacks& callbacks = {}, const DriveRunOptions& run_options = {});

/// The offline POS of a drive, as RunDrive's offline workflow places the scans on it.
struct OfflinePos {
  std::vector<InsState> states;  ///< T_world_body (with covariances), strictly increasing stamps.
  GeodeticPoint origin;          ///< The world origin used.
  bool smoothed = false;         ///< PosSmoother ran (false: the input's own external POS).
};

/// The input's own external POS in world (local ENU about options.origin, else its first record)
/// where it has one, else PosSmoother over its IMU + GNSS with options.ins, options.origin and the
/// outage windows (relative to scan 0's start). Errors name the reader (FailedPrecondition where
/// there is no initial attitude or no usable fix).
[[nodiscard]] StatusOr<OfflinePos> ComputeOfflinePos(const DriveReader& reader,
                                                     const MappingSystem::Options& options);

/// The boresight self-calibration of DriveRunOptions::estimate_extrinsics: ComputeOfflinePos, then
/// CalibrateExtrinsics from reader.streams().T_body_lidar (time offset 0: the reader's own clock)
/// with `calibration` and options.num_threads. `stop` is polled between rounds. Errors: theirs.
[[nodiscard]] StatusOr<ExtrinsicCalibration> CalibrateDriveExtrinsics(
    const DriveReader& reader, const MappingSystem::Options& options,
    const ExtrinsicCalibrationOptions& calibration, const std::atomic<bool>* stop = nullptr);

/// The external POS records in world (local ENU about `origin`): positions through WGS-84, the
/// attitudes rotated from each record's local ENU into world, covariances from the sigmas (else
/// 1 cm / 0.01 deg). Fails on a record outside the WGS-84 range.
[[nodiscard]] StatusOr<std::vector<InsState>> PosRecordsInWorld(
    const std::vector<PosRecord>& records, const GeodeticPoint& origin);

}  // namespace slam_mms
