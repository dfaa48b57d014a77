#include "slam_mms/io/imu_noise_yaml.hpp"

#include <yaml-cpp/yaml.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <system_error>

#include "io/drive_imu_noise.hpp"
#include "io/file_util.hpp"
#include "io/yaml_util.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kMicroG = 9.80665e-6;  // [m/s^2]

// One quantity: its SI key, its datasheet key and the factor datasheet -> SI.
struct Quantity {
  const char* si_key;
  const char* datasheet_key;
  double to_si;
  double ImuNoiseSpec::*field;
  bool required;
};

const std::array<Quantity, 8>& Quantities() {
  static const std::array<Quantity, 8> kQ = {{
      {"gyro_noise_density", "angle_random_walk_deg_per_sqrt_h", kDeg / 60.0,
       &ImuNoiseSpec::gyro_noise_density, true},
      {"accel_noise_density", "velocity_random_walk_mps_per_sqrt_h", 1.0 / 60.0,
       &ImuNoiseSpec::accel_noise_density, true},
      {"gyro_bias_instability", "gyro_bias_instability_deg_per_h", kDeg / 3600.0,
       &ImuNoiseSpec::gyro_bias_instability, true},
      {"gyro_bias_correlation_time_s", nullptr, 1.0, &ImuNoiseSpec::gyro_bias_correlation_time_s,
       true},
      {"accel_bias_instability", "accel_bias_instability_ug", kMicroG,
       &ImuNoiseSpec::accel_bias_instability, true},
      {"accel_bias_correlation_time_s", nullptr, 1.0, &ImuNoiseSpec::accel_bias_correlation_time_s,
       true},
      {"gyro_turn_on_bias_sigma", "gyro_bias_repeatability_deg_per_h", kDeg / 3600.0,
       &ImuNoiseSpec::gyro_turn_on_bias_sigma, false},
      {"accel_turn_on_bias_sigma", "accel_bias_repeatability_ug", kMicroG,
       &ImuNoiseSpec::accel_turn_on_bias_sigma, false},
  }};
  return kQ;
}

using io_internal::YamlWhere;

}  // namespace

StatusOr<ImuNoiseSpec> ParseImuNoiseYaml(const std::string& text, const std::string& file) {
  try {
    SLAM_MMS_ASSIGN_OR_RETURN(const YAML::Node root, io_internal::YamlOneDocument(text, file));
    if (!root.IsMap()) {
      return DataLossError(file +
                           ": an IMU noise file must be a YAML map (see imu_noise_yaml.hpp)");
    }
    ImuNoiseSpec spec;
    std::array<std::string, 8> seen;  // the key that set each quantity
    for (const auto& kv : root) {
      if (!kv.first.IsScalar()) {
        return DataLossError(YamlWhere(file, kv.first) + ": keys must be plain names");
      }
      const std::string key = kv.first.Scalar();
      const YAML::Node& v = kv.second;
      if (key == "model") {
        if (!v.IsScalar()) return DataLossError(YamlWhere(file, v) + ": model must be a text");
        spec.model = v.Scalar();
        continue;
      }
      bool known = false;
      for (size_t q = 0; q < Quantities().size(); ++q) {
        const Quantity& Q = Quantities()[q];
        const bool si = key == Q.si_key;
        if (!si && (Q.datasheet_key == nullptr || key != Q.datasheet_key)) continue;
        known = true;
        if (!seen[q].empty()) {
          return DataLossError(YamlWhere(file, kv.first) + ": " + key +
                               " gives the same quantity as " + seen[q] + "; give one of them");
        }
        double d = 0.0;
        SLAM_MMS_RETURN_IF_ERROR(
            io_internal::YamlFiniteNumber(v, YamlWhere(file, v) + ": " + key, "", &d));
        spec.*Q.field = si ? d : d * Q.to_si;
        seen[q] = key;
      }
      if (!known) {
        SLAM_MMS_LOG(kInfo) << YamlWhere(file, kv.first) << ": key '" << key << "' ignored";
      }
    }
    for (size_t q = 0; q < Quantities().size(); ++q) {
      const Quantity& Q = Quantities()[q];
      if (Q.required && seen[q].empty()) {
        return DataLossError(file + ": key " +
                             (Q.datasheet_key
                                  ? std::string(Q.datasheet_key) + " (or " + Q.si_key + ")"
                                  : std::string(Q.si_key)) +
                             " missing");
      }
    }
    const Status valid = spec.Validate();
    if (!valid.ok()) return DataLossError(file + ": " + valid.message());
    return spec;
  } catch (const YAML::Exception& e) {
    return DataLossError(file + ":" + std::to_string(e.mark.line + 1) + ": YAML error: " + e.msg);
  } catch (const std::exception& e) {
    return DataLossError(file + ": YAML error: " + e.what());
  }
}

StatusOr<ImuNoiseSpec> ReadImuNoiseYaml(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) {
    return NotFoundError("IMU noise file " + file.string() + " not found");
  }
  SLAM_MMS_ASSIGN_OR_RETURN(const std::string text, io_internal::ReadFileBytes(file));
  return ParseImuNoiseYaml(text, file.string());
}

std::string FormatImuNoiseYaml(const ImuNoiseSpec& spec) {
  using io_internal::FormatDouble;
  std::string s =
      "# slam_mms IMU noise (datasheet values, SI; io/imu_noise_yaml.hpp). In datasheet units:\n";
  for (const Quantity& Q : Quantities()) {
    if (Q.datasheet_key == nullptr) continue;
    char line[160];
    std::snprintf(line, sizeof line, "#   %s: %.6g\n", Q.datasheet_key, spec.*Q.field / Q.to_si);
    s += line;
  }
  if (!spec.model.empty()) {
    YAML::Emitter e;  // quotes the text where YAML needs it
    e << YAML::DoubleQuoted << spec.model;
    s += std::string("model: ") + e.c_str() + "\n";
  }
  for (const Quantity& Q : Quantities()) {
    if (!Q.required && spec.*Q.field == 0.0) continue;
    s += std::string(Q.si_key) + ": " + FormatDouble(spec.*Q.field) + "\n";
  }
  return s;
}

Status io_internal::ReadDriveImuNoise(const std::filesystem::path& dir, DriveStreams* streams) {
  const std::filesystem::path file = dir / kImuNoiseFileName;
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) return OkStatus();
  SLAM_MMS_ASSIGN_OR_RETURN(streams->imu_noise, ReadImuNoiseYaml(file));
  streams->imu_noise_source = file.string();
  return OkStatus();
}

Status WriteImuNoiseYaml(const ImuNoiseSpec& spec, const std::filesystem::path& file) {
  return io_internal::WriteFileBytes(file, FormatImuNoiseYaml(spec));
}

}  // namespace slam_mms
