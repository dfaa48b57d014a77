#pragma once
// A drive's calibration (DriveExtrinsics) as a KITTI calib_imu_to_velo.txt, and ReadExtrinsicsFile,
// which reads either that or extrinsics.yaml (slam_mms_run --extrinsics):
//
//   calib_time: slam_mms
//   R: r00 r01 r02 r10 r11 r12 r20 r21 r22      # rotation of T_lidar_body, row-major
//   T: tx ty tz                                 # translation of T_lidar_body [m]
//   lidar_time_offset_s: t                      # optional, only written when nonzero
//
// KITTI's file maps IMU (body) points into the Velodyne frame: R, T are those of
// T_lidar_body = T_body_lidar.inverse(). The writer prints every number with %.17g; the reader
// projects R onto SO(3) (as ReadKittiRigidCalibration does for KITTI's 7-digit files), so a written
// file reads back within ~1e-15. Other KITTI tools parse lines as "key: floats" and skip unknown
// keys, so the extra lidar_time_offset_s line does not disturb them. A calib file carries no
// antenna lever arm: t_body_antenna_m reads back empty.
//
// Errors (kDataLoss; kNotFound for a missing file) name "<file>:<line>" and the key.
// Thread safety: pure functions; safe from any thread.

#include <filesystem>
#include <string>

#include "slam_mms/core/status.hpp"
#include "slam_mms/io/extrinsics_yaml.hpp"

namespace slam_mms {

/// The text of calib_imu_to_velo.txt for `extrinsics` (see the file comment); `calib_time` is
/// written after "calib_time: ". extrinsics.t_body_antenna_m is not written.
std::string FormatKittiImuToVelo(const DriveExtrinsics& extrinsics, const std::string& calib_time);

/// Writes FormatKittiImuToVelo to `file` (kUnavailable naming the file when it cannot be written).
[[nodiscard]] Status WriteKittiImuToVelo(const DriveExtrinsics& extrinsics,
                                         const std::filesystem::path& file,
                                         const std::string& calib_time = "slam_mms");

/// Reads a calib_imu_to_velo.txt: T_body_lidar = [R T].inverse(), lidar_time_offset_s (0 when
/// absent), no antenna. Errors as ReadKittiRigidCalibration, and for a lidar_time_offset_s that is
/// not one finite number or is given twice.
[[nodiscard]] StatusOr<DriveExtrinsics> ReadKittiImuToVelo(const std::filesystem::path& file);

/// An extrinsics file of either format, by extension: ".yaml" / ".yml" -> ReadExtrinsicsYaml,
/// anything else -> ReadKittiImuToVelo.
[[nodiscard]] StatusOr<DriveExtrinsics> ReadExtrinsicsFile(const std::filesystem::path& file);

}  // namespace slam_mms
