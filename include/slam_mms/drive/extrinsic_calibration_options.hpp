#pragma once
// ExtrinsicCalibrationOptions: the options of the boresight self-calibration
// (drive/extrinsic_calibrator.hpp, CalibrateExtrinsics); part of the drive runner's options
// (DriveRunOptions::extrinsic_calibration, config keys drive.extrinsic_calibration.*).
//
// Thread safety: a plain value type.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"

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
  /// The POS's own position error, estimated with the extrinsic as a correction in world axes,
  /// linear between knots every pos_drift_knot_interval_s [s] over the scans used. Its prior is
  /// the POS's error as a Gauss-Markov process of the POS's stated position sigma s and
  /// correlation time pos_error_correlation_s (tau, the GNSS error's), whose rate is a
  /// Gauss-Markov process of sigma v = s sqrt(2 / tau) and tau: knots dt apart differ by
  /// v dt, their rates by v sqrt(2 dt / tau) (and 1 m about the POS at each knot, the gauge: the
  /// scans' consistency does not see a common shift). A GNSS/INS on float or code fixes wanders
  /// by a few cm/s (4.7 cm/s vertical on a simulated float drive whose attitude was 0.006 deg
  /// off); the scans' path tilts by that rate over the speed, and without this model the
  /// boresight takes it (0.35 deg of roll and pitch there). A shift of the scans is told apart
  /// from a rotation by the scans' geometry, as in a registration, except where it is not: along
  /// walls parallel to the path a yaw and a sideways drift look alike, over flat ground a pitch
  /// and a vertical one, so a POS that wanders leaves those to the turns and facades (and the
  /// lever arm and clock offset to the turns) (docs/calibration.md).
  /// The drift's rate is also capped at pos_max_velocity_error_mps: a POS whose position is
  /// metres off (a code-only GNSS) is not off by metres per second, since its INS holds the
  /// velocity (a GNSS/INS velocity error is a few cm/s: 4.7 cm/s vertical on that float drive).
  /// Without the cap, the real KITTI frames' POS (sigma of metres) "drifted" 0.8 m/s and took the
  /// whole extrinsic with it.
  bool estimate_pos_drift = true;
  double pos_drift_knot_interval_s = 1.0;
  double pos_error_correlation_s = 30.0;
  double pos_max_velocity_error_mps = 0.1;
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
  /// "pos" / "travel_direction" in config files (drive.extrinsic_calibration.attitude_reference).
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
  /// Observable: sigma <= max_sigma_* and sigma <= prior sigma / min_prior_reduction. 0.1 deg:
  /// with the POS's drift marginalised, the systematic floor of a yaw came out 0.055-0.073 deg on
  /// drives whose yaw the data gave to 0.01 deg; with the significance test below, what is
  /// applied is more than 3 sigma off the file (on the simulated sweep: a wrong file's yaw
  /// median 0.88 -> 0.70 deg, rule failures 8 -> 3; a right file kept on every run, as at
  /// 0.05 deg).
  double max_sigma_rpy_rad = 0.1 * 3.14159265358979 / 180.0;
  double max_sigma_xyz_m = 0.03;
  double max_sigma_time_s = 0.003;
  double min_prior_reduction = 5.0;
  /// Applied: observable and its correction at least min_significance x its sigma (rotations:
  /// with the attitude reference's sigma in quadrature); the others are held at the initial value.
  /// A correction the data cannot tell from their noise, or from the POS's own attitude error
  /// (which the map cannot tell from a boresight), keeps the calibration file's value: on the
  /// simulated sweep with a right file, yaw corrections of 0.05-0.1 deg within one sigma of the
  /// POS's heading error made the extrinsic worse than the file (docs/calibration.md).
  double min_significance = 3.0;
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
  [[nodiscard]] Status Validate() const;
};

}  // namespace slam_mms
