#include "slam_mms_convert/writers.hpp"

#include <cstdio>

#include "slam_mms/io/drive_folder_writer.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#if defined(SLAM_MMS_HAVE_ROSBAG)
#include "slam_mms/rosbag/rosbag_writer.hpp"
#endif

namespace slam_mms::app {
namespace {

struct NamedScanFormat {
  const char* name;
  FolderWriteOptions::ScanFormat format;
};
constexpr NamedScanFormat kScanFormats[] = {
    {"pcd_binary", FolderWriteOptions::ScanFormat::kPcdBinary},
    {"pcd_ascii", FolderWriteOptions::ScanFormat::kPcdAscii},
    {"ply_binary", FolderWriteOptions::ScanFormat::kPlyBinary},
    {"ply_ascii", FolderWriteOptions::ScanFormat::kPlyAscii},
    {"bin", FolderWriteOptions::ScanFormat::kBin},
};

}  // namespace

std::vector<std::string> ScanFormatNames() {
  std::vector<std::string> names;
  for (const NamedScanFormat& f : kScanFormats) names.emplace_back(f.name);
  return names;
}

Status WriteDrive(const DriveReader& reader, const std::string& to,
                  const std::filesystem::path& out, const WriteSettings& settings) {
  if (to == "folder") {
    FolderWriteOptions o;
    bool known = false;
    for (const NamedScanFormat& f : kScanFormats) {
      if (settings.scan_format == f.name) {
        o.scan_format = f.format;
        known = true;
      }
    }
    if (!known) return InvalidArgumentError("--scan-format " + settings.scan_format + ": unknown");
    o.gnss_format = settings.gnss_format == "nmea" ? FolderWriteOptions::GnssFormat::kNmea
                                                   : FolderWriteOptions::GnssFormat::kCsv;
    o.write_point_time = settings.folder_point_time;
    return WriteDriveFolder(reader, out, o);
  }
  if (to == "rosbag") {
#if defined(SLAM_MMS_HAVE_ROSBAG)
    RosbagWriteOptions o;
    o.write_point_time = !settings.bag_no_point_time;
    return WriteRosbag(reader, out, o);
#else
    return Status(StatusCode::kUnimplemented,
                  "--to rosbag: this slam_mms was built without the rosbag module");
#endif
  }
  if (to == "kitti-raw") {
    size_t dropped = 0;
    SLAM_MMS_RETURN_IF_ERROR(WriteKittiRawDrive(reader, out, &dropped));
    if (dropped > 0) {
      std::printf(
          "[convert] %zu GNSS fixes did not fit KITTI raw's one OXTS record per scan and were "
          "dropped\n",
          dropped);
    }
    return OkStatus();
  }
  return InvalidArgumentError("--to " + to + ": expected folder, rosbag or kitti-raw");
}

}  // namespace slam_mms::app
