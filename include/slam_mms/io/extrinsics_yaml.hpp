#pragma once
// DriveExtrinsics and its YAML file (a drive folder's extrinsics.yaml, slam_mms_run --extrinsics):
//
//   # p_body = T_body_lidar * p_lidar
//   T_body_lidar: [r00, r01, r02, tx, r10, r11, r12, ty, r20, r21, r22, tz, 0, 0, 0, 1]
//   t_body_antenna_m: [x, y, z]      # optional: GNSS antenna lever arm in the body frame
//   lidar_time_offset_s: t           # optional (default 0): see DriveExtrinsics
//   imu_frame_is_vehicle_frame: true # optional: see DriveExtrinsics
//
// or, for T_body_lidar, `{xyz: [x, y, z], rpy_deg: [roll, pitch, yaw]}` with
// R = Rz(yaw) Ry(pitch) Rx(roll). The 4x4 matrix is row-major; its rotation must be orthonormal
// within 1e-6 (max |R^T R - I|) with det +1 and its last row exactly 0 0 0 1; it is used as given
// (not re-orthonormalised), so a written file reads back bit for bit. Unknown keys are ignored
// (logged at kInfo). Errors (kDataLoss; kNotFound for a missing file) name "<file>:<line>" and the
// key ("T_body_lidar has 15 numbers, expected 16").
//
// Read with yaml-cpp; the writer prints numbers with %.17g (lossless).
// Thread safety: pure functions; safe from any thread.

#include <Eigen/Geometry>
#include <filesystem>
#include <optional>
#include <string>

#include "slam_mms/core/status.hpp"

namespace slam_mms {

/// The calibration of a drive: where the LiDAR and the GNSS antenna sit in the body (IMU) frame.
struct DriveExtrinsics {
  /// Maps points of the lidar frame into the body frame.
  Eigen::Isometry3d T_body_lidar = Eigen::Isometry3d::Identity();
  /// GNSS antenna position in the body frame [m]; empty = not given.
  std::optional<Eigen::Vector3d> t_body_antenna_m;
  /// The LiDAR clock's offset [s]: a LiDAR stamp s is the time s + lidar_time_offset_s on the
  /// IMU/GNSS clock.
  double lidar_time_offset_s = 0.0;
  /// Whether the body (IMU) frame is the vehicle's: x forward, y left, z up, as a KITTI OXTS is
  /// mounted (DriveStreams::imu_frame_is_vehicle_frame; where true, RunDrive's POS may hold the
  /// vehicle's non-holonomic constraint, ApplyInputModels). Empty: not stated (a folder reader
  /// then takes false; an override keeps the reader's own).
  std::optional<bool> imu_frame_is_vehicle_frame;
};

/// Reads an extrinsics file (see the file comment).
[[nodiscard]] StatusOr<DriveExtrinsics> ReadExtrinsicsYaml(const std::filesystem::path& file);

/// Parses the text of an extrinsics file; `file` names it in messages.
[[nodiscard]] StatusOr<DriveExtrinsics> ParseExtrinsicsYaml(const std::string& text,
                                                            const std::string& file);

/// The text WriteExtrinsicsYaml writes (T_body_lidar as 16 numbers; lidar_time_offset_s only when
/// nonzero; imu_frame_is_vehicle_frame only when stated).
std::string FormatExtrinsicsYaml(const DriveExtrinsics& extrinsics);

/// Writes `extrinsics` to `file` (kUnavailable when it cannot be written).
[[nodiscard]] Status WriteExtrinsicsYaml(const DriveExtrinsics& extrinsics,
                                         const std::filesystem::path& file);

}  // namespace slam_mms
