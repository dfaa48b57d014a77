#pragma once
// ImuNoiseSpec: the noise of an IMU as its datasheet states it, the way post-processing software
// asks for it when the IMU model is chosen (white noise, bias instability with its correlation
// time, bias repeatability). A drive's reader gives it where the input states it
// (DriveStreams::imu_noise: a drive folder's or KITTI raw drive's imu_noise.yaml, which
// slam_mms_sim writes from the IMU it simulates); InsFilter::Options::SetImuNoise and
// ImuPreintegration::Options::SetImuNoise turn it into their noise models. The file:
// io/imu_noise_yaml.hpp.
//
// All fields SI. A first-order Gauss-Markov bias of stationary sigma s and correlation time tau
// is modelled by the estimators as a random walk of density s * sqrt(2 / tau) (the same growth
// over one correlation time).
//
// Thread safety: a value type.

#include <string>

#include "slam_mms/core/status.hpp"

namespace slam_mms {

struct ImuNoiseSpec {
  std::string model;                   ///< Free text ("OXTS RT3003", "slam_mms_sim tactical").
  double gyro_noise_density = 0.0;     ///< Angle random walk [rad/s/sqrt(Hz)], > 0.
  double accel_noise_density = 0.0;    ///< Velocity random walk [m/s^2/sqrt(Hz)], > 0.
  double gyro_bias_instability = 0.0;  ///< Stationary sigma of the in-run bias [rad/s], > 0.
  double gyro_bias_correlation_time_s = 0.0;   ///< > 0 [s].
  double accel_bias_instability = 0.0;         ///< [m/s^2], > 0.
  double accel_bias_correlation_time_s = 0.0;  ///< > 0 [s].
  /// Turn-on bias (repeatability) 1-sigma [rad/s], [m/s^2]; 0 = not stated.
  double gyro_turn_on_bias_sigma = 0.0;
  double accel_turn_on_bias_sigma = 0.0;

  /// InvalidArgument naming "ImuNoiseSpec::<field>" for a value out of range (or not finite).
  [[nodiscard]] Status Validate() const;
  /// Random-walk densities of the biases: instability * sqrt(2 / correlation time)
  /// [rad/s^2/sqrt(Hz)], [m/s^3/sqrt(Hz)].
  double GyroBiasRandomWalk() const;
  double AccelBiasRandomWalk() const;
  /// 1-sigma of the bias at the start of a run: sqrt(turn-on^2 + instability^2).
  double GyroBiasInitialSigma() const;
  double AccelBiasInitialSigma() const;
};

}  // namespace slam_mms
