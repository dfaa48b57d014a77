#pragma once
// InsFilter: the POS of a traditional mobile mapping system (paper §4, the `gnss_ins` baseline) and
// the motion prior of the SLAM-integrated one: a 22-state error-state EKF fusing IMU samples with
// GNSS position fixes (through GnssPrior's use / down-weight / reject decisions), or, instead, an
// external POS solution (a commercial INS's poses) that is only stored and interpolated.
//
// Model (documented simplifications):
// - Nominal state: p_world, v_world, R_world_body, accel bias ba, gyro bias bg, GNSS position bias
//   b_gnss, IMU-to-vehicle misalignment m (pitch, yaw) and the vehicle's lateral model l (lever
//   arm, sideslip; see the constraint below); `world` is the
//   local ENU frame of GnssPrior. Gravity is constant in world, g = (0, 0, -gravity): Somigliana's
//   normal gravity at the origin's latitude and height by default (or a given constant). Earth
//   rotation (15 deg/h) and transport rate are neglected: fine for a tactical IMU over minutes, and
//   a tactical gyro could not gyrocompass anyway (so static alignment needs a given yaw).
// - Error state [dp (world, additive), dv (world), dtheta (right: R = R_hat Exp(dtheta)), dba,
//   dbg, db_gnss (world), dm, dl (additive)], IMU biases as random walks, m and l random
//   constants.
//   Propagation between consecutive samples uses the mean of the two samples (second order); a GNSS
//   fix between samples propagates to the fix with the last sample held. A fix older than the state
//   (latency <= max_fix_latency_s) is compared with the antenna position extrapolated back by the
//   velocity; an older one is rejected (kReject, with the lag in the reason), not an error.
// - GNSS errors are time-correlated (float ambiguities, single-point orbit/clock/atmosphere
//   errors, multipath): a fix measures p + R t_body_antenna + b_gnss + white noise. The share
//   `correlated_fraction` of the fix's variance (as GnssPrior weighs it) is a first-order
//   Gauss-Markov bias b_gnss with the fix type's correlation time, the rest is white. A new
//   solution (another fix type, or the first fix after an outage) starts a new bias: b_gnss is
//   reset to zero with its stationary covariance (F = 0 on its block), so a fixed -> float step is
//   taken up by b_gnss, not by the tilt or the accelerometer bias. Correlated fraction 0 (RTK fixed
//   by default) is white noise (b_gnss held at zero with a negligible variance).
// - Zero-velocity updates (ZUPT, and the gyro bias from the mean rate, ZARU) while the vehicle
//   stands: the IMU is still over zupt_window_s (every sample's rate and gravity-compensated
//   acceleration below thresholds)
//   and the estimated speed is below zupt_max_speed_mps (the speed guard keeps a vehicle cruising
//   on a smooth road, whose IMU is also still, from being stopped).
// - Optional non-holonomic constraint (a vehicle does not slide sideways or jump): the vehicle's
//   y and z velocity zero with nhc_sigma_mps while moving. The vehicle's frame is the body (IMU)
//   frame turned by the IMU-to-vehicle misalignment (pitch about body y, yaw about body z:
//   R_body_vehicle = Exp((0, pitch, yaw))), two random constants in the error state estimated from
//   the constraint against GNSS and the IMU, starting from the given angles with
//   vehicle_misalignment_sigma_rad (0: the given angles are taken as exact). A real IMU is mounted
//   a few tenths of a degree off the car's axes (and an OXTS's heading is off its travel
//   direction by as much); a constraint that takes the IMU's axes for the car's turns the heading
//   onto the travel direction, against the GNSS (docs/ins.md). Likewise the car's wheels keep to
//   its x axis only at the rear axle, and slip by an angle proportional to the lateral
//   acceleration: the constraint allows the IMU's lateral velocity the lateral model gives (its
//   lever arm ahead of the axle, the sideslip coefficient; estimated the same way).
// - During GNSS outages (no usable fix) the filter propagates the IMU alone and its covariance
//   grows.
//
// Ownership: owns its GnssPrior and a bounded state history (history_s); move-only.
// Thread safety: not thread-safe for mutation; const queries may run concurrently.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <deque>
#include <memory>
#include <optional>
#include <vector>

#include "slam_mms/core/imu_noise.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/ins/gnss_prior.hpp"

namespace slam_mms {

using Matrix15d = Eigen::Matrix<double, 15, 15>;
/// Dimension of InsFilter's error state [dp, dv, dtheta, dba, dbg, db_gnss, dm, dl]; dm: the
/// IMU-to-vehicle misalignment (pitch, yaw) [rad]; dl: the vehicle's lateral motion model (the
/// IMU's lever arm ahead of the non-holonomic point [m], the sideslip coefficient [rad/(m/s^2)]).
constexpr int kInsErrorDim = 22;
using InsErrorMatrix = Eigen::Matrix<double, kInsErrorDim, kInsErrorDim>;
using InsErrorVector = Eigen::Matrix<double, kInsErrorDim, 1>;

/// One step of the forward filter as a smoother needs it (InsFilter::Options::record_steps): the
/// nominal state and the 22x22 error covariance [dp, dv, dtheta, dba, dbg, db_gnss, dm, dl] after
/// the propagation to `stamp` (a priori) and after the measurement updates at `stamp` (a
/// posteriori; equal to the a-priori ones where no fix was used), and the error-state transition
/// matrix from the previous step's a-posteriori error to this step's a-priori error (identity for
/// the first step). The nominal states' cov_T_world_body is the filter's pose covariance at that
/// point.
struct InsFilterStep {
  Timestamp stamp;
  InsState prior;
  InsState posterior;
  Eigen::Vector3d gnss_bias_prior = Eigen::Vector3d::Zero();  ///< b_gnss (world) [m].
  Eigen::Vector3d gnss_bias_posterior = Eigen::Vector3d::Zero();
  /// IMU-to-vehicle misalignment (pitch, yaw) [rad].
  Eigen::Vector2d vehicle_misalignment_prior = Eigen::Vector2d::Zero();
  Eigen::Vector2d vehicle_misalignment_posterior = Eigen::Vector2d::Zero();
  /// The vehicle's lateral motion model (lever arm [m], sideslip coefficient [rad/(m/s^2)]).
  Eigen::Vector2d vehicle_lateral_model_prior = Eigen::Vector2d::Zero();
  Eigen::Vector2d vehicle_lateral_model_posterior = Eigen::Vector2d::Zero();
  InsErrorMatrix P_prior = InsErrorMatrix::Zero();
  InsErrorMatrix P_posterior = InsErrorMatrix::Zero();
  InsErrorMatrix F = InsErrorMatrix::Identity();
  bool updated = false;  ///< A measurement was used at this step.
};

class InsFilter {
 public:
  struct Options {
    // IMU noise, continuous-time densities (RT3003-like tactical grade by default).
    double gyro_noise_density = 1.7e-4;      ///< [rad/s/sqrt(Hz)] (~0.6 deg/sqrt(h)).
    double accel_noise_density = 2.0e-3;     ///< [m/s^2/sqrt(Hz)].
    double gyro_bias_random_walk = 2.0e-5;   ///< [rad/s^2/sqrt(Hz)].
    double accel_bias_random_walk = 3.0e-4;  ///< [m/s^3/sqrt(Hz)].
    /// Gravity magnitude [m/s^2]; <= 0 selects Somigliana normal gravity at the world origin.
    double gravity_mps2 = 0.0;
    // Initial 1-sigma uncertainties.
    double init_sigma_position_m = 1.0;  ///< Used by Initialize() (GNSS init: the fix's).
    double init_sigma_velocity_mps = 0.1;
    double init_sigma_roll_pitch_rad = 0.0087;  ///< 0.5 deg.
    double init_sigma_yaw_rad = 0.035;          ///< 2 deg.
    double init_sigma_accel_bias_mps2 = 0.05;
    double init_sigma_gyro_bias_radps = 1.0e-3;
    /// Start from the initial attitude's stated accuracy where its source gives one
    /// (InitializeAttitude's sigma_rpy_rad: a KITTI OXTS record, initial_state.csv's sigma
    /// columns, a bag's orientation_covariance); false: always the init sigmas above. On by
    /// default since session 42, with the stated IMU noise and the vehicle constraint
    /// (docs/ins.md, "A land vehicle's POS"); alone, with this filter's default IMU model (3-25x a
    /// tactical IMU's noise), the stated prior outweighs what GNSS and motion tell of the
    /// attitude (docs/sweep.md, fix 5).
    bool use_stated_attitude_sigma = true;
    double max_imu_gap_s = 0.6;         ///< Longer IMU gaps are bridged but logged [s].
    double max_fix_latency_s = 0.25;    ///< Older fixes (than the state) are rejected [s].
    double max_extrapolation_s = 0.25;  ///< StateAt beyond the last state by at most this [s].
    double history_s = 600.0;           ///< States kept for StateAt [s].
    GnssPrior::Options gnss;            ///< Lever arm, floors, gates, outage timeout.
    /// Time-correlated GNSS error of one solution type (gnss_prior.hpp).
    using GnssErrorModel = ::slam_mms::GnssErrorModel;
    GnssErrorModel gnss_error_rtk_fixed{0.0, 30.0};  ///< Fixed ambiguities: cm-level, ~white.
    GnssErrorModel gnss_error_rtk_float{0.9, 30.0};  ///< Float ambiguities converge over ~30 s.
    /// Single-point and differential (code) solutions: orbit, clock, atmosphere, multipath.
    GnssErrorModel gnss_error_code{0.9, 60.0};
    // Zero-velocity update (on by default) and its stationarity detector.
    bool zupt = true;
    double zupt_window_s = 0.5;         ///< IMU samples the detector looks at [s].
    double zupt_max_gyro_radps = 0.01;  ///< Max |gyro - bg| over the window [rad/s].
    /// Max |R_world_body (accel - ba) + g| over the window: the specific force is gravity alone.
    double zupt_max_accel_mps2 = 0.1;
    double zupt_max_speed_mps = 0.2;  ///< Estimated speed must be below this [m/s].
    double zupt_sigma_mps = 0.01;     ///< Zero-velocity measurement sigma [m/s].
    double zupt_interval_s = 0.1;     ///< At most one ZUPT (and ZARU) per interval [s].
    /// Non-holonomic constraint sigma on the body y/z velocity [m/s]; 0 = off (default here;
    /// RunDrive sets MappingSystem::Options::vehicle_nhc_sigma_mps where the input's IMU frame is
    /// the vehicle's, see ApplyInputModels).
    double nhc_sigma_mps = 0.0;
    double nhc_min_speed_mps = 1.0;  ///< Applied above this estimated speed [m/s].
    /// Correlation times of the constraint's errors, lateral (y) and vertical (z) rows [s]; 0:
    /// white. A car's velocity off its axes is not white noise: tyre slip, the road's
    /// camber and grade changes, suspension pitch under braking last seconds (KITTI's records,
    /// 40 drives: 2.6 s lateral, 0.8 s vertical; docs/ins.md). Taken as white at the
    /// constraint's rate, n updates of one error count as n independent ones; with a correlation
    /// time tau each update's variance is nhc_sigma_mps^2 * max(1, 2 tau / dt) (dt: the time
    /// since the last constraint update), the white noise of the same spectral density at low
    /// frequencies, which is what a drift in heading or height integrates. Defaults: KITTI's.
    double nhc_lateral_correlation_time_s = 2.6;
    double nhc_vertical_correlation_time_s = 0.84;
    /// IMU-to-vehicle misalignment the constraint starts from: the vehicle frame is the body
    /// frame turned by pitch about body y and yaw about body z [rad] (a calibrated mounting).
    double vehicle_pitch_misalignment_rad = 0.0;
    double vehicle_yaw_misalignment_rad = 0.0;
    /// 1-sigma of those angles: > 0 estimates them (random constants) while the constraint is
    /// on; 0 takes them as exact. 1 deg by default: a unit mounted by hand, an OXTS whose heading
    /// is off the travel direction (KITTI: -0.24 / 0.04 / 0.47 deg, 10th/50th/90th percentile).
    double vehicle_misalignment_sigma_rad = 0.0175;
    /// The vehicle's lateral motion the constraint allows: a car's wheels roll without sliding
    /// sideways only at its rear axle (its non-holonomic point), and its tyres slip by an angle
    /// proportional to the lateral acceleration. The IMU's velocity in the vehicle frame is
    /// v_y = lever * w_z + sideslip * v_x * a_lat (a_lat = v_x * w_z), v_z = -lever * w_y, with
    /// `lever` the IMU's distance ahead of the rear axle along the vehicle's x axis [m] and
    /// `sideslip` the angle of the axle's velocity to the left of the vehicle's x axis per
    /// lateral acceleration [rad/(m/s^2)] (a car's tyres: a few thousandths, negative, its nose
    /// turns into the turn). Both start from the given values and are estimated (random
    /// constants) with the sigmas where those are > 0 (0: the given value is exact). An IMU 1 m
    /// ahead of the axle moves sideways by 0.5 m/s at 0.5 rad/s of yaw rate: a constraint
    /// without the lever arm turns the heading by 4 deg at 7 m/s.
    double vehicle_lever_arm_m = 0.0;
    double vehicle_lever_arm_sigma_m = 1.0;
    double vehicle_sideslip_rad_per_mps2 = 0.0;
    double vehicle_sideslip_sigma_rad_per_mps2 = 0.005;
    /// Keep every step (InsFilterStep) since the initialisation for a forward-backward smoother
    /// (PosSmoother). Memory: sizeof(InsFilterStep), 12.8 kB, per IMU sample or fix (100 Hz IMU
    /// + 10 Hz GNSS: 84 MB per minute, 5.1 GB per hour: smooth long drives in pieces). Not bounded
    /// by history_s.
    bool record_steps = false;

    [[nodiscard]] Status Validate() const;
    /// The IMU noise model from a datasheet (a validated spec): the four densities (bias random
    /// walks from instability and correlation time) and the initial bias sigmas (turn-on and
    /// instability). The filter's defaults are an IMU of unknown grade.
    void SetImuNoise(const ImuNoiseSpec& spec);
  };

  /// Default options.
  InsFilter();
  static StatusOr<InsFilter> Create(const Options& options);
  ~InsFilter();
  InsFilter(InsFilter&&) noexcept;
  InsFilter& operator=(InsFilter&&) noexcept;
  InsFilter(const InsFilter&) = delete;
  InsFilter& operator=(const InsFilter&) = delete;

  // ---- initialisation ------------------------------------------------------------------------
  /// Full state known (position in world). Covariance from the options' initial sigmas.
  [[nodiscard]] Status Initialize(const InsState& state);
  /// Attitude and velocity known; the position comes from the next usable GNSS fix (through the
  /// lever arm), which also sets the filter's time.
  /// With `stamp` (the time the attitude and velocity hold at), IMU samples after it carry them
  /// forward until that fix: a vehicle turning at 20 deg/s would otherwise start with 20 deg of
  /// heading error when the first usable fix comes 1 s later.
  /// `sigma_rpy_rad`: the attitude's 1-sigma roll, pitch and yaw (about the world axes) [rad] as
  /// its source states it (e.g. an OXTS record: KittiDriveReader); the filter starts with it,
  /// grown by init_sigma_gyro_bias_radps over the carry to the first fix. Empty: the options'
  /// init_sigma_roll_pitch_rad / init_sigma_yaw_rad (an attitude of unknown quality).
  [[nodiscard]] Status InitializeAttitude(
      const Eigen::Quaterniond& q_world_body, const Eigen::Vector3d& v_world_mps,
      std::optional<Timestamp> stamp = std::nullopt,
      const std::optional<Eigen::Vector3d>& sigma_rpy_rad = std::nullopt);
  /// Static alignment: roll and pitch from the mean specific force, gyro bias from the mean rate,
  /// yaw given (ENU, 0 = east, counter-clockwise); velocity zero; position from the next usable
  /// fix.
  [[nodiscard]] Status InitializeStaticAlignment(const std::vector<ImuSample>& static_samples,
                                                 double yaw_rad);
  bool initialized() const;

  // ---- data ----------------------------------------------------------------------------------
  /// One IMU sample (time-ordered). Before initialisation only remembered.
  [[nodiscard]] Status AddImu(const ImuSample& sample);
  /// One GNSS fix: decision by GnssPrior against the current estimate, then the EKF update if
  /// usable. Also completes a pending attitude initialisation.
  StatusOr<GnssDecisionResult> AddGnss(const GnssFix& fix);
  /// An external POS solution (instead of IMU + GNSS): states are stored and interpolated. Cannot
  /// be mixed with AddImu.
  [[nodiscard]] Status AddExternalPose(const InsState& state);

  // ---- queries -------------------------------------------------------------------------------
  /// The latest state (FailedPrecondition before initialisation).
  StatusOr<InsState> CurrentState() const;
  /// The state at `t`, interpolated between stored states (pose by slerp, velocity and covariance
  /// linearly), or extrapolated with the last IMU sample up to max_extrapolation_s past the last.
  StatusOr<InsState> StateAt(Timestamp t) const;
  /// Forgets the stored states that StateAt no longer needs for times >= `t`: it keeps the last
  /// state at or before `t` and every later one (and at least two). For a host that knows the
  /// oldest time it will still ask for (MappingSystem: its unreported submaps and queued scans);
  /// otherwise Options::history_s bounds the history. Estimates are unchanged.
  void ForgetStatesBefore(Timestamp t);
  /// 22x22 error-state covariance [dp, dv, dtheta, dba, dbg, db_gnss, dm, dl] of the latest state.
  const InsErrorMatrix& covariance() const;
  /// The GNSS error model's bias (antenna position error of the current solution type) [m].
  Eigen::Vector3d gnss_bias_world() const;
  /// The estimated IMU-to-vehicle misalignment (pitch, yaw) [rad] (the options' angles where the
  /// non-holonomic constraint is off or the angles are taken as exact); its covariance is the
  /// 2x2 block of covariance() at 18.
  Eigen::Vector2d vehicle_misalignment_rad() const;
  /// The estimated lateral motion model of the vehicle (the IMU's lever arm ahead of the
  /// non-holonomic point [m], the sideslip coefficient [rad/(m/s^2)]; the options' values where
  /// the constraint is off or they are taken as exact); its covariance is the last 2x2 block.
  Eigen::Vector2d vehicle_lateral_model() const;
  /// The attitude errors' correlation between two times of the forward filter (level 2's POS
  /// attitude chain, SubmapGraph::AddAttitudeChainFactor): MarkAttitudeEpoch() starts tracking
  /// the cross-covariance between the error state and the attitude error of the current state
  /// (propagated with every transition and update: Cov(dx_now, dtheta_epoch) = prod (I - K H) F
  /// * P_epoch[:, dtheta]); AttitudeSinceEpoch() reads it for the current state. Errors are right
  /// perturbations in each time's body axes, as cov_T_world_body's rotation block. A new
  /// initialisation forgets the epoch (FailedPrecondition until the next mark).
  struct AttitudeCorrelation {
    Timestamp epoch, now;
    Eigen::Matrix3d R_world_body_epoch = Eigen::Matrix3d::Identity();
    Eigen::Matrix3d R_world_body_now = Eigen::Matrix3d::Identity();
    Eigen::Matrix3d cov_epoch = Eigen::Matrix3d::Identity();  ///< Cov(dtheta_epoch) [rad^2]
    Eigen::Matrix3d cov_now = Eigen::Matrix3d::Identity();    ///< Cov(dtheta_now)
    Eigen::Matrix3d cross = Eigen::Matrix3d::Zero();          ///< Cov(dtheta_now, dtheta_epoch)
  };
  /// FailedPrecondition before initialisation or with an external POS.
  [[nodiscard]] Status MarkAttitudeEpoch();
  StatusOr<AttitudeCorrelation> AttitudeSinceEpoch() const;
  /// Zero-velocity updates applied since the initialisation.
  int num_zero_velocity_updates() const;
  /// Every stored state, oldest first (the GNSS/INS-only trajectory).
  std::vector<InsState> States() const;
  /// The recorded steps since the last initialisation (empty unless options.record_steps).
  const std::vector<InsFilterStep>& Steps() const;
  /// Gravity vector in world (valid once the origin is known or gravity_mps2 > 0).
  Eigen::Vector3d gravity_world() const;

  const GnssPrior& gnss_prior() const;
  /// For outage windows, the reference time and the origin.
  GnssPrior& mutable_gnss_prior();
  const Options& options() const;

  /// Somigliana normal gravity on the WGS-84 ellipsoid with the free-air height correction [m/s^2].
  static double NormalGravity(double latitude_deg, double height_m);

 private:
  explicit InsFilter(const Options& options);
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
