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
// Unobservable parameters are then held at their initial
// values and the others solved again: the result never invents a number the drive cannot give
// (a straight drive cannot give the lever arm, level roads never its vertical component, constant
// speed never the time offset apart from the forward lever arm).
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
#include "slam_mms/io/drive_reader.hpp"

namespace slam_mms {

struct ExtrinsicCalibrationOptions {
  /// Scans used: at most max_scans, evenly spaced over the drive.
  int max_scans = 400;
  /// Per scan: points in [min_range_m, max_range_m] from the sensor, one per voxel of voxel_m in
  /// the lidar frame, at most max_points_per_scan; every query_stride-th of them is a query point
  /// (the others only fit the planes of partners).
  double min_range_m = 3.0;
  double max_range_m = 60.0;
  double voxel_m = 0.2;
  int max_points_per_scan = 8000;
  int query_stride = 6;
  /// Partners of a scan: the scans nearest to these time separations [s] before and after it, and
  /// up to max_revisit_partners scans more than revisit_min_separation_s apart whose POS position
  /// is within revisit_max_distance_m. Partners farther than max_partner_distance_m are dropped.
  std::vector<double> partner_separations_s = {0.5, 1.0, 2.0, 4.0};
  int max_revisit_partners = 2;
  double revisit_min_separation_s = 15.0;
  double revisit_max_distance_m = 15.0;
  double max_partner_distance_m = 40.0;
  /// Each query point is associated with this many of its scan's partners (round robin).
  int partners_per_point = 2;
  /// Plane of a partner: neighbours (k) all within max_neighbour_distance_m of the query point,
  /// thickness (sqrt of the smallest eigenvalue) <= max_plane_thickness_m, second eigenvalue >=
  /// 4 x the smallest (a plane, not a line).
  int num_neighbours = 8;
  double max_neighbour_distance_m = 1.0;
  double max_plane_thickness_m = 0.04;
  /// Residual gate [m], from initial_gate_m down to final_gate_m over the first rounds; Huber
  /// threshold huber_m.
  double initial_gate_m = 0.5;
  double final_gate_m = 0.15;
  double huber_m = 0.05;
  int max_rounds = 12;
  int gauss_newton_steps_per_round = 3;
  /// Scans whose POS position sigma (largest axis) exceeds max_pos_sigma_m [m] or
  /// max_pos_sigma_ratio x its median over the drive (GNSS outages, where the POS drifts) are not
  /// used. The absolute sigma of a GNSS/INS is mostly a slowly varying offset that moves the
  /// scans of a few seconds together; it is the drift in outages that breaks their consistency.
  double max_pos_sigma_m = 0.5;
  double max_pos_sigma_ratio = 3.0;
  /// The attitude the boresight is relative to. The map constrains only the sum of the
  /// boresight and the POS's own attitude error (on level roads the rotations commute), so the
  /// POS's heading error (0.05-0.3 deg for a tactical or navigation IMU over a minute of driving)
  /// would go into the yaw. kTravelDirection assumes the body x axis points along the direction of
  /// travel (an IMU aligned with the vehicle, no side slip on straight stretches): the POS's mean
  /// heading error is the mean angle of its own horizontal velocity in its own body frame over
  /// the scans faster than travel_min_speed_mps turning slower than travel_max_yaw_rate_radps,
  /// and the yaw is moved to the travel frame (pitch stays on the POS: its vertical velocity is
  /// too noisy, its gravity-levelled pitch good). kPos takes the POS attitude as it is (an IMU
  /// mounted askew to the vehicle). travel_sigma_rad: allowance for the alignment of the IMU with
  /// the vehicle axis and for slip, added in quadrature to the reference's own sigma. kPos is the
  /// default: it makes no assumption, and the estimate is the one that places the scans best on
  /// this POS (on the real KITTI frames kTravelDirection was 1.6 deg off it, docs/calibration.md).
  /// "pos" / "travel_direction" in config files (level2.extrinsic_calibration.attitude_reference).
  enum class AttitudeReference { kPos, kTravelDirection };
  AttitudeReference attitude_reference = AttitudeReference::kPos;
  double travel_min_speed_mps = 3.0;
  double travel_max_yaw_rate_radps = 0.05;
  double travel_sigma_rad = 0.01 * 3.14159265358979 / 180.0;
  /// Prior (1 sigma) about the initial value: roll/pitch/yaw [rad], lever arm [m], time [s].
  Eigen::Vector3d prior_sigma_rpy_rad = Eigen::Vector3d::Constant(2.0 * 3.14159265358979 / 180.0);
  Eigen::Vector3d prior_sigma_xyz_m = Eigen::Vector3d::Constant(0.3);
  double prior_sigma_time_s = 0.1;
  /// What is estimated (false: held at the initial value).
  bool estimate_rotation = true;
  bool estimate_translation = true;
  bool estimate_time_offset = true;
  /// Observable: sigma <= max_sigma_* and sigma <= prior sigma / min_prior_reduction.
  double max_sigma_rpy_rad = 0.05 * 3.14159265358979 / 180.0;
  double max_sigma_xyz_m = 0.03;
  double max_sigma_time_s = 0.003;
  double min_prior_reduction = 5.0;
  /// The residuals' systematic error that no number of them averages away [m]: a parameter is
  /// known at best to systematic_error_m / its sensitivity (the weighted RMS change of the
  /// residuals per unit of it). 0.5 mm: the smallest floor that covers the bias left with the
  /// true poses as the POS (roll 0.011 deg off on the demo drive, where this floor is 0.016 deg).
  /// It keeps the vertical lever arm, which level roads barely move the residuals with, from being
  /// "observed" (KITTI 0005's motion: 0.30 m off with a jackknife sigma of 0.026 m; floor 0.042 m)
  /// (docs/calibration.md).
  double systematic_error_m = 0.0005;
  /// Time blocks of the jackknife (>= 2).
  int jackknife_blocks = 8;
  int num_threads = 2;
  [[nodiscard]] Status Validate() const;
};

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
  /// value. sigma_rpy_rad includes pos_attitude_sigma_rad in quadrature: the map constrains only
  /// the sum of the boresight and the POS's own attitude error (on level roads the two rotations
  /// commute), so no drive gives the boresight better than its POS gives the attitude.
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
/// than 10 usable scans or no associations).
[[nodiscard]] StatusOr<ExtrinsicCalibration> CalibrateExtrinsics(
    const DriveReader& reader, const std::vector<InsState>& pos,
    const Eigen::Isometry3d& T_body_lidar_initial, double time_offset_initial_s,
    const ExtrinsicCalibrationOptions& options, const std::atomic<bool>* stop = nullptr);


}  // namespace slam_mms
