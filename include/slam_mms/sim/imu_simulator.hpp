#pragma once
// ImuSimulator: a strapdown IMU sampled from the reference trajectory's analytic derivatives:
// specific force f = R^T (a - g) (gravity included, as KITTI/OXTS report it) and angular rate in
// the body frame, plus a turn-on bias, a first-order Gauss-Markov bias drift and white noise:
//   measurement = truth + b_on + b_gm(t) + n,   n ~ N(0, density^2 * rate),
//   b_gm(k+1) = exp(-dt/tau) b_gm(k) + sigma_instability sqrt(1 - exp(-2 dt/tau)) w.
// Earth rotation is not modelled (the world is a non-rotating local ENU frame with constant
// gravity).
//
// Thread safety: none (stateful noise); one simulator per stream.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>

#include "slam_mms/core/imu_noise.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/sim/reference_trajectory.hpp"

namespace slam_mms::sim {

enum class ImuGrade { kPerfect, kConsumer, kTactical, kNavigation };
const char* ImuGradeName(ImuGrade grade);
/// "perfect" | "consumer" | "tactical" | "navigation".
[[nodiscard]] StatusOr<ImuGrade> ParseImuGrade(const std::string& name);

class ImuSimulator {
 public:
  struct Options {
    double rate_hz = 100.0;
    double gravity_mps2 = 9.81;
    double gyro_noise_density = 5.8e-5;     ///< [rad/s/sqrt(Hz)] (0.2 deg/sqrt(h))
    double gyro_bias_instability = 9.7e-6;  ///< [rad/s] (2 deg/h)
    double gyro_bias_tau_s = 300.0;
    double gyro_turn_on_bias_sigma = 2.4e-5;  ///< [rad/s] (5 deg/h)
    double accel_noise_density = 5.0e-4;      ///< [m/s^2/sqrt(Hz)] (50 ug/sqrt(Hz))
    double accel_bias_instability = 1.0e-4;   ///< [m/s^2] (10 ug)
    double accel_bias_tau_s = 300.0;
    double accel_turn_on_bias_sigma = 5.0e-4;  ///< [m/s^2] (50 ug)

    /// The presets (default-constructed Options are the tactical, RT3003-like grade).
    static Options ForGrade(ImuGrade grade);
    [[nodiscard]] Status Validate() const;
    /// This IMU's datasheet (what DriveSimulator writes to imu_noise.yaml); empty for an IMU
    /// without white noise or bias drift (the perfect grade), which no datasheet describes.
    std::optional<ImuNoiseSpec> NoiseSpec() const;
  };

  ImuSimulator(const Options& options, uint64_t seed);

  /// The measurement for `state` (call in time order, once per sample period).
  ImuSample Measure(const BodyState& state, Timestamp stamp);
  /// The noise-free measurement.
  static ImuSample TrueMeasurement(const BodyState& state, Timestamp stamp, double gravity_mps2);

  /// The total biases used by the last Measure call (ground truth).
  const Eigen::Vector3d& gyro_bias() const { return gyro_bias_total_; }
  const Eigen::Vector3d& accel_bias() const { return accel_bias_total_; }
  const Options& options() const { return options_; }

 private:
  Options options_;
  uint64_t rng_state_;
  double NextNormal();
  Eigen::Vector3d NextNormal3() { return {NextNormal(), NextNormal(), NextNormal()}; }
  Eigen::Vector3d gyro_on_, accel_on_, gyro_gm_, accel_gm_;
  Eigen::Vector3d gyro_bias_total_ = Eigen::Vector3d::Zero(),
                  accel_bias_total_ = Eigen::Vector3d::Zero();
  bool has_spare_ = false;
  double spare_ = 0.0;
};

}  // namespace slam_mms::sim
