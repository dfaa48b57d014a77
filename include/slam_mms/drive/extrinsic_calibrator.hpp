#pragma once
// CalibrateExtrinsics: boresight self-calibration from the drive itself. Estimates the rotation
// R_body_lidar (roll, pitch, yaw), the lever arm t_body_lidar and a constant LiDAR clock offset
// (a LiDAR stamp s is the time s + lidar_time_offset_s on the IMU/GNSS clock), with a prior from
// the calibration file, and says which of the seven are observable in this drive
// (docs/calibration.md).
//
// Method (the map-to-map consistency of the survey workflow's boresight adjustment): the scans
// are placed in the world by the POS (an offline, smoothed GNSS/INS trajectory, independent of the
// LiDAR): T_world_lidar(scan a, point time tau) = T_world_body(t_a + dt + tau) * T_body_lidar.
// With the wrong extrinsic, the same surface seen from two scans taken at different vehicle poses
// does not coincide. Each scan is de-skewed with the POS into its own rigid frame; points of scan
// a are associated with local planes of partner scans b (taken 0.5-4 s apart, and revisits);
// Gauss-Newton minimises the robust (Huber) point-to-plane distances over the 7 parameters, with
// the planes moving with the extrinsic too, re-associating and re-de-skewing between rounds:
//   r = n_w . (w_a - c_w),  w_a = T_world_body(t_a+dt) X q_a,  c_w = T_world_body(t_b+dt) X c_b,
//   n_w = R_world_body(t_b+dt) R_X n_b,  X = T_body_lidar.
// Observability: a parameter is reported observable when its standard deviation is below
// Options::max_sigma_* and at most 1/min_prior_reduction of its prior sigma. The sigma is the
// largest of the formal one (Huber-weighted normal equations, scaled by the residual variance),
// a leave-one-block-out jackknife over time blocks of the drive (the formal one ignores that
// residuals of one scan are correlated) and a systematic floor (Options::systematic_error_m).
// An observable parameter is applied where its correction is significant
// (Options::min_significance). The others are then held at their initial values and the
// applied ones solved again: the result never invents a number the drive cannot give (a straight
// drive cannot give the lever arm, level roads never its vertical component, constant speed
// never the time offset apart from the forward lever arm), nor replaces the file's value with
// one it cannot tell from it.
//
// The POS's own position error, which tilts the scans' path by its rate over the speed, is
// estimated with them (a correction linear between knots, Options::estimate_pos_drift); the
// seven's sigmas are those with it marginalised.
//
// Scans where the POS is worse than usual (GNSS outages: Options::max_pos_sigma_*) are not used.
//
// Thread safety: a pure function; reads the reader's scans through its const ReadScan.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <atomic>
#include <cstddef>
#include <string>
#include <vector>

#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/drive/extrinsic_calibration_options.hpp"
#include "slam_mms/io/drive_reader.hpp"

namespace slam_mms {

/// What CalibrateExtrinsics estimated. Parameter order everywhere: roll, pitch, yaw, x, y, z, time.
struct ExtrinsicCalibration {
  Eigen::Isometry3d T_body_lidar_initial = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d T_body_lidar_estimated = Eigen::Isometry3d::Identity();
  double time_offset_initial_s = 0.0;
  double time_offset_s = 0.0;  ///< Estimated lidar_time_offset_s.
  /// R_estimated = Rz(yaw) Ry(pitch) Rx(roll) * R_initial (about the body axes) [rad];
  /// t_estimated = t_initial + correction_xyz_m (body frame).
  Eigen::Vector3d correction_rpy_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d correction_xyz_m = Eigen::Vector3d::Zero();
  /// 1 sigma (see the file comment) of the correction; 0 for a parameter held at its initial
  /// value (not applied). sigma_rpy_rad includes pos_attitude_sigma_rad in quadrature: the map
  /// constrains only the sum of the boresight and the POS's own attitude error (on level roads the
  /// two rotations commute), so no drive gives the boresight better than its POS gives the
  /// attitude.
  Eigen::Vector3d sigma_rpy_rad = Eigen::Vector3d::Zero();
  Eigen::Vector3d sigma_xyz_m = Eigen::Vector3d::Zero();
  double sigma_time_s = 0.0;
  /// The formal and the jackknife sigmas of the first solve (all seven free, prior included).
  Eigen::Matrix<double, 7, 1> formal_sigma = Eigen::Matrix<double, 7, 1>::Zero();
  Eigen::Matrix<double, 7, 1> jackknife_sigma = Eigen::Matrix<double, 7, 1>::Zero();
  /// Options::systematic_error_m over each parameter's sensitivity.
  Eigen::Matrix<double, 7, 1> systematic_sigma = Eigen::Matrix<double, 7, 1>::Zero();
  /// Whether the drive determines each parameter (false also for one not estimated).
  std::array<bool, 7> observable{};
  /// Whether the estimate replaced the initial value: observable and significant
  /// (Options::min_significance). The others are held at their initial values.
  std::array<bool, 7> applied{};
  /// Each parameter's correction over its sigma in the first solve (all free; rotations with the
  /// attitude reference's sigma in quadrature); 0 for one not estimated.
  Eigen::Matrix<double, 7, 1> significance = Eigen::Matrix<double, 7, 1>::Zero();
  /// The sigma of the attitude reference, body axes: the median over the scans used of the POS's
  /// own attitude sigma (its covariance); with kTravelDirection, for pitch and yaw that reference's
  /// (yaw: the standard error of its time-block means and travel_sigma_rad in quadrature).
  Eigen::Vector3d pos_attitude_sigma_rad = Eigen::Vector3d::Zero();
  /// kTravelDirection: the POS's mean heading error found [0, 0, yaw] [rad] and the
  /// number of scans it came from (0: not applied).
  Eigen::Vector3d travel_correction_rad = Eigen::Vector3d::Zero();
  /// The reference used: "pos" or "travel_direction" (kTravelDirection falls back to "pos" on a
  /// drive without straight stretches, logged).
  std::string attitude_reference = "pos";
  int travel_samples = 0;
  /// The POS's position correction (Options::estimate_pos_drift): its knots (0: not estimated),
  /// the RMS of its rate between knots per world axis [m/s] and its largest excursion from its
  /// mean [m] (the part of the POS's error the scans' consistency sees).
  int pos_drift_knots = 0;
  Eigen::Vector3d pos_drift_rate_rms_mps = Eigen::Vector3d::Zero();
  double pos_drift_max_m = 0.0;
  int scans_used = 0;
  int scans_skipped_pos = 0;         ///< POS sigma above max_pos_sigma_m.
  int scans_skipped_unreadable = 0;  ///< ReadScan failed.
  size_t residuals = 0;              ///< Associations of the last round.
  int rounds = 0;
  bool converged = false;
  /// RMS of the point-to-plane distances (gate final_gate_m) at the initial and final values [m].
  double rms_initial_m = 0.0;
  double rms_final_m = 0.0;
  /// Heading change of the POS over the scans used, summed |delta yaw| [rad] (turns observe the
  /// lever arm).
  double total_heading_change_rad = 0.0;
  double wall_s = 0.0;
};

/// Names of the seven parameters: "roll", "pitch", "yaw", "x", "y", "z", "time_offset".
const char* ExtrinsicParameterName(int i);

/// Estimates the extrinsic of `reader`'s LiDAR from its scans and `pos` (T_world_body states,
/// strictly increasing stamps, e.g. PosSmoother's smoothed states; their cov_T_world_body select
/// the scans). Starts from (T_body_lidar_initial, time_offset_initial_s), which is also the
/// prior's mean. `stop` (may be null) is polled between rounds: FailedPrecondition "stopped".
/// Errors: InvalidArgument (options, non-rigid initial, unordered POS), FailedPrecondition (fewer
/// than 10 usable scans or no associations). `num_threads` (>= 1, the caller included) share
/// the association and normal-equation work.
[[nodiscard]] StatusOr<ExtrinsicCalibration> CalibrateExtrinsics(
    const DriveReader& reader, const std::vector<InsState>& pos,
    const Eigen::Isometry3d& T_body_lidar_initial, double time_offset_initial_s,
    const ExtrinsicCalibrationOptions& options, const std::atomic<bool>* stop = nullptr,
    int num_threads = 2);

}  // namespace slam_mms
