#include "sim/oxts_synthesis.hpp"

#include <cmath>

#include "sim/random.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms::sim {

InsErrorProcess::InsErrorProcess(double rp, double yaw, double vel, uint64_t seed)
    : rp_sigma_(rp), yaw_sigma_(yaw), vel_sigma_(vel), rng_(MixSeed(seed, 0x1E5)) {
  rpy_ = Eigen::Vector3d(rp_sigma_ * Normal(), rp_sigma_ * Normal(), yaw_sigma_ * Normal());
  vel_ = vel_sigma_ * Eigen::Vector3d(Normal(), Normal(), Normal());
}

double InsErrorProcess::Normal() {
  rng_ = MixSeed(rng_, 3);
  const double u1 = (static_cast<double>(rng_ >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  rng_ = MixSeed(rng_, 5);
  const double u2 = (static_cast<double>(rng_ >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

void InsErrorProcess::Step(double dt, bool gnss_available) {
  // Roll/pitch are held by gravity (tau 100 s); heading and velocity are held by GNSS (tau 300 s /
  // 10 s) and drift as random walks without it.
  const double e_rp = std::exp(-dt / 100.0);
  rpy_.x() = e_rp * rpy_.x() + rp_sigma_ * std::sqrt(1 - e_rp * e_rp) * Normal();
  rpy_.y() = e_rp * rpy_.y() + rp_sigma_ * std::sqrt(1 - e_rp * e_rp) * Normal();
  if (gnss_available) {
    const double e_y = std::exp(-dt / 300.0), e_v = std::exp(-dt / 10.0);
    rpy_.z() = e_y * rpy_.z() + yaw_sigma_ * std::sqrt(1 - e_y * e_y) * Normal();
    for (int k = 0; k < 3; ++k)
      vel_(k) = e_v * vel_(k) + vel_sigma_ * std::sqrt(1 - e_v * e_v) * Normal();
  } else {
    rpy_.z() += yaw_sigma_ * std::sqrt(dt / 100.0) * Normal();
    for (int k = 0; k < 3; ++k) vel_(k) += vel_sigma_ * std::sqrt(dt / 10.0) * Normal();
  }
}

int PosMode(GnssState s) {
  switch (s) {
    case GnssState::kRtkFixed: return static_cast<int>(OxtsGnssMode::kRtkInteger);
    case GnssState::kRtkFloat: return static_cast<int>(OxtsGnssMode::kRtkFloat);
    case GnssState::kSps: return static_cast<int>(OxtsGnssMode::kSps);
    case GnssState::kNone: return static_cast<int>(OxtsGnssMode::kNone);
  }
  return 0;
}

OxtsRecord SynthesizeOxts(const BodyState& truth, const BodyState& inertial_truth,
                          const ImuSample& imu, const GnssSample& gnss, const InsErrorProcess& ins,
                          const GeographicLib::LocalCartesian& enu) {
  OxtsRecord r;
  const Eigen::Vector3d p = truth.T_world_body.translation() + gnss.error_enu_m;
  enu.Reverse(p.x(), p.y(), p.z(), r.lat_deg, r.lon_deg, r.alt_m);
  const Eigen::Vector3d rpy = truth.rpy_rad + ins.rpy_error();
  r.roll_rad = rpy.x();
  r.pitch_rad = rpy.y();
  r.yaw_rad = std::remainder(rpy.z(), 2.0 * M_PI);
  const Eigen::Vector3d v = inertial_truth.v_world_mps + ins.velocity_error();
  r.ve = v.x();
  r.vn = v.y();
  r.vu = v.z();
  const double cy = std::cos(r.yaw_rad), sy = std::sin(r.yaw_rad);
  r.vf = v.x() * cy + v.y() * sy;
  r.vl = -v.x() * sy + v.y() * cy;
  r.ax = imu.accel_mps2.x();
  r.ay = imu.accel_mps2.y();
  r.az = imu.accel_mps2.z();
  r.wx = imu.gyro_radps.x();
  r.wy = imu.gyro_radps.y();
  r.wz = imu.gyro_radps.z();
  // Level frame (forward, left, up): the body frame with roll and pitch removed.
  const Eigen::Matrix3d R_level_body =
      Eigen::AngleAxisd(r.pitch_rad, Eigen::Vector3d::UnitY()).matrix() *
      Eigen::AngleAxisd(r.roll_rad, Eigen::Vector3d::UnitX()).matrix();
  const Eigen::Vector3d a_level = R_level_body * imu.accel_mps2;
  const Eigen::Vector3d w_level = R_level_body * imu.gyro_radps;
  r.af = a_level.x();
  r.al = a_level.y();
  r.au = a_level.z();
  r.wf = w_level.x();
  r.wl = w_level.y();
  r.wu = w_level.z();
  r.pos_accuracy_m = gnss.sigma_horizontal_m;
  switch (gnss.state) {
    case GnssState::kRtkFixed: r.vel_accuracy_mps = 0.02; break;
    case GnssState::kRtkFloat: r.vel_accuracy_mps = 0.04; break;
    case GnssState::kSps: r.vel_accuracy_mps = 0.1; break;
    case GnssState::kNone: r.vel_accuracy_mps = 0.1 + 0.01 * gnss.sigma_horizontal_m; break;
  }
  r.navstat = kOxtsNavstatLocked;
  r.numsats = gnss.num_satellites;
  r.posmode = PosMode(gnss.state);
  r.velmode = r.posmode;
  r.orimode = 0;
  return r;
}

}  // namespace slam_mms::sim
