#include "slam_mms/sim/imu_simulator.hpp"

#include <cmath>
#include <sstream>

#include "sim/random.hpp"

namespace slam_mms::sim {

const char* ImuGradeName(ImuGrade grade) {
  switch (grade) {
    case ImuGrade::kPerfect: return "perfect";
    case ImuGrade::kConsumer: return "consumer";
    case ImuGrade::kTactical: return "tactical";
    case ImuGrade::kNavigation: return "navigation";
  }
  return "tactical";
}

StatusOr<ImuGrade> ParseImuGrade(const std::string& name) {
  for (ImuGrade g :
       {ImuGrade::kPerfect, ImuGrade::kConsumer, ImuGrade::kTactical, ImuGrade::kNavigation}) {
    if (name == ImuGradeName(g)) return g;
  }
  return InvalidArgumentError("unknown IMU grade '" + name +
                              "'; use perfect, consumer, tactical or navigation");
}

ImuSimulator::Options ImuSimulator::Options::ForGrade(ImuGrade grade) {
  Options o;
  const double deg = M_PI / 180.0;
  switch (grade) {
    case ImuGrade::kPerfect:
      o.gyro_noise_density = o.gyro_bias_instability = o.gyro_turn_on_bias_sigma = 0.0;
      o.accel_noise_density = o.accel_bias_instability = o.accel_turn_on_bias_sigma = 0.0;
      break;
    case ImuGrade::kConsumer:  // MPU-6000 class (SENSORS_AND_METRICS.md)
      o.gyro_noise_density = 0.3 * deg / 60.0;
      o.gyro_bias_instability = 4.6 * deg / 3600.0;
      o.gyro_bias_tau_s = 500.0;
      o.gyro_turn_on_bias_sigma = 0.1 * deg;
      o.accel_noise_density = 2.4e-3;
      o.accel_bias_instability = 36e-6 * 9.81;
      o.accel_bias_tau_s = 800.0;
      o.accel_turn_on_bias_sigma = 0.02;
      break;
    case ImuGrade::kTactical: break;  // the defaults
    case ImuGrade::kNavigation:       // HG9900 class
      o.gyro_noise_density = 0.002 * deg / 60.0;
      o.gyro_bias_instability = 0.1 * deg / 3600.0;
      o.gyro_bias_tau_s = 3600.0;
      o.gyro_turn_on_bias_sigma = 0.2 * deg / 3600.0;
      o.accel_noise_density = 2.5e-5;
      o.accel_bias_instability = 3.6e-6;
      o.accel_bias_tau_s = 3600.0;
      o.accel_turn_on_bias_sigma = 1e-5;
      break;
  }
  return o;
}

Status ImuSimulator::Options::Validate() const {
  auto fail = [](const char* name, double v, const char* rule) {
    std::ostringstream s;
    s << "ImuSimulator::Options::" << name << " = " << v << "; " << rule;
    return InvalidArgumentError(s.str());
  };
  if (!(rate_hz > 0.0)) return fail("rate_hz", rate_hz, "must be > 0");
  if (!(gravity_mps2 > 0.0)) return fail("gravity_mps2", gravity_mps2, "must be > 0");
  for (auto [name, v] : {std::pair<const char*, double>{"gyro_noise_density", gyro_noise_density},
                         {"gyro_bias_instability", gyro_bias_instability},
                         {"gyro_turn_on_bias_sigma", gyro_turn_on_bias_sigma},
                         {"accel_noise_density", accel_noise_density},
                         {"accel_bias_instability", accel_bias_instability},
                         {"accel_turn_on_bias_sigma", accel_turn_on_bias_sigma}}) {
    if (!(v >= 0.0)) return fail(name, v, "must be >= 0");
  }
  if (!(gyro_bias_tau_s > 0.0)) return fail("gyro_bias_tau_s", gyro_bias_tau_s, "must be > 0");
  if (!(accel_bias_tau_s > 0.0)) return fail("accel_bias_tau_s", accel_bias_tau_s, "must be > 0");
  return OkStatus();
}

std::optional<ImuNoiseSpec> ImuSimulator::Options::NoiseSpec() const {
  ImuNoiseSpec spec;
  spec.model = "slam_mms_sim simulated IMU (first-order Gauss-Markov bias drift)";
  spec.gyro_noise_density = gyro_noise_density;
  spec.accel_noise_density = accel_noise_density;
  spec.gyro_bias_instability = gyro_bias_instability;
  spec.gyro_bias_correlation_time_s = gyro_bias_tau_s;
  spec.accel_bias_instability = accel_bias_instability;
  spec.accel_bias_correlation_time_s = accel_bias_tau_s;
  spec.gyro_turn_on_bias_sigma = gyro_turn_on_bias_sigma;
  spec.accel_turn_on_bias_sigma = accel_turn_on_bias_sigma;
  if (!spec.Validate().ok()) return std::nullopt;
  return spec;
}

ImuSimulator::ImuSimulator(const Options& options, uint64_t seed)
    : options_(options), rng_state_(MixSeed(seed, 0x1A0)) {
  gyro_on_ = options_.gyro_turn_on_bias_sigma * NextNormal3();
  accel_on_ = options_.accel_turn_on_bias_sigma * NextNormal3();
  gyro_gm_ = options_.gyro_bias_instability * NextNormal3();  // stationary start
  accel_gm_ = options_.accel_bias_instability * NextNormal3();
}

double ImuSimulator::NextNormal() {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  auto uniform = [this]() {
    rng_state_ = MixSeed(rng_state_, 0x77);
    return (static_cast<double>(rng_state_ >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  };
  const double u1 = uniform(), u2 = uniform();
  const double r = std::sqrt(-2.0 * std::log(u1));
  spare_ = r * std::sin(2.0 * M_PI * u2);
  has_spare_ = true;
  return r * std::cos(2.0 * M_PI * u2);
}

ImuSample ImuSimulator::TrueMeasurement(const BodyState& state, Timestamp stamp,
                                        double gravity_mps2) {
  ImuSample s;
  s.stamp = stamp;
  s.accel_mps2 = ReferenceTrajectory::SpecificForceBody(state, gravity_mps2);
  s.gyro_radps = state.omega_body_radps;
  return s;
}

ImuSample ImuSimulator::Measure(const BodyState& state, Timestamp stamp) {
  const double dt = 1.0 / options_.rate_hz;
  const double eg = std::exp(-dt / options_.gyro_bias_tau_s),
               ea = std::exp(-dt / options_.accel_bias_tau_s);
  gyro_gm_ =
      eg * gyro_gm_ + options_.gyro_bias_instability * std::sqrt(1.0 - eg * eg) * NextNormal3();
  accel_gm_ =
      ea * accel_gm_ + options_.accel_bias_instability * std::sqrt(1.0 - ea * ea) * NextNormal3();
  gyro_bias_total_ = gyro_on_ + gyro_gm_;
  accel_bias_total_ = accel_on_ + accel_gm_;
  ImuSample s = TrueMeasurement(state, stamp, options_.gravity_mps2);
  const double sq = std::sqrt(options_.rate_hz);
  s.gyro_radps += gyro_bias_total_ + options_.gyro_noise_density * sq * NextNormal3();
  s.accel_mps2 += accel_bias_total_ + options_.accel_noise_density * sq * NextNormal3();
  return s;
}

}  // namespace slam_mms::sim
