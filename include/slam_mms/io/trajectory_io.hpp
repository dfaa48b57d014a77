#pragma once
// Trajectory files: TUM, KITTI and CSV with covariance. Poses are T_world_body of
// core/trajectory.hpp's Trajectory.
//
//   TUM:   one line per pose "t tx ty tz qx qy qz qw"; t in seconds written exactly to the
//          nanosecond ("1317042651.106324297"), read exactly (no double round trip of t).
//          Lines starting with '#' and blank lines are skipped on reading.
//   KITTI: one line per pose, the 12 numbers of the 3x4 [R | t] row-major; no time.
//   CSV:   header line, then "stamp_ns,tx,ty,tz,qx,qy,qz,qw,c00,c01,...,c55": the 6x6 covariance
//          row-major (rotation first [omega, v], right perturbation), empty fields where the pose
//          has none.
// Numbers are written with %.17g (lossless); quaternions are normalised on reading.
// Errors name the file, line and field.
//
// Thread safety: pure functions; distinct files may be written concurrently.

#include <Eigen/Geometry>
#include <filesystem>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/core/trajectory.hpp"

namespace slam_mms {

[[nodiscard]] Status WriteTrajectoryTum(const Trajectory& trajectory,
                                        const std::filesystem::path& file);
[[nodiscard]] StatusOr<Trajectory> ReadTrajectoryTum(const std::filesystem::path& file);

[[nodiscard]] Status WriteTrajectoryKitti(const Trajectory& trajectory,
                                          const std::filesystem::path& file);
/// Reads the poses of a KITTI file (no stamps).
[[nodiscard]] StatusOr<std::vector<Eigen::Isometry3d>> ReadPosesKitti(
    const std::filesystem::path& file);
/// Reads a KITTI file and attaches `stamps` (one per line, strictly increasing); kInvalidArgument
/// when the counts differ.
[[nodiscard]] StatusOr<Trajectory> ReadTrajectoryKitti(const std::filesystem::path& file,
                                                       const std::vector<Timestamp>& stamps);

[[nodiscard]] Status WriteTrajectoryCsv(const Trajectory& trajectory,
                                        const std::filesystem::path& file);
[[nodiscard]] StatusOr<Trajectory> ReadTrajectoryCsv(const std::filesystem::path& file);

/// Parses decimal seconds ("1317042651.106324297", up to 9 fraction digits, optional sign) exactly
/// to a Timestamp; kInvalidArgument otherwise.
[[nodiscard]] StatusOr<Timestamp> ParseSecondsExact(const std::string& text);
/// Formats a Timestamp as decimal seconds with 9 fraction digits (exact).
std::string FormatSecondsExact(Timestamp stamp);

}  // namespace slam_mms
