#include "slam_mms/ins/ins_filter.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {

namespace {

// Error-state indices.
constexpr int kP = 0, kV = 3, kTh = 6, kBa = 9, kBg = 12;

bool PositiveFinite(double x) { return std::isfinite(x) && x > 0.0; }

Status FieldError(const char* field, double value, const char* rule) {
  std::ostringstream s;
  s << "InsFilter::Options::" << field << " = " << value << "; " << rule;
  return InvalidArgumentError(s.str());
}

struct Nominal {
  Timestamp stamp;
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // R_world_body
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();
};

struct HistoryEntry {
  Nominal x;
  Matrix6d cov_pose;  // rotation first, right perturbation of T_world_body
};

// 6x6 pose covariance [omega, v_body] from the 15x15 [dp_world, dv, dtheta, ...]:
// T_hat Exp([w; rho]) = (R Exp(w), p + R rho) -> w = dtheta, rho = R^T dp.
Matrix6d PoseCovariance(const Matrix15d& P, const Eigen::Matrix3d& R) {
  Eigen::Matrix<double, 6, 15> J = Eigen::Matrix<double, 6, 15>::Zero();
  J.block<3, 3>(0, kTh) = Eigen::Matrix3d::Identity();
  J.block<3, 3>(3, kP) = R.transpose();
  return J * P * J.transpose();
}

InsState ToInsState(const HistoryEntry& e) {
  InsState s;
  s.stamp = e.x.stamp;
  s.T_world_body = MakeIsometry(e.x.q.normalized(), e.x.p);
  s.v_world_mps = e.x.v;
  s.cov_T_world_body = e.cov_pose;
  s.accel_bias_mps2 = e.x.ba;
  s.gyro_bias_radps = e.x.bg;
  return s;
}

}  // namespace

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
  return gnss.Validate();
}

double InsFilter::NormalGravity(double latitude_deg, double height_m) {
  // Somigliana (WGS-84), then the free-air correction.
  const double s2 = std::pow(std::sin(latitude_deg * M_PI / 180.0), 2);
  const double g0 =
      9.7803253359 * (1.0 + 0.00193185265241 * s2) / std::sqrt(1.0 - 0.00669437999013 * s2);
  return g0 - 3.086e-6 * height_m;
}

enum class Mode { kNone, kImu, kExternal };

struct InsFilter::Impl {
  Options options;
  GnssPrior gnss;
  Mode mode = Mode::kNone;
  bool initialized = false;
  std::optional<Eigen::Quaterniond> pending_q;  // attitude waiting for a GNSS position
  Eigen::Vector3d pending_v = Eigen::Vector3d::Zero();
  Eigen::Vector3d pending_bg = Eigen::Vector3d::Zero();
  std::optional<Timestamp> pending_stamp;  // when pending_q / pending_v hold (carried by the IMU)
  Nominal x;
  Matrix15d P = Matrix15d::Zero();
  std::optional<ImuSample> last_imu;
  std::deque<HistoryEntry> history;
  // Smoother record (options.record_steps): the transition since the last recorded step.
  std::vector<InsFilterStep> steps;
  Matrix15d F_since_step = Matrix15d::Identity();
  bool propagated_since_step = false;

  Eigen::Vector3d g() const {
    double gm = options.gravity_mps2;
    if (!(gm > 0.0)) {
      const GeodeticPoint o = gnss.origin();
      gm = gnss.has_origin() ? NormalGravity(o.latitude_deg, o.height_m) : 9.80665;
    }
    return Eigen::Vector3d(0.0, 0.0, -gm);
  }

  void InitCovariance(double sigma_p_h, double sigma_p_v) {
    P.setZero();
    P.block<3, 3>(kP, kP).diagonal() << sigma_p_h * sigma_p_h, sigma_p_h * sigma_p_h,
        sigma_p_v * sigma_p_v;
    P.block<3, 3>(kV, kV).diagonal().setConstant(std::pow(options.init_sigma_velocity_mps, 2));
    // Roll/pitch/yaw sigmas mapped into the body-frame right perturbation approximately: the yaw
    // uncertainty is about world z, i.e. R^T z in body.
    const Eigen::Matrix3d R = x.q.toRotationMatrix();
    const double srp = options.init_sigma_roll_pitch_rad, sy = options.init_sigma_yaw_rad;
    const Eigen::Matrix3d cov_world = Eigen::Vector3d(srp * srp, srp * srp, sy * sy).asDiagonal();
    P.block<3, 3>(kTh, kTh) = R.transpose() * cov_world * R;
    P.block<3, 3>(kBa, kBa).diagonal().setConstant(std::pow(options.init_sigma_accel_bias_mps2, 2));
    P.block<3, 3>(kBg, kBg).diagonal().setConstant(std::pow(options.init_sigma_gyro_bias_radps, 2));
  }

  void Record() {
    HistoryEntry e{x, PoseCovariance(P, x.q.toRotationMatrix())};
    if (options.record_steps) RecordStep(e);
    if (!history.empty() && history.back().x.stamp == x.stamp) {
      history.back() = e;
    } else {
      history.push_back(e);
    }
    while (history.size() > 2 &&
           history.back().x.stamp.SecondsSince(history.front().x.stamp) > options.history_s) {
      history.pop_front();
    }
  }

  // A propagation starts a new step; an update (no propagation since) rewrites the last step's
  // a-posteriori part. Initialisation clears the record first (history.empty()).
  void RecordStep(const HistoryEntry& e) {
    if (history.empty()) steps.clear();
    if (steps.empty() || propagated_since_step) {
      InsFilterStep st;
      st.stamp = x.stamp;
      st.prior = ToInsState(e);
      st.posterior = st.prior;
      st.P_prior = P;
      st.P_posterior = P;
      st.F = steps.empty() ? Matrix15d::Identity() : F_since_step;
      steps.push_back(st);
    } else {
      InsFilterStep& st = steps.back();
      st.posterior = ToInsState(e);
      st.P_posterior = P;
      st.updated = true;
    }
    F_since_step.setIdentity();
    propagated_since_step = false;
  }

  // Nominal + covariance propagation over dt with bias-corrected mean measurements.
  void Propagate(const Eigen::Vector3d& accel, const Eigen::Vector3d& gyro, double dt) {
    const Eigen::Vector3d a = accel - x.ba;
    const Eigen::Vector3d w = gyro - x.bg;
    const Eigen::Matrix3d R = x.q.toRotationMatrix();
    const Eigen::Vector3d phi = w * dt;
    const Eigen::Matrix3d dR = so3::Exp(phi);
    const Eigen::Matrix3d R_mid = R * so3::Exp(0.5 * phi);
    const Eigen::Vector3d acc_world = R_mid * a + g();
    const double dt2 = dt * dt;

    Matrix15d F = Matrix15d::Identity();
    const Eigen::Matrix3d a_hat = so3::Hat(a);
    F.block<3, 3>(kP, kV) = Eigen::Matrix3d::Identity() * dt;
    F.block<3, 3>(kP, kTh) = -0.5 * R_mid * a_hat * dt2;
    F.block<3, 3>(kP, kBa) = -0.5 * R_mid * dt2;
    F.block<3, 3>(kV, kTh) = -R_mid * a_hat * dt;
    F.block<3, 3>(kV, kBa) = -R_mid * dt;
    F.block<3, 3>(kTh, kTh) = dR.transpose();
    F.block<3, 3>(kTh, kBg) = -so3::RightJacobian(phi) * dt;
    Matrix15d Q = Matrix15d::Zero();
    const double qa = std::pow(options.accel_noise_density, 2) * dt;
    const double qg = std::pow(options.gyro_noise_density, 2) * dt;
    Q.block<3, 3>(kP, kP).diagonal().setConstant(qa * dt2 / 3.0);
    Q.block<3, 3>(kP, kV).diagonal().setConstant(qa * dt / 2.0);
    Q.block<3, 3>(kV, kP).diagonal().setConstant(qa * dt / 2.0);
    Q.block<3, 3>(kV, kV).diagonal().setConstant(qa);
    Q.block<3, 3>(kTh, kTh).diagonal().setConstant(qg);
    Q.block<3, 3>(kBa, kBa).diagonal().setConstant(std::pow(options.accel_bias_random_walk, 2) *
                                                   dt);
    Q.block<3, 3>(kBg, kBg).diagonal().setConstant(std::pow(options.gyro_bias_random_walk, 2) * dt);
    P = F * P * F.transpose() + Q;
    P = 0.5 * (P + P.transpose());
    if (options.record_steps) {
      F_since_step = F * F_since_step;
      propagated_since_step = true;
    }

    x.p += x.v * dt + 0.5 * acc_world * dt2;
    x.v += acc_world * dt;
    x.q = Eigen::Quaterniond(R * dR).normalized();
  }

  // Nominal-only prediction with a held sample (for extrapolated queries).
  static Nominal Extrapolate(Nominal n, const ImuSample& s, const Eigen::Vector3d& g, double dt) {
    const Eigen::Vector3d a = s.accel_mps2 - n.ba;
    const Eigen::Vector3d w = s.gyro_radps - n.bg;
    const Eigen::Matrix3d R = n.q.toRotationMatrix();
    const Eigen::Vector3d acc_world = R * so3::Exp(0.5 * w * dt) * a + g;
    n.p += n.v * dt + 0.5 * acc_world * dt * dt;
    n.v += acc_world * dt;
    n.q = Eigen::Quaterniond(R * so3::Exp(w * dt)).normalized();
    n.stamp = n.stamp.PlusSeconds(dt);
    return n;
  }
};

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
const Matrix15d& InsFilter::covariance() const { return impl_->P; }
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
                                     std::optional<Timestamp> stamp) {
  if (impl_->mode == Mode::kExternal)
    return FailedPreconditionError("InsFilter: external POS mode");
  if (!q_world_body.coeffs().allFinite() || q_world_body.norm() < 0.5 || !v_world_mps.allFinite()) {
    return InvalidArgumentError("InsFilter::InitializeAttitude: invalid attitude or velocity");
  }
  impl_->pending_q = q_world_body.normalized();
  impl_->pending_v = v_world_mps;
  impl_->pending_bg.setZero();
  impl_->pending_stamp = stamp;
  impl_->initialized = false;
  impl_->mode = Mode::kImu;
  return OkStatus();
}

Status InsFilter::InitializeFromOxts(const OxtsRecord& record, Timestamp stamp) {
  const Eigen::Quaterniond q(OxtsAttitude(record));
  SLAM_MMS_RETURN_IF_ERROR(InitializeAttitude(q, Eigen::Vector3d(record.ve, record.vn, record.vu)));
  auto r = AddGnss(ToGnssFix(record, stamp));
  if (!r.ok()) return r.status();
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
      im.InitCovariance(std::sqrt(C(0, 0)), std::sqrt(C(2, 2)));
      im.P.block<3, 3>(kP, kP) = C;
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
  Eigen::Matrix<double, 3, 15> H = Eigen::Matrix<double, 3, 15>::Zero();
  H.block<3, 3>(0, kP) = Eigen::Matrix3d::Identity();
  H.block<3, 3>(0, kV) = -lag * Eigen::Matrix3d::Identity();
  H.block<3, 3>(0, kTh) = -R * so3::Hat(t_ba);
  GnssPrediction pred;
  pred.p_world_antenna = im.x.p + R * t_ba - im.x.v * lag;
  pred.cov_world_antenna = H * im.P * H.transpose();
  SLAM_MMS_ASSIGN_OR_RETURN(GnssDecisionResult r, im.gnss.Process(fix, &pred));
  if (!r.usable()) return r;

  // EKF update (Joseph form), then injection into the nominal state and the reset Jacobian.
  const Eigen::Matrix3d& Rm = r.measurement.cov_world_antenna;
  const Eigen::Matrix3d S = H * im.P * H.transpose() + Rm;
  const Eigen::Matrix<double, 15, 3> K = im.P * H.transpose() * S.inverse();
  const Eigen::Matrix<double, 15, 1> dx =
      K * (r.measurement.p_world_antenna - pred.p_world_antenna);
  const Matrix15d IKH = Matrix15d::Identity() - K * H;
  im.P = IKH * im.P * IKH.transpose() + K * Rm * K.transpose();
  im.x.p += dx.segment<3>(kP);
  im.x.v += dx.segment<3>(kV);
  const Eigen::Vector3d dth = dx.segment<3>(kTh);
  im.x.q = Eigen::Quaterniond(R * so3::Exp(dth)).normalized();
  im.x.ba += dx.segment<3>(kBa);
  im.x.bg += dx.segment<3>(kBg);
  Matrix15d G = Matrix15d::Identity();
  G.block<3, 3>(kTh, kTh) -= 0.5 * so3::Hat(dth);
  im.P = G * im.P * G.transpose();
  im.P = 0.5 * (im.P + im.P.transpose());
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
