#pragma once
// The output side of slam_mms_convert: a DriveReader written as a plain drive folder, a ROS 1 bag
// or a KITTI raw drive.

#include <filesystem>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/io/drive_reader.hpp"

namespace slam_mms::app {

struct WriteSettings {
  std::string scan_format = "pcd_binary";  ///< --to folder: see ScanFormatNames().
  std::string gnss_format = "csv";         ///< --to folder: csv | nmea.
  /// --to folder: a float32 `t` field per point. Without it the folder reader derives the times
  /// from the azimuth over scans.csv's [start, end], exactly as KITTI raw.
  bool folder_point_time = false;
  /// --to rosbag: no `time` field. PointCloud2 has no end stamp, so the reader would take the
  /// median scan period for the azimuth time: kept by default.
  bool bag_no_point_time = false;
};

/// The accepted --scan-format values.
std::vector<std::string> ScanFormatNames();

/// Writes `reader` as `to` ("folder", "rosbag", "kitti-raw") at `out`.
[[nodiscard]] Status WriteDrive(const DriveReader& reader, const std::string& to,
                                const std::filesystem::path& out, const WriteSettings& settings);

}  // namespace slam_mms::app
