#include "slam_mms/ins/imu_preintegration.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/option_error.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms {

namespace {
bool PositiveFinite(double x) { return std::isfinite(x) && x > 0.0; }
}  // namespace

void ImuPreintegration::Options::SetImuNoise(const ImuNoiseSpec& spec) {
  gyro_noise_density = spec.gyro_noise_density;
  accel_noise_density = spec.accel_noise_density;
  gyro_bias_random_walk = spec.GyroBiasRandomWalk();
  accel_bias_random_walk = spec.AccelBiasRandomWalk();
}

Status ImuPreintegration::Options::Validate() const {
  if (!PositiveFinite(gyro_noise_density))
    return internal::OptionError("ImuPreintegration::Options", "gyro_noise_density",
                                 gyro_noise_density, "must be > 0");
  if (!PositiveFinite(accel_noise_density))
    return internal::OptionError("ImuPreintegration::Options", "accel_noise_density",
                                 accel_noise_density, "must be > 0");
  if (!PositiveFinite(gyro_bias_random_walk))
    return internal::OptionError("ImuPreintegration::Options", "gyro_bias_random_walk",
                                 gyro_bias_random_walk, "must be > 0");
  if (!PositiveFinite(accel_bias_random_walk))
    return internal::OptionError("ImuPreintegration::Options", "accel_bias_random_walk",
                                 accel_bias_random_walk, "must be > 0");
  if (!PositiveFinite(max_sample_dt_s))
    return internal::OptionError("ImuPreintegration::Options", "max_sample_dt_s", max_sample_dt_s,
                                 "must be > 0");
  return OkStatus();
}

ImuPreintegration::ImuPreintegration() = default;

ImuPreintegration::ImuPreintegration(const Options& options, const Eigen::Vector3d& accel_bias_mps2,
                                     const Eigen::Vector3d& gyro_bias_radps)
    : options_(options), ba_lin_(accel_bias_mps2), bg_lin_(gyro_bias_radps) {}

void ImuPreintegration::Reset(const Eigen::Vector3d& accel_bias_mps2,
                              const Eigen::Vector3d& gyro_bias_radps) {
  const Options options = options_;
  *this = ImuPreintegration(options, accel_bias_mps2, gyro_bias_radps);
}

Status ImuPreintegration::Integrate(const Eigen::Vector3d& accel_mps2,
                                    const Eigen::Vector3d& gyro_radps, double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s) || dt_s > options_.max_sample_dt_s) {
    return InvalidArgumentError(
        "ImuPreintegration::Integrate: dt_s = " + std::to_string(dt_s) +
        "; must be in (0, max_sample_dt_s = " + std::to_string(options_.max_sample_dt_s) + "]");
  }
  if (!accel_mps2.allFinite() || !gyro_radps.allFinite()) {
    return InvalidArgumentError("ImuPreintegration::Integrate: non-finite IMU measurement");
  }
  const Eigen::Vector3d a = accel_mps2 - ba_lin_;
  const Eigen::Vector3d w = gyro_radps - bg_lin_;
  const Eigen::Vector3d phi = w * dt_s;
  const Eigen::Matrix3d dR_step = so3::Exp(phi);
  const Eigen::Matrix3d Jr = so3::RightJacobian(phi);
  const Eigen::Matrix3d a_hat = so3::Hat(a);
  const double dt2 = dt_s * dt_s;
  // The specific force of the interval is rotated with the interval's mid attitude: eq 13 uses
  // dR_ik (first order in the rotation over one sample); the midpoint keeps the scheme second order
  // (about 10x smaller error at 100 Hz on a car), at no cost.
  const Eigen::Matrix3d R_mid = dR_ * so3::Exp(0.5 * phi);

  // Covariance propagation, state [dtheta, dv, dp] (Forster et al. eq 62-63).
  Matrix9d A = Matrix9d::Identity();
  A.block<3, 3>(0, 0) = dR_step.transpose();
  A.block<3, 3>(3, 0) = -R_mid * a_hat * dt_s;
  A.block<3, 3>(6, 0) = -0.5 * R_mid * a_hat * dt2;
  A.block<3, 3>(6, 3) = Eigen::Matrix3d::Identity() * dt_s;
  Eigen::Matrix<double, 9, 3> Bg = Eigen::Matrix<double, 9, 3>::Zero();
  Eigen::Matrix<double, 9, 3> Ba = Eigen::Matrix<double, 9, 3>::Zero();
  Bg.block<3, 3>(0, 0) = Jr * dt_s;
  Ba.block<3, 3>(3, 0) = R_mid * dt_s;
  Ba.block<3, 3>(6, 0) = 0.5 * R_mid * dt2;
  // Discrete white-noise variances: density^2 / dt.
  const double var_g = options_.gyro_noise_density * options_.gyro_noise_density / dt_s;
  const double var_a = options_.accel_noise_density * options_.accel_noise_density / dt_s;
  cov_ = A * cov_ * A.transpose() + var_g * Bg * Bg.transpose() + var_a * Ba * Ba.transpose();

  // Bias Jacobians (Forster et al. appendix B), p before v before R: each uses the old values.
  dp_dba_ += dv_dba_ * dt_s - 0.5 * R_mid * dt2;
  dp_dbg_ += dv_dbg_ * dt_s - 0.5 * R_mid * a_hat * dR_dbg_ * dt2;
  dv_dba_ -= R_mid * dt_s;
  dv_dbg_ -= R_mid * a_hat * dR_dbg_ * dt_s;
  dR_dbg_ = dR_step.transpose() * dR_dbg_ - Jr * dt_s;

  // The deltas themselves (eq 13, midpoint attitude).
  dp_ += dv_ * dt_s + 0.5 * R_mid * a * dt2;
  dv_ += R_mid * a * dt_s;
  dR_ = dR_ * dR_step;
  dt_ += dt_s;
  ++num_samples_;
  return OkStatus();
}

Status ImuPreintegration::IntegrateWindow(const std::vector<ImuSample>& samples, Timestamp t_start,
                                          Timestamp t_end) {
  if (samples.empty())
    return InvalidArgumentError("ImuPreintegration::IntegrateWindow: no samples");
  if (!(t_start < t_end)) {
    return InvalidArgumentError("ImuPreintegration::IntegrateWindow: t_start must be < t_end");
  }
  for (size_t k = 1; k < samples.size(); ++k) {
    if (!(samples[k - 1].stamp < samples[k].stamp)) {
      return InvalidArgumentError(
          "ImuPreintegration::IntegrateWindow: samples are not strictly time-ordered at index " +
          std::to_string(k));
    }
  }
  if (samples.front().stamp.SecondsSince(t_start) > options_.max_sample_dt_s ||
      t_end.SecondsSince(samples.back().stamp) > options_.max_sample_dt_s) {
    return OutOfRangeError(
        "ImuPreintegration::IntegrateWindow: the samples do not cover the window within "
        "max_sample_dt_s");
  }
  // Pieces: [t_start, first sample) held, intervals between samples (mean of the ends), after last.
  auto integrate_piece = [&](Timestamp a, Timestamp b, const Eigen::Vector3d& acc,
                             const Eigen::Vector3d& gyr) -> Status {
    const Timestamp lo = std::max(a, t_start);
    const Timestamp hi = std::min(b, t_end);
    if (!(lo < hi)) return OkStatus();
    return Integrate(acc, gyr, hi.SecondsSince(lo));
  };
  SLAM_MMS_RETURN_IF_ERROR(integrate_piece(t_start, samples.front().stamp,
                                           samples.front().accel_mps2, samples.front().gyro_radps));
  for (size_t k = 1; k < samples.size(); ++k) {
    const ImuSample& s0 = samples[k - 1];
    const ImuSample& s1 = samples[k];
    if (s1.stamp <= t_start) continue;
    if (s0.stamp >= t_end) break;
    SLAM_MMS_RETURN_IF_ERROR(integrate_piece(s0.stamp, s1.stamp,
                                             0.5 * (s0.accel_mps2 + s1.accel_mps2),
                                             0.5 * (s0.gyro_radps + s1.gyro_radps)));
  }
  return integrate_piece(samples.back().stamp, t_end, samples.back().accel_mps2,
                         samples.back().gyro_radps);
}

Eigen::Matrix3d ImuPreintegration::CorrectedDeltaR(const Eigen::Vector3d& gyro_bias_radps) const {
  return dR_ * so3::Exp(dR_dbg_ * (gyro_bias_radps - bg_lin_));
}

Eigen::Vector3d ImuPreintegration::CorrectedDeltaV(const Eigen::Vector3d& accel_bias_mps2,
                                                   const Eigen::Vector3d& gyro_bias_radps) const {
  return dv_ + dv_dba_ * (accel_bias_mps2 - ba_lin_) + dv_dbg_ * (gyro_bias_radps - bg_lin_);
}

Eigen::Vector3d ImuPreintegration::CorrectedDeltaP(const Eigen::Vector3d& accel_bias_mps2,
                                                   const Eigen::Vector3d& gyro_bias_radps) const {
  return dp_ + dp_dba_ * (accel_bias_mps2 - ba_lin_) + dp_dbg_ * (gyro_bias_radps - bg_lin_);
}

NavState ImuPreintegration::Predict(const Eigen::Isometry3d& T_frame_body,
                                    const Eigen::Vector3d& v_frame,
                                    const Eigen::Vector3d& g_frame) const {
  NavState s;
  s.q_world_body = Eigen::Quaterniond(T_frame_body.linear());
  s.p_world = T_frame_body.translation();
  s.v_world = v_frame;
  return Predict(s, g_frame);
}

NavState ImuPreintegration::Predict(const NavState& state_i, const Eigen::Vector3d& g_world) const {
  NavState s;
  const Eigen::Matrix3d R_i = state_i.q_world_body.toRotationMatrix();
  s.q_world_body = Eigen::Quaterniond(R_i * dR_).normalized();
  s.v_world = state_i.v_world + g_world * dt_ + R_i * dv_;
  s.p_world = state_i.p_world + state_i.v_world * dt_ + 0.5 * g_world * dt_ * dt_ + R_i * dp_;
  return s;
}

}  // namespace slam_mms
