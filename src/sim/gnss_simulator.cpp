#include "slam_mms/sim/gnss_simulator.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "sim/random.hpp"

namespace slam_mms::sim {

const char* GnssStateName(GnssState s) {
  switch (s) {
    case GnssState::kNone: return "none";
    case GnssState::kSps: return "sps";
    case GnssState::kRtkFloat: return "rtk_float";
    case GnssState::kRtkFixed: return "rtk_fixed";
  }
  return "none";
}

Status GnssSimulator::Options::Validate() const {
  auto fail = [](const std::string& name, double v, const char* rule) {
    std::ostringstream s;
    s << "GnssSimulator::Options::" << name << " = " << v << "; " << rule;
    return InvalidArgumentError(s.str());
  };
  if (!(rate_hz > 0.0)) return fail("rate_hz", rate_hz, "must be > 0");
  if (!(epoch_rate_hz > 0.0 && epoch_rate_hz <= rate_hz))
    return fail("epoch_rate_hz", epoch_rate_hz, "must be in (0, rate_hz]");
  for (auto [name, v] : {std::pair<const char*, double>{"sigma_fixed_h_m", sigma_fixed_h_m},
                         {"sigma_fixed_v_m", sigma_fixed_v_m},
                         {"sigma_float_h_m", sigma_float_h_m},
                         {"sigma_float_v_m", sigma_float_v_m},
                         {"sigma_sps_h_m", sigma_sps_h_m},
                         {"sigma_sps_v_m", sigma_sps_v_m},
                         {"multipath_rate_hz", multipath_rate_hz},
                         {"multipath_sigma_m", multipath_sigma_m},
                         {"urban_canyon_scale", urban_canyon_scale},
                         {"ins_velocity_drift_sigma_mps", ins_velocity_drift_sigma_mps},
                         {"ins_accel_drift_sigma_mps2", ins_accel_drift_sigma_mps2}}) {
    if (!(v >= 0.0) || !std::isfinite(v)) return fail(name, v, "must be finite and >= 0");
  }
  if (!(blockage_float <= blockage_sps && blockage_sps <= blockage_none))
    return fail("blockage_sps", blockage_sps,
                "thresholds must satisfy blockage_float <= blockage_sps <= blockage_none");
  for (size_t i = 0; i < outages.size(); ++i) {
    if (!(outages[i].duration_s > 0.0) || !std::isfinite(outages[i].start_s))
      return fail("outages[" + std::to_string(i) + "].duration_s", outages[i].duration_s,
                  "must be > 0 with a finite start");
  }
  return OkStatus();
}

GnssSimulator::GnssSimulator(const Options& options, uint64_t seed)
    : options_(options), rng_(MixSeed(seed, 0x6E55)), state_(options.best_state) {
  const Eigen::Vector3d s = Sigma(state_);
  bias_ = Eigen::Vector3d(s.x() * Normal(), s.y() * Normal(), s.z() * Normal());
  error_ = bias_;
  sats_ = 8 + static_cast<int>(Uniform() * 4);
}

double GnssSimulator::Uniform() {
  rng_ = MixSeed(rng_, 0x99);
  return (static_cast<double>(rng_ >> 11) + 0.5) * (1.0 / 9007199254740992.0);
}

double GnssSimulator::Normal() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  const double u1 = Uniform(), u2 = Uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  spare_ = r * std::sin(2.0 * M_PI * u2);
  has_spare_ = true;
  return r * std::cos(2.0 * M_PI * u2);
}

Eigen::Vector3d GnssSimulator::Sigma(GnssState s) const {
  switch (s) {
    case GnssState::kRtkFixed:
      return {options_.sigma_fixed_h_m, options_.sigma_fixed_h_m, options_.sigma_fixed_v_m};
    case GnssState::kRtkFloat:
      return {options_.sigma_float_h_m, options_.sigma_float_h_m, options_.sigma_float_v_m};
    case GnssState::kSps:
    case GnssState::kNone:
      return {options_.sigma_sps_h_m, options_.sigma_sps_h_m, options_.sigma_sps_v_m};
  }
  return Eigen::Vector3d::Ones();
}

bool GnssSimulator::InOutage(double t) const {
  for (const auto& o : options_.outages)
    if (t >= o.start_s && t < o.start_s + o.duration_s) return true;
  return false;
}

void GnssSimulator::Enter(GnssState s, double t) {
  if (s == state_) return;
  if (s == GnssState::kNone) {
    t_outage_start_ = t;
    drift_v_ =
        options_.ins_velocity_drift_sigma_mps * Eigen::Vector3d(Normal(), Normal(), 0.3 * Normal());
    drift_a_ =
        options_.ins_accel_drift_sigma_mps2 * Eigen::Vector3d(Normal(), Normal(), 0.3 * Normal());
  } else {
    // A new solution type starts with its own bias (stationary draw).
    const Eigen::Vector3d sg = Sigma(s);
    bias_ = Eigen::Vector3d(sg.x() * Normal(), sg.y() * Normal(), sg.z() * Normal());
  }
  state_ = s;
  t_state_ = t;
  // Delay before the next upgrade becomes possible.
  switch (s) {
    case GnssState::kNone: upgrade_delay_ = Uniform() * 2.0 + 1.0; break;
    case GnssState::kSps: upgrade_delay_ = 5.0 + 10.0 * Uniform(); break;
    case GnssState::kRtkFloat: upgrade_delay_ = 10.0 + 20.0 * Uniform(); break;
    case GnssState::kRtkFixed: upgrade_delay_ = 0.0; break;
  }
}

GnssSample GnssSimulator::Step(double t, double sky_blockage) {
  const double dt = t_prev_ < -1e8 ? 1.0 / options_.rate_hz : std::max(0.0, t - t_prev_);
  t_prev_ = t;
  GnssSample out;
  out.sky_blockage = sky_blockage;
  out.in_scripted_outage = InOutage(t);
  // Best state reachable now.
  const double b = std::clamp(sky_blockage * options_.urban_canyon_scale, 0.0, 1.0);
  GnssState target = options_.best_state;
  if (b > options_.blockage_none)
    target = GnssState::kNone;
  else if (b > options_.blockage_sps)
    target = std::min(target, GnssState::kSps);
  else if (b > options_.blockage_float)
    target = std::min(target, GnssState::kRtkFloat);
  if (out.in_scripted_outage) target = GnssState::kNone;
  if (target < state_) {
    // Degrade: immediately in a scripted outage, else with a ~1 s reaction.
    if (out.in_scripted_outage || Uniform() < dt / 1.0) Enter(target, t);
  } else if (target > state_ && t - t_state_ >= upgrade_delay_) {
    Enter(static_cast<GnssState>(static_cast<int>(state_) + 1), t);
  }
  // Error processes.
  const Eigen::Vector3d sg = Sigma(state_);
  if (state_ != GnssState::kNone) {
    const double tau = state_ == GnssState::kRtkFixed   ? 30.0
                       : state_ == GnssState::kRtkFloat ? 20.0
                                                        : 60.0;
    const double e = std::exp(-dt / tau), q = std::sqrt(std::max(0.0, 1.0 - e * e));
    for (int k = 0; k < 3; ++k) bias_(k) = e * bias_(k) + sg(k) * q * Normal();
    if (t >= next_epoch_) {
      next_epoch_ = t + 1.0 / options_.epoch_rate_hz - 1e-9;
      white_ = 0.2 * Eigen::Vector3d(sg.x() * Normal(), sg.y() * Normal(), sg.z() * Normal());
    }
    // Multipath jumps in SPS.
    if (state_ == GnssState::kSps &&
        Uniform() < options_.multipath_rate_hz * (1.0 + 10.0 * b) * dt) {
      jump_ += options_.multipath_sigma_m * Eigen::Vector3d(Normal(), Normal(), 0.5 * Normal());
      jump_tau_ = 5.0 + 15.0 * Uniform();
    }
    jump_ *= std::exp(-dt / jump_tau_);
    if (state_ != GnssState::kSps) jump_ *= std::exp(-dt / 1.0);
    const Eigen::Vector3d gnss_error = bias_ + white_ + jump_;
    // The INS solution converges back to the GNSS error after dead reckoning (tau 2 s).
    const double c = std::exp(-dt / 2.0);
    error_ = c * error_ + (1.0 - c) * gnss_error;
    if ((error_ - gnss_error).norm() < 1e-3 || t - t_state_ > 20.0) error_ = gnss_error;
    if (t - t_state_ < 1e-9 && (error_ - gnss_error).norm() > 5.0) error_ = gnss_error;
    sigma_factor_log_ = std::exp(-dt / 30.0) * sigma_factor_log_ +
                        0.25 * std::sqrt(1.0 - std::exp(-2.0 * dt / 30.0)) * Normal();
    const double f = std::exp(sigma_factor_log_);
    out.sigma_horizontal_m = sg.x() * f;
    out.sigma_vertical_m = sg.z() * f;
    sigma_at_outage_ = out.sigma_horizontal_m;
  } else {
    error_ += drift_v_ * dt + drift_a_ * (t - t_outage_start_) * dt;
    const double tau = t - t_outage_start_;
    out.sigma_horizontal_m = sigma_at_outage_ + options_.ins_velocity_drift_sigma_mps * tau +
                             0.5 * options_.ins_accel_drift_sigma_mps2 * tau * tau;
    out.sigma_vertical_m = 1.5 * out.sigma_horizontal_m;
  }
  // Satellites follow the state (slowly varying).
  const int lo = state_ == GnssState::kRtkFixed   ? 8
                 : state_ == GnssState::kRtkFloat ? 6
                 : state_ == GnssState::kSps      ? 4
                                                  : 0;
  const int hi = state_ == GnssState::kNone ? 3 : lo + 4;
  if (Uniform() < dt / 3.0) sats_ += Uniform() < 0.5 ? -1 : 1;
  sats_ = std::clamp(sats_, lo, hi);
  out.state = state_;
  out.error_enu_m = error_;
  out.num_satellites = sats_;
  return out;
}

}  // namespace slam_mms::sim
