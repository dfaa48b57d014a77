#include "slam_mms/core/imu_noise.hpp"

#include <cmath>
#include <utility>

#include "core/option_error.hpp"

namespace slam_mms {

Status ImuNoiseSpec::Validate() const {
  using internal::OptionError;
  constexpr const char* kOwner = "ImuNoiseSpec";
  for (auto [name, v] : {std::pair<const char*, double>{"gyro_noise_density", gyro_noise_density},
                         {"accel_noise_density", accel_noise_density},
                         {"gyro_bias_instability", gyro_bias_instability},
                         {"accel_bias_instability", accel_bias_instability}}) {
    if (!(std::isfinite(v) && v > 0.0)) return OptionError(kOwner, name, v, "must be > 0");
  }
  for (auto [name, v] :
       {std::pair<const char*, double>{"gyro_turn_on_bias_sigma", gyro_turn_on_bias_sigma},
        {"accel_turn_on_bias_sigma", accel_turn_on_bias_sigma}}) {
    if (!(std::isfinite(v) && v >= 0.0)) return OptionError(kOwner, name, v, "must be >= 0");
  }
  for (auto [name, v] : {std::pair<const char*, double>{"gyro_bias_correlation_time_s",
                                                        gyro_bias_correlation_time_s},
                         {"accel_bias_correlation_time_s", accel_bias_correlation_time_s}}) {
    if (!(std::isfinite(v) && v > 0.0)) return OptionError(kOwner, name, v, "must be > 0 [s]");
  }
  return OkStatus();
}

double ImuNoiseSpec::GyroBiasRandomWalk() const {
  return gyro_bias_instability * std::sqrt(2.0 / gyro_bias_correlation_time_s);
}

double ImuNoiseSpec::AccelBiasRandomWalk() const {
  return accel_bias_instability * std::sqrt(2.0 / accel_bias_correlation_time_s);
}

double ImuNoiseSpec::GyroBiasInitialSigma() const {
  return std::hypot(gyro_turn_on_bias_sigma, gyro_bias_instability);
}

double ImuNoiseSpec::AccelBiasInitialSigma() const {
  return std::hypot(accel_turn_on_bias_sigma, accel_bias_instability);
}

}  // namespace slam_mms
