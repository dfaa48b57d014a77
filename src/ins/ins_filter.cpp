#include "slam_mms/ins/ins_filter.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "core/option_error.hpp"
#include "ins/ins_filter_impl.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {

namespace {

Status FieldError(const char* field, double value, const char* rule) {
  return internal::OptionError("InsFilter::Options", field, value, rule);
}

}  // namespace

void InsFilter::Options::SetImuNoise(const ImuNoiseSpec& spec) {
  gyro_noise_density = spec.gyro_noise_density;
  accel_noise_density = spec.accel_noise_density;
  gyro_bias_random_walk = spec.GyroBiasRandomWalk();
  accel_bias_random_walk = spec.AccelBiasRandomWalk();
  init_sigma_gyro_bias_radps = spec.GyroBiasInitialSigma();
  init_sigma_accel_bias_mps2 = spec.AccelBiasInitialSigma();
}

Status InsFilter::Options::Validate() const {
  if (!PositiveFinite(gyro_noise_density))
    return FieldError("gyro_noise_density", gyro_noise_density, "must be > 0");
  if (!PositiveFinite(accel_noise_density))
    return FieldError("accel_noise_density", accel_noise_density, "must be > 0");
  if (!PositiveFinite(gyro_bias_random_walk))
    return FieldError("gyro_bias_random_walk", gyro_bias_random_walk, "must be > 0");
  if (!PositiveFinite(accel_bias_random_walk))
    return FieldError("accel_bias_random_walk", accel_bias_random_walk, "must be > 0");
  if (!std::isfinite(gravity_mps2) || gravity_mps2 > 20.0)
    return FieldError("gravity_mps2", gravity_mps2, "must be finite and <= 20 (<= 0: Somigliana)");
  if (!PositiveFinite(init_sigma_position_m))
    return FieldError("init_sigma_position_m", init_sigma_position_m, "must be > 0");
  if (!PositiveFinite(init_sigma_velocity_mps))
    return FieldError("init_sigma_velocity_mps", init_sigma_velocity_mps, "must be > 0");
  if (!PositiveFinite(init_sigma_roll_pitch_rad))
    return FieldError("init_sigma_roll_pitch_rad", init_sigma_roll_pitch_rad, "must be > 0");
  if (!PositiveFinite(init_sigma_yaw_rad))
    return FieldError("init_sigma_yaw_rad", init_sigma_yaw_rad, "must be > 0");
  if (!PositiveFinite(init_sigma_accel_bias_mps2))
    return FieldError("init_sigma_accel_bias_mps2", init_sigma_accel_bias_mps2, "must be > 0");
  if (!PositiveFinite(init_sigma_gyro_bias_radps))
    return FieldError("init_sigma_gyro_bias_radps", init_sigma_gyro_bias_radps, "must be > 0");
  if (!PositiveFinite(max_imu_gap_s))
    return FieldError("max_imu_gap_s", max_imu_gap_s, "must be > 0");
  if (!(max_fix_latency_s >= 0.0) || !std::isfinite(max_fix_latency_s))
    return FieldError("max_fix_latency_s", max_fix_latency_s, "must be >= 0");
  if (!(max_extrapolation_s >= 0.0) || !std::isfinite(max_extrapolation_s))
    return FieldError("max_extrapolation_s", max_extrapolation_s, "must be >= 0");
  if (!PositiveFinite(history_s)) return FieldError("history_s", history_s, "must be > 0");
  for (const auto& [name, m] : {std::pair<const char*, const GnssErrorModel*>{
                                    "gnss_error_rtk_fixed", &gnss_error_rtk_fixed},
                                {"gnss_error_rtk_float", &gnss_error_rtk_float},
                                {"gnss_error_code", &gnss_error_code}}) {
    if (!(m->correlated_fraction >= 0.0 && m->correlated_fraction < 1.0)) {
      return FieldError((std::string(name) + ".correlated_fraction").c_str(),
                        m->correlated_fraction, "must be in [0, 1)");
    }
    if (!PositiveFinite(m->correlation_time_s)) {
      return FieldError((std::string(name) + ".correlation_time_s").c_str(), m->correlation_time_s,
                        "must be > 0");
    }
  }
  for (const auto& [name, v] : {std::pair<const char*, double>{"zupt_window_s", zupt_window_s},
                                {"zupt_max_gyro_radps", zupt_max_gyro_radps},
                                {"zupt_max_accel_mps2", zupt_max_accel_mps2},
                                {"zupt_max_speed_mps", zupt_max_speed_mps},
                                {"zupt_sigma_mps", zupt_sigma_mps},
                                {"zupt_interval_s", zupt_interval_s}}) {
    if (!PositiveFinite(v)) return FieldError(name, v, "must be > 0");
  }
  if (!(nhc_sigma_mps >= 0.0) || !std::isfinite(nhc_sigma_mps))
    return FieldError("nhc_sigma_mps", nhc_sigma_mps, "must be >= 0 (0: off)");
  if (!(nhc_min_speed_mps >= 0.0) || !std::isfinite(nhc_min_speed_mps))
    return FieldError("nhc_min_speed_mps", nhc_min_speed_mps, "must be >= 0");
  for (const auto& [name, v] :
       {std::pair<const char*, double>{"nhc_lateral_correlation_time_s",
                                       nhc_lateral_correlation_time_s},
        {"nhc_vertical_correlation_time_s", nhc_vertical_correlation_time_s}}) {
    if (!(v >= 0.0 && v <= 60.0)) return FieldError(name, v, "must be within [0, 60] s (0: white)");
  }
  for (const auto& [name, v] : {std::pair<const char*, double>{"vehicle_pitch_misalignment_rad",
                                                               vehicle_pitch_misalignment_rad},
                                {"vehicle_yaw_misalignment_rad", vehicle_yaw_misalignment_rad}}) {
    if (!(std::abs(v) <= 0.2)) return FieldError(name, v, "must be within +-0.2 rad (11 deg)");
  }
  if (!(vehicle_misalignment_sigma_rad >= 0.0 && vehicle_misalignment_sigma_rad <= 0.2)) {
    return FieldError("vehicle_misalignment_sigma_rad", vehicle_misalignment_sigma_rad,
                      "must be in [0, 0.2] rad (0: the given angles are exact)");
  }
  // A car's IMU is within a few metres of its rear axle; tyres slip by a few hundredths of a
  // radian per g (0.005 rad/(m/s^2) is 2.8 deg/g).
  if (!(std::abs(vehicle_lever_arm_m) <= 10.0))
    return FieldError("vehicle_lever_arm_m", vehicle_lever_arm_m, "must be within +-10 m");
  if (!(vehicle_lever_arm_sigma_m >= 0.0 && vehicle_lever_arm_sigma_m <= 10.0)) {
    return FieldError("vehicle_lever_arm_sigma_m", vehicle_lever_arm_sigma_m,
                      "must be in [0, 10] m (0: the given lever arm is exact)");
  }
  if (!(std::abs(vehicle_sideslip_rad_per_mps2) <= 0.05)) {
    return FieldError("vehicle_sideslip_rad_per_mps2", vehicle_sideslip_rad_per_mps2,
                      "must be within +-0.05 rad/(m/s^2)");
  }
  if (!(vehicle_sideslip_sigma_rad_per_mps2 >= 0.0 &&
        vehicle_sideslip_sigma_rad_per_mps2 <= 0.05)) {
    return FieldError("vehicle_sideslip_sigma_rad_per_mps2", vehicle_sideslip_sigma_rad_per_mps2,
                      "must be in [0, 0.05] rad/(m/s^2) (0: the given sideslip is exact)");
  }
  return gnss.Validate();
}

double InsFilter::NormalGravity(double latitude_deg, double height_m) {
  // Somigliana (WGS-84), then the free-air correction.
  const double s2 = std::pow(std::sin(latitude_deg * M_PI / 180.0), 2);
  const double g0 =
      9.7803253359 * (1.0 + 0.00193185265241 * s2) / std::sqrt(1.0 - 0.00669437999013 * s2);
  return g0 - 3.086e-6 * height_m;
}

InsFilter::InsFilter() : InsFilter(Options()) {}
InsFilter::InsFilter(const Options& options) : impl_(std::make_unique<Impl>()) {
  impl_->options = options;
  impl_->gnss = GnssPrior::Create(options.gnss).value();
}
InsFilter::~InsFilter() = default;
InsFilter::InsFilter(InsFilter&&) noexcept = default;
InsFilter& InsFilter::operator=(InsFilter&&) noexcept = default;

StatusOr<InsFilter> InsFilter::Create(const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  return InsFilter(options);
}

const InsFilter::Options& InsFilter::options() const { return impl_->options; }
const GnssPrior& InsFilter::gnss_prior() const { return impl_->gnss; }
GnssPrior& InsFilter::mutable_gnss_prior() { return impl_->gnss; }
bool InsFilter::initialized() const { return impl_->initialized; }
const InsErrorMatrix& InsFilter::covariance() const { return impl_->P; }
Eigen::Vector3d InsFilter::gnss_bias_world() const { return impl_->x.bn; }
Eigen::Vector2d InsFilter::vehicle_misalignment_rad() const { return impl_->x.m; }
Eigen::Vector2d InsFilter::vehicle_lateral_model() const { return impl_->x.l; }
int InsFilter::num_zero_velocity_updates() const { return impl_->num_zupt; }
Eigen::Vector3d InsFilter::gravity_world() const { return impl_->g(); }

Status InsFilter::Initialize(const InsState& state) {
  Impl& im = *impl_;
  if (im.mode == Mode::kExternal) return FailedPreconditionError("InsFilter: external POS mode");
  if (!state.T_world_body.matrix().allFinite() || !state.v_world_mps.allFinite() ||
      !state.accel_bias_mps2.allFinite() || !state.gyro_bias_radps.allFinite()) {
    return InvalidArgumentError("InsFilter::Initialize: non-finite state");
  }
  im.x = Nominal();
  im.x.stamp = state.stamp;
  im.x.q = Eigen::Quaterniond(state.T_world_body.linear()).normalized();
  im.x.p = state.T_world_body.translation();
  im.x.v = state.v_world_mps;
  im.x.ba = state.accel_bias_mps2;
  im.x.bg = state.gyro_bias_radps;
  im.ResetAuxiliary();
  im.InitCovariance(im.options.init_sigma_position_m, im.options.init_sigma_position_m);
  im.initialized = true;
  im.pending_q.reset();
  im.mode = Mode::kImu;
  im.history.clear();
  im.Record();
  return OkStatus();
}

Status InsFilter::InitializeAttitude(const Eigen::Quaterniond& q_world_body,
                                     const Eigen::Vector3d& v_world_mps,
                                     std::optional<Timestamp> stamp,
                                     const std::optional<Eigen::Vector3d>& sigma_rpy_rad) {
  if (impl_->mode == Mode::kExternal)
    return FailedPreconditionError("InsFilter: external POS mode");
  if (!q_world_body.coeffs().allFinite() || q_world_body.norm() < 0.5 || !v_world_mps.allFinite()) {
    return InvalidArgumentError("InsFilter::InitializeAttitude: invalid attitude or velocity");
  }
  if (sigma_rpy_rad && !(sigma_rpy_rad->allFinite() && sigma_rpy_rad->minCoeff() > 0.0)) {
    return InvalidArgumentError(
        "InsFilter::InitializeAttitude: sigma_rpy_rad must be finite and > 0, got (" +
        std::to_string((*sigma_rpy_rad)(0)) + ", " + std::to_string((*sigma_rpy_rad)(1)) + ", " +
        std::to_string((*sigma_rpy_rad)(2)) + ")");
  }
  impl_->pending_sigma_rpy =
      impl_->options.use_stated_attitude_sigma ? sigma_rpy_rad : std::nullopt;
  impl_->pending_from = stamp;
  impl_->pending_q = q_world_body.normalized();
  impl_->pending_v = v_world_mps;
  impl_->pending_bg.setZero();
  impl_->pending_stamp = stamp;
  impl_->initialized = false;
  impl_->mode = Mode::kImu;
  return OkStatus();
}

Status InsFilter::InitializeStaticAlignment(const std::vector<ImuSample>& samples, double yaw_rad) {
  if (samples.size() < 10) {
    return InvalidArgumentError("InsFilter::InitializeStaticAlignment: needs at least 10 samples");
  }
  Eigen::Vector3d f = Eigen::Vector3d::Zero(), w = Eigen::Vector3d::Zero();
  for (const ImuSample& s : samples) {
    f += s.accel_mps2;
    w += s.gyro_radps;
  }
  f /= static_cast<double>(samples.size());
  w /= static_cast<double>(samples.size());
  if (!f.allFinite() || f.norm() < 5.0 || f.norm() > 15.0 || !std::isfinite(yaw_rad)) {
    return InvalidArgumentError(
        "InsFilter::InitializeStaticAlignment: mean specific force is not gravity-like "
        "(is the vehicle static?) or yaw not finite");
  }
  // At rest f_body = R^T (0, 0, g): roll = atan2(fy, fz), pitch = atan2(-fx, sqrt(fy^2 + fz^2)).
  const double roll = std::atan2(f.y(), f.z());
  const double pitch = std::atan2(-f.x(), std::hypot(f.y(), f.z()));
  const Eigen::Quaterniond q(FromRollPitchYaw(roll, pitch, yaw_rad));
  SLAM_MMS_RETURN_IF_ERROR(InitializeAttitude(q, Eigen::Vector3d::Zero()));
  impl_->pending_bg = w;  // at rest the gyro measures its bias (earth rate neglected)
  impl_->last_imu = samples.back();
  return OkStatus();
}

Status InsFilter::AddImu(const ImuSample& sample) {
  Impl& im = *impl_;
  if (im.mode == Mode::kExternal) {
    return FailedPreconditionError("InsFilter::AddImu: the filter holds an external POS solution");
  }
  if (!sample.accel_mps2.allFinite() || !sample.gyro_radps.allFinite()) {
    return InvalidArgumentError("InsFilter::AddImu: non-finite sample");
  }
  if (im.last_imu && sample.stamp <= im.last_imu->stamp) {
    return InvalidArgumentError("InsFilter::AddImu: samples must be strictly time-ordered");
  }
  const std::optional<ImuSample> prev = im.last_imu;
  im.last_imu = sample;
  if (!im.initialized && im.pending_q && im.pending_stamp && sample.stamp > *im.pending_stamp) {
    // Attitude and velocity known at pending_stamp, the position not yet: carry them forward
    // (strapdown, mean of the interval's end samples) to the first usable fix.
    Eigen::Vector3d a = sample.accel_mps2, w = sample.gyro_radps;
    if (prev && prev->stamp >= *im.pending_stamp) {
      a = 0.5 * (a + prev->accel_mps2);
      w = 0.5 * (w + prev->gyro_radps);
    }
    const double dt = sample.stamp.SecondsSince(*im.pending_stamp);
    if (dt > im.options.max_imu_gap_s) {
      // No IMU data near the attitude's stamp (or no real stamp given): carry it from here on.
      im.pending_stamp = sample.stamp;
      return OkStatus();
    }
    const Eigen::Matrix3d R = im.pending_q->toRotationMatrix();
    const Eigen::Vector3d dtheta = (w - im.pending_bg) * dt;
    im.pending_v += (R * a + im.g()) * dt;
    im.pending_q = (*im.pending_q * so3::ExpQuaternion(dtheta)).normalized();
    im.pending_stamp = sample.stamp;
    return OkStatus();
  }
  if (!im.initialized || sample.stamp <= im.x.stamp) return OkStatus();
  im.mode = Mode::kImu;
  const double dt = sample.stamp.SecondsSince(im.x.stamp);
  if (dt > im.options.max_imu_gap_s) {
    SLAM_MMS_LOG(kWarning) << "InsFilter: IMU gap of " << dt << " s bridged";
  }
  // Mean of the interval's end samples (the previous sample covers the interval start).
  Eigen::Vector3d a = sample.accel_mps2, w = sample.gyro_radps;
  if (prev) {
    a = 0.5 * (a + prev->accel_mps2);
    w = 0.5 * (w + prev->gyro_radps);
  }
  im.Propagate(a, w, dt);
  im.x.stamp = sample.stamp;
  im.Record();
  im.ApplyMotionConstraints(sample);
  return OkStatus();
}

StatusOr<GnssDecisionResult> InsFilter::AddGnss(const GnssFix& fix) {
  Impl& im = *impl_;
  if (im.mode == Mode::kExternal) {
    return FailedPreconditionError("InsFilter::AddGnss: the filter holds an external POS solution");
  }
  const Eigen::Vector3d& t_ba = im.options.gnss.t_body_antenna;
  if (!im.initialized) {
    SLAM_MMS_ASSIGN_OR_RETURN(GnssDecisionResult r, im.gnss.Process(fix, nullptr));
    if (r.usable() && im.pending_q) {
      // Complete the attitude initialisation with this fix's position.
      im.x = Nominal();
      im.x.stamp = fix.stamp;
      im.x.q = *im.pending_q;
      im.x.v = im.pending_v;
      im.x.bg = im.pending_bg;
      if (im.pending_stamp && fix.stamp > *im.pending_stamp) {
        // The last sample held over the rest of the interval.
        const double dt = fix.stamp.SecondsSince(*im.pending_stamp);
        if (im.last_imu) {
          im.x.v += (im.x.q.toRotationMatrix() * im.last_imu->accel_mps2 + im.g()) * dt;
          im.x.q = (im.x.q * so3::ExpQuaternion((im.last_imu->gyro_radps - im.pending_bg) * dt))
                       .normalized();
        }
      }
      im.pending_stamp.reset();
      im.x.p = r.measurement.p_world_antenna - im.x.q.toRotationMatrix() * t_ba;
      const Eigen::Matrix3d& C = r.measurement.cov_world_antenna;
      im.ResetAuxiliary();
      // The fix's error (bias + white) is the position's: cov(dp, db) = -bias covariance.
      const int model = Impl::ModelIndex(fix.type);
      const Options::GnssErrorModel& em = im.ErrorModel(model);
      im.bias_cov = Impl::BiasCovariance(em, C, r.innovation_weight);
      im.bias_model = model;
      im.bias_tau_s = em.correlation_time_s;
      im.last_used_fix = fix.stamp;
      // A stated attitude sigma grows while the IMU carried it to this fix: by the gyro bias
      // the filter has not yet observed (init_sigma_gyro_bias_radps) over the carry.
      std::optional<Eigen::Vector3d> sigma_rpy = im.pending_sigma_rpy;
      if (sigma_rpy && im.pending_from && fix.stamp > *im.pending_from) {
        const double drift =
            im.options.init_sigma_gyro_bias_radps * fix.stamp.SecondsSince(*im.pending_from);
        *sigma_rpy = (sigma_rpy->cwiseAbs2().array() + drift * drift).sqrt().matrix();
      }
      im.InitCovariance(std::sqrt(C(0, 0)), std::sqrt(C(2, 2)), sigma_rpy);
      im.P.block<3, 3>(kP, kP) = C;
      if (em.correlated_fraction > 0.0) {
        im.P.block<3, 3>(kP, kBn) = -im.bias_cov;
        im.P.block<3, 3>(kBn, kP) = -im.bias_cov;
      }
      im.initialized = true;
      im.pending_q.reset();
      im.history.clear();
      im.Record();
    }
    return r;
  }
  // Bring the state to the fix time (last sample held), or measure the lag of a late fix.
  double lag = fix.stamp < im.x.stamp ? im.x.stamp.SecondsSince(fix.stamp) : 0.0;
  if (lag > im.options.max_fix_latency_s) {
    // Too late to be compared with the state: not an input error (a host may deliver its streams
    // in batches), the fix is rejected and said why.
    GnssDecisionResult late;
    late.decision = GnssDecision::kReject;
    late.reason = "fix older than the state by " + std::to_string(lag) + " s (max_fix_latency_s)";
    return late;
  }
  if (fix.stamp > im.x.stamp) {
    if (!im.last_imu) return FailedPreconditionError("InsFilter::AddGnss: no IMU sample yet");
    im.Propagate(im.last_imu->accel_mps2, im.last_imu->gyro_radps,
                 fix.stamp.SecondsSince(im.x.stamp));
    im.x.stamp = fix.stamp;
    im.Record();
  }
  const Eigen::Matrix3d R = im.x.q.toRotationMatrix();
  // A new solution (another fix type, or the first fix after an outage) has its own bias.
  const int model = Impl::ModelIndex(fix.type);
  const bool new_solution =
      im.CanStartSolutionHere() &&
      (model != im.bias_model || !im.last_used_fix ||
       fix.stamp.SecondsSince(*im.last_used_fix) > im.options.gnss.outage_timeout_s);
  Eigen::Matrix<double, 3, kN> H = Eigen::Matrix<double, 3, kN>::Zero();
  H.block<3, 3>(0, kP) = Eigen::Matrix3d::Identity();
  H.block<3, 3>(0, kV) = -lag * Eigen::Matrix3d::Identity();
  H.block<3, 3>(0, kTh) = -R * so3::Hat(t_ba);
  // The innovation test: the measured covariance already holds the bias's share, so the
  // prediction's covariance leaves b_gnss out (its mean is in, unless a new solution starts).
  GnssPrediction pred;
  pred.p_world_antenna = im.x.p + R * t_ba - im.x.v * lag + (new_solution ? 0.0 : 1.0) * im.x.bn;
  pred.cov_world_antenna =
      H.leftCols<kBn>() * im.P.topLeftCorner<kBn, kBn>() * H.leftCols<kBn>().transpose();
  H.block<3, 3>(0, kBn) = Eigen::Matrix3d::Identity();
  SLAM_MMS_ASSIGN_OR_RETURN(GnssDecisionResult r, im.gnss.Process(fix, &pred));
  if (!r.usable()) return r;

  // Split the measured covariance: the correlated share is b_gnss's stationary covariance (the
  // fix type's weight included, the innovation test's inflation not), the rest is white.
  const Eigen::Matrix3d& C = r.measurement.cov_world_antenna;
  const Options::GnssErrorModel& em = im.ErrorModel(model);
  const Eigen::Matrix3d bias_cov = Impl::BiasCovariance(em, C, r.innovation_weight);
  const Eigen::Matrix3d Rm = em.correlated_fraction > 0.0 ? Eigen::Matrix3d(C - bias_cov) : C;
  if (new_solution) {
    im.ResetBias(bias_cov, em.correlation_time_s);
    im.bias_model = model;
  } else {
    im.bias_cov = bias_cov;  // the stationary covariance follows the reported sigma
  }
  im.last_used_fix = fix.stamp;
  const Eigen::Vector3d predicted = im.x.p + R * t_ba - im.x.v * lag + im.x.bn;
  im.Update<3>(H, r.measurement.p_world_antenna - predicted, Rm);
  im.Record();
  return r;
}

Status InsFilter::AddExternalPose(const InsState& state) {
  Impl& im = *impl_;
  if (im.mode == Mode::kImu) {
    return FailedPreconditionError("InsFilter::AddExternalPose: the filter is fusing IMU + GNSS");
  }
  if (!state.T_world_body.matrix().allFinite() || !state.cov_T_world_body.allFinite()) {
    return InvalidArgumentError("InsFilter::AddExternalPose: non-finite pose or covariance");
  }
  if (!im.history.empty() && state.stamp <= im.history.back().x.stamp) {
    return InvalidArgumentError("InsFilter::AddExternalPose: poses must be strictly time-ordered");
  }
  im.mode = Mode::kExternal;
  HistoryEntry e;
  e.x.stamp = state.stamp;
  e.x.q = Eigen::Quaterniond(state.T_world_body.linear()).normalized();
  e.x.p = state.T_world_body.translation();
  e.x.v = state.v_world_mps;
  e.x.ba = state.accel_bias_mps2;
  e.x.bg = state.gyro_bias_radps;
  e.cov_pose = state.cov_T_world_body;
  im.history.push_back(e);
  im.x = e.x;
  im.initialized = true;
  while (im.history.size() > 2 && im.history.back().x.stamp.SecondsSince(
                                      im.history.front().x.stamp) > im.options.history_s) {
    im.history.pop_front();
  }
  return OkStatus();
}

StatusOr<InsState> InsFilter::CurrentState() const {
  if (impl_->history.empty()) return FailedPreconditionError("InsFilter: not initialised");
  return ToInsState(impl_->history.back());
}

Status InsFilter::MarkAttitudeEpoch() {
  Impl& im = *impl_;
  if (im.mode == Mode::kExternal) {
    return FailedPreconditionError("InsFilter::MarkAttitudeEpoch: external POS (no covariances)");
  }
  if (!im.initialized || im.history.empty()) {
    return FailedPreconditionError("InsFilter::MarkAttitudeEpoch: not initialised");
  }
  Impl::AttitudeEpoch e;
  e.stamp = im.x.stamp;
  e.R = im.x.q.toRotationMatrix();
  e.cov = im.P.block<3, 3>(kTh, kTh);
  e.cross = im.P.middleCols<3>(kTh);
  im.attitude_epoch = e;
  return OkStatus();
}

StatusOr<InsFilter::AttitudeCorrelation> InsFilter::AttitudeSinceEpoch() const {
  const Impl& im = *impl_;
  if (!im.attitude_epoch) {
    return FailedPreconditionError("InsFilter::AttitudeSinceEpoch: no epoch marked");
  }
  AttitudeCorrelation c;
  c.epoch = im.attitude_epoch->stamp;
  c.now = im.x.stamp;
  c.R_world_body_epoch = im.attitude_epoch->R;
  c.R_world_body_now = im.x.q.toRotationMatrix();
  c.cov_epoch = im.attitude_epoch->cov;
  c.cov_now = im.P.block<3, 3>(kTh, kTh);
  c.cross = im.attitude_epoch->cross.middleRows<3>(kTh);
  return c;
}

void InsFilter::ForgetStatesBefore(Timestamp t) {
  auto& h = impl_->history;
  while (h.size() > 2 && h[1].x.stamp <= t) h.pop_front();
}

StatusOr<InsState> InsFilter::StateAt(Timestamp t) const {
  const auto& h = impl_->history;
  if (h.empty()) return FailedPreconditionError("InsFilter::StateAt: not initialised");
  if (t < h.front().x.stamp) {
    return OutOfRangeError("InsFilter::StateAt: time before the first stored state");
  }
  if (t >= h.back().x.stamp) {
    const double dt = t.SecondsSince(h.back().x.stamp);
    if (dt > impl_->options.max_extrapolation_s) {
      return OutOfRangeError("InsFilter::StateAt: time " + std::to_string(dt) +
                             " s after the last state (max_extrapolation_s)");
    }
    HistoryEntry e = h.back();
    if (dt > 0.0 && impl_->mode == Mode::kImu && impl_->last_imu) {
      e.x = Impl::Extrapolate(e.x, *impl_->last_imu, impl_->g(), dt);
    } else if (dt > 0.0) {
      e.x.p += e.x.v * dt;  // external POS: constant velocity
    }
    e.x.stamp = t;
    return ToInsState(e);
  }
  auto it = std::upper_bound(h.begin(), h.end(), t,
                             [](Timestamp a, const HistoryEntry& e) { return a < e.x.stamp; });
  const HistoryEntry& b = *it;
  const HistoryEntry& a = *(it - 1);
  const double alpha = t.SecondsSince(a.x.stamp) / b.x.stamp.SecondsSince(a.x.stamp);
  InsState s = ToInsState(a);
  s.stamp = t;
  s.T_world_body = InterpolatePose(s.T_world_body, MakeIsometry(b.x.q.normalized(), b.x.p), alpha);
  s.v_world_mps = (1.0 - alpha) * a.x.v + alpha * b.x.v;
  s.cov_T_world_body = (1.0 - alpha) * a.cov_pose + alpha * b.cov_pose;
  s.accel_bias_mps2 = (1.0 - alpha) * a.x.ba + alpha * b.x.ba;
  s.gyro_bias_radps = (1.0 - alpha) * a.x.bg + alpha * b.x.bg;
  return s;
}

const std::vector<InsFilterStep>& InsFilter::Steps() const { return impl_->steps; }

std::vector<InsState> InsFilter::States() const {
  std::vector<InsState> out;
  out.reserve(impl_->history.size());
  for (const HistoryEntry& e : impl_->history) out.push_back(ToInsState(e));
  return out;
}

}  // namespace slam_mms
