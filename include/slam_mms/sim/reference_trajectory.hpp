#pragma once
// ReferenceTrajectory: the simulator's true, smooth motion of the body (IMU) frame in the local ENU
// world frame, with analytic first and second derivatives so that the simulated IMU (specific force
// and angular rate), the LiDAR firing poses and the ground truth are mutually consistent.
//
// Representation: six uniform cubic B-splines (C2) over time for x, y, z [m] and roll, pitch, yaw
// [rad] (yaw unwrapped), R_world_body = Rz(yaw) Ry(pitch) Rx(roll) (the KITTI/OXTS convention).
// Angular rate in the body frame follows analytically from the Euler-angle rates; the acceleration
// from the position spline's second derivative. The splines are fitted by regularised least squares
// to pose samples (real KITTI OXTS poses, or the samples of the embedded urban route), which both
// smooths and interpolates them.
//
// Ownership: value type. Thread safety: const methods may be called concurrently.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <filesystem>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms::sim {

/// The kinematic state of the body at one time.
struct BodyState {
  Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
  Eigen::Vector3d v_world_mps = Eigen::Vector3d::Zero();       ///< Velocity in world.
  Eigen::Vector3d a_world_mps2 = Eigen::Vector3d::Zero();      ///< Kinematic acceleration in world.
  Eigen::Vector3d omega_body_radps = Eigen::Vector3d::Zero();  ///< Angular rate in body.
  Eigen::Vector3d rpy_rad = Eigen::Vector3d::Zero();  ///< Roll, pitch, yaw (yaw unwrapped).
};

/// A pose sample to fit: position of the body in world and its roll/pitch/yaw (KITTI convention),
/// optionally with the body's velocity and the position's own 1-sigma accuracy.
struct PoseSample {
  double t_s = 0.0;  ///< Seconds since the trajectory's epoch.
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d rpy_rad = Eigen::Vector3d::Zero();
  /// 1-sigma of p_world per axis [m]; 0 = FitOptions::position_sigma_m.
  double position_sigma_m = 0.0;
  /// With has_velocity, the fitted positions' time derivative follows v_world_mps (weighted by
  /// FitOptions::velocity_sigma_mps) as well as the positions (each by its sigma).
  bool has_velocity = false;
  Eigen::Vector3d v_world_mps = Eigen::Vector3d::Zero();
  int record = -1;  ///< The input record it came from (OXTS file number), -1 = none.
};

class ReferenceTrajectory {
 public:
  struct FitOptions {
    double knot_spacing_s = 0.1;     ///< Spline knot interval [s]; > 0.
    double position_sigma_m = 0.02;  ///< Expected noise of the sampled positions [m]; > 0.
    double angle_sigma_rad = 0.002;  ///< Expected noise of the sampled angles [rad]; > 0.
    /// Expected noise of the sampled velocities (PoseSample::has_velocity) [m/s]; > 0.
    double velocity_sigma_mps = 0.02;
    /// White-noise acceleration prior (smoothing) [m/s^2 per sqrt(Hz)] and its angular
    /// counterpart [rad/s^2 per sqrt(Hz)]; larger follows the samples more closely. > 0.
    double accel_density = 3.0;
    double angular_accel_density = 1.0;

    [[nodiscard]] Status Validate() const;
  };

  ReferenceTrajectory() = default;

  /// Fits the splines to `samples` (time-ordered, at least 4, spanning > 3 knot intervals). Yaw is
  /// unwrapped first. `epoch` is the absolute time of t_s = 0. Positions are weighted by their
  /// own position_sigma_m where set; samples with has_velocity also constrain the positions'
  /// derivative (so, with loose positions, the motion follows the velocities and the positions
  /// only over longer times). Angles are fitted on their own.
  [[nodiscard]] static StatusOr<ReferenceTrajectory> Fit(Timestamp epoch,
                                                         const std::vector<PoseSample>& samples,
                                                         const FitOptions& options);

  /// The same motion over [from_s, to_s] only (widened to whole knot intervals): the control
  /// points of those segments, so Evaluate agrees exactly inside it. InvalidArgument where the
  /// span leaves nothing of [start_s(), end_s()].
  [[nodiscard]] StatusOr<ReferenceTrajectory> Restricted(double from_s, double to_s) const;

  /// The state at `t_s` seconds after the epoch, clamped to [start_s(), end_s()].
  BodyState Evaluate(double t_s) const;
  BodyState Evaluate(Timestamp t) const { return Evaluate(t.SecondsSince(epoch_)); }
  Eigen::Isometry3d Pose(double t_s) const { return Evaluate(t_s).T_world_body; }

  /// Specific force in body (what an accelerometer measures): R^T (a - g), g = (0, 0, -gravity).
  static Eigen::Vector3d SpecificForceBody(const BodyState& state, double gravity_mps2);

  Timestamp epoch() const { return epoch_; }
  double start_s() const { return t0_s_; }
  double end_s() const { return t0_s_ + dt_s_ * static_cast<double>(num_segments_); }
  double DurationSeconds() const { return end_s() - start_s(); }
  Timestamp ToTimestamp(double t_s) const { return epoch_.PlusSeconds(t_s); }
  /// Path length of the positions sampled every `step_s` [m].
  double PathLength(double step_s = 0.1) const;

 private:
  Timestamp epoch_;
  double t0_s_ = 0.0;
  double dt_s_ = 0.1;
  int num_segments_ = 0;
  std::vector<Eigen::Matrix<double, 6, 1>> control_;  // x y z roll pitch yaw
};

/// Trajectory samples of the embedded default urban drive ("--scenario default"): a rectangular
/// block loop with turns, two stops and a revisit of the first street, about 1.3 km in about 3
/// minutes at 30-40 km/h, at 10 Hz. Height, pitch and roll follow a gentle road profile and the
/// vehicle's accelerations. The route is fixed (the seed varies the world and the sensors, not the
/// route) so drives with different seeds share their motion.
std::vector<PoseSample> DefaultUrbanRouteSamples();

/// The demo drive of slam_mms_run / scripts/demo.sh: one city block with four turns, then its
/// first street again (a revisit), about 60 s at 8-9 m/s.
std::vector<PoseSample> DemoUrbanRouteSamples();

/// Number of route variants of scripted scenario `scenario`: 3 for "demo" and "default" (drives
/// through overlapping streets of one city plan), 0 for any other.
int NumRouteVariants(const std::string& scenario);

/// Trajectory samples of route variant `variant` (in [0, NumRouteVariants(scenario))) of the
/// scripted scenario "demo" or "default": variant 0 is DemoUrbanRouteSamples /
/// DefaultUrbanRouteSamples itself; the others drive some of its streets (in either direction) and
/// streets of their own, in the same city frame (docs/simulator.md "Route variants"). Each pair of
/// variants shares at least one street and each variant has a street no other drives. Times start
/// at 0 like the other routes. InvalidArgument (naming route_variant) for a variant out of range
/// or a scenario without variants.
[[nodiscard]] StatusOr<std::vector<PoseSample>> RouteVariantSamples(const std::string& scenario,
                                                                    int variant);

/// Trajectory samples of the long urban drive ("--scenario long"): a serpentine through a street
/// grid (420 m streets, 120 m apart), always into new streets, of at least `min_duration_s`
/// (plus up to one street), at 30-36 km/h with a stop every fourth street. For long-run and memory
/// benchmarks: the mapped area grows with the drive.
std::vector<PoseSample> LongUrbanRouteSamples(double min_duration_s);

/// Pose samples of an unpacked KITTI OXTS drive folder (`<drive>_sync` with oxts/timestamps.txt
/// and oxts/data/*.txt), converted to local ENU about the WGS-84 origin (lat, lon [deg], h [m])
/// with GeographicLib; `origin_from_first` replaces the origin by the first record's position.
/// Records with duplicate or backward stamps are dropped. `epoch` receives the first stamp. Each
/// sample carries the record's velocity (v_world_mps = Rz(yaw) (vf, vl, vu): forward and leftward
/// parallel to the earth's surface, up perpendicular to it; has_velocity = true) and its stated
/// horizontal accuracy (position_sigma_m = pos_accuracy where finite and > 0, else 0).
struct OxtsPoseSamples {
  Timestamp epoch;
  std::vector<PoseSample> samples;
  double origin_latitude_deg = 0.0;
  double origin_longitude_deg = 0.0;
  double origin_height_m = 0.0;
  int num_dropped = 0;
};
/// A span of samples whose recorded velocity is not a road car's (FindImplausibleMotion).
struct ImplausibleMotion {
  double from_s = 0.0, to_s = 0.0;           ///< Sample times of the span's first and last sample.
  size_t first_sample = 0, last_sample = 0;  ///< Indices into the samples.
  int first_record = -1, last_record = -1;   ///< Their PoseSample::record.
  double max_sideways_mps = 0.0;             ///< |velocity across the heading, level| in the span.
  double max_vertical_mps = 0.0;             ///< |vertical velocity| in the span.
};

/// Limits of a road car's motion: sideways 1.5 m/s is a slip angle of 8.5 deg at 36 km/h (a skid),
/// vertical 3 m/s a 30 % grade at 36 km/h. Every KITTI drive stays below a third of either
/// (sideways 0.39 m/s, vertical 1.64 m/s) except where its OXTS records are broken.
inline constexpr double kCarMaxSidewaysMps = 1.5;
inline constexpr double kCarMaxVerticalMps = 3.0;

/// The spans of `samples` with has_velocity whose velocity exceeds either limit (merged where
/// less than 1 s apart): records that do not describe a car, e.g. an INS free-running without
/// GNSS (KITTI 2011_09_26_drive_0093). Empty where every sample is plausible or has no velocity.
std::vector<ImplausibleMotion> FindImplausibleMotion(const std::vector<PoseSample>& samples,
                                                     double max_sideways_mps = kCarMaxSidewaysMps,
                                                     double max_vertical_mps = kCarMaxVerticalMps);

[[nodiscard]] StatusOr<OxtsPoseSamples> LoadOxtsPoseSamples(const std::filesystem::path& drive_dir,
                                                            double origin_latitude_deg,
                                                            double origin_longitude_deg,
                                                            double origin_height_m,
                                                            bool origin_from_first);

}  // namespace slam_mms::sim
