#include "slam_mms/io/kitti_calibration.hpp"

#include <algorithm>
#include <cctype>
#include <optional>

#include "io/file_util.hpp"
#include "io/parsers.hpp"

namespace slam_mms {
namespace {

constexpr const char* kTimeOffsetKey = "lidar_time_offset_s";

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

}  // namespace

std::string FormatKittiImuToVelo(const DriveExtrinsics& e, const std::string& calib_time) {
  using io_internal::FormatDouble;
  // KITTI's file maps body (IMU) points into the lidar frame.
  const Eigen::Isometry3d T_lidar_body = e.T_body_lidar.inverse();
  const Eigen::Matrix3d R = T_lidar_body.linear();
  const Eigen::Vector3d t = T_lidar_body.translation();
  std::string s = "calib_time: " + calib_time + "\nR:";
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) s += " " + FormatDouble(R(r, c));
  }
  s += "\nT:";
  for (int k = 0; k < 3; ++k) s += " " + FormatDouble(t(k));
  s += "\n";
  if (e.lidar_time_offset_s != 0.0) {
    s += std::string(kTimeOffsetKey) + ": " + FormatDouble(e.lidar_time_offset_s) + "\n";
  }
  return s;
}

Status WriteKittiImuToVelo(const DriveExtrinsics& extrinsics, const std::filesystem::path& file,
                           const std::string& calib_time) {
  return io_internal::WriteFileBytes(file, FormatKittiImuToVelo(extrinsics, calib_time));
}

StatusOr<DriveExtrinsics> io_internal::ParseKittiImuToVeloLines(
    const std::vector<std::string>& lines, const std::string& file) {
  SLAM_MMS_ASSIGN_OR_RETURN(const Eigen::Isometry3d T_lidar_body,
                            ParseKittiRigidCalibrationLines(lines, file));
  DriveExtrinsics out;
  out.T_body_lidar = T_lidar_body.inverse();
  std::optional<size_t> offset_line;
  for (size_t l = 0; l < lines.size(); ++l) {
    const std::string& line = lines[l];
    const size_t colon = line.find(':');
    if (colon == std::string::npos || line.compare(0, colon, kTimeOffsetKey) != 0) continue;
    const std::string where = file + ":" + std::to_string(l + 1) + ": key " + kTimeOffsetKey;
    if (offset_line) {
      return DataLossError(where + " given twice (first on line " +
                           std::to_string(*offset_line + 1) + ")");
    }
    offset_line = l;
    const std::vector<std::string> tokens = SplitWhitespace(line.substr(colon + 1));
    if (tokens.size() != 1 || !ParseDouble(tokens[0], &out.lidar_time_offset_s)) {
      std::string value;
      for (const std::string& t : tokens) value += (value.empty() ? "" : " ") + t;
      return DataLossError(where + " '" + value + "' is not one finite number [s]");
    }
  }
  return out;
}

StatusOr<DriveExtrinsics> ReadKittiImuToVelo(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) {
    return NotFoundError("calibration file " + file.string() + " not found");
  }
  SLAM_MMS_ASSIGN_OR_RETURN(const std::vector<std::string> lines, io_internal::ReadLines(file));
  return io_internal::ParseKittiImuToVeloLines(lines, file.string());
}

StatusOr<DriveExtrinsics> ReadExtrinsicsFile(const std::filesystem::path& file) {
  const std::string ext = Lower(file.extension().string());
  if (ext == ".yaml" || ext == ".yml") return ReadExtrinsicsYaml(file);
  return ReadKittiImuToVelo(file);
}

}  // namespace slam_mms
