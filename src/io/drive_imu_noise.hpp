#pragma once
// Private to the io module: the drive readers' optional imu_noise.yaml (io/imu_noise_yaml.hpp).

#include <filesystem>

#include "slam_mms/core/status.hpp"
#include "slam_mms/io/drive_reader.hpp"

namespace slam_mms::io_internal {

/// Reads `dir`/imu_noise.yaml into streams->imu_noise and imu_noise_source where the file exists;
/// its errors name the file (nothing is set then).
[[nodiscard]] Status ReadDriveImuNoise(const std::filesystem::path& dir, DriveStreams* streams);

}  // namespace slam_mms::io_internal
