#pragma once
// ImuNoiseSpec's YAML file, `imu_noise.yaml` in a drive folder or a KITTI raw drive folder
// (optional in both; slam_mms_sim writes it for the IMU it simulates; slam_mms_run --imu-noise
// FILE gives one for any input):
//
//   model: OXTS RT3003                          # optional, free text
//   angle_random_walk_deg_per_sqrt_h: 0.2       # or gyro_noise_density [rad/s/sqrt(Hz)]
//   velocity_random_walk_mps_per_sqrt_h: 0.03   # or accel_noise_density [m/s^2/sqrt(Hz)]
//   gyro_bias_instability_deg_per_h: 2          # or gyro_bias_instability [rad/s]
//   gyro_bias_correlation_time_s: 300
//   accel_bias_instability_ug: 10               # or accel_bias_instability [m/s^2]
//   accel_bias_correlation_time_s: 300
//   gyro_bias_repeatability_deg_per_h: 5        # optional; or gyro_turn_on_bias_sigma [rad/s]
//   accel_bias_repeatability_ug: 50             # optional; or accel_turn_on_bias_sigma [m/s^2]
//
// Each quantity by exactly one of its two keys: the datasheet units (1 ug = 9.80665e-6 m/s^2) or
// SI. The writer writes SI with %.17g (a written file reads back bit for bit) and the datasheet
// values as comments. Errors (kDataLoss; kNotFound for a missing file) name "<file>:<line>" and
// the key; a value out of range names the ImuNoiseSpec field (Validate). Unknown keys are
// logged at kInfo and ignored. Read with yaml-cpp.
//
// Thread safety: pure functions; safe from any thread.

#include <filesystem>
#include <string>

#include "slam_mms/core/imu_noise.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms {

/// The file name readers look for in a drive folder.
inline constexpr const char* kImuNoiseFileName = "imu_noise.yaml";

[[nodiscard]] StatusOr<ImuNoiseSpec> ReadImuNoiseYaml(const std::filesystem::path& file);
/// Parses the text of such a file; `file` names it in messages.
[[nodiscard]] StatusOr<ImuNoiseSpec> ParseImuNoiseYaml(const std::string& text,
                                                       const std::string& file);
std::string FormatImuNoiseYaml(const ImuNoiseSpec& spec);
/// kUnavailable when `file` cannot be written.
[[nodiscard]] Status WriteImuNoiseYaml(const ImuNoiseSpec& spec, const std::filesystem::path& file);

}  // namespace slam_mms
