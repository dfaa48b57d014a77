#include "slam_mms/pipeline/open_drive.hpp"

#include "slam_mms/io/kitti_drive_reader.hpp"

namespace slam_mms {

const char* DriveSourceKindName(DriveSourceKind kind) {
  switch (kind) {
    case DriveSourceKind::kAuto: return "auto";
    case DriveSourceKind::kKittiRaw: return "kitti_raw";
    case DriveSourceKind::kFolder: return "folder";
    case DriveSourceKind::kRosbag: return "rosbag";
  }
  return "?";
}

DriveSourceKind DetectDriveSourceKind(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_regular_file(path, ec) && path.extension() == ".bag") {
    return DriveSourceKind::kRosbag;
  }
  if (std::filesystem::is_regular_file(path / "scans.csv", ec)) return DriveSourceKind::kFolder;
  return DriveSourceKind::kKittiRaw;
}

StatusOr<std::unique_ptr<DriveReader>> OpenDrive(const std::filesystem::path& path,
                                                 const DriveSourceOptions& options) {
  const DriveSourceKind kind =
      options.kind == DriveSourceKind::kAuto ? DetectDriveSourceKind(path) : options.kind;
  switch (kind) {
    case DriveSourceKind::kAuto:
    case DriveSourceKind::kKittiRaw: {
      if (!options.extrinsics.empty()) {
        return InvalidArgumentError("--extrinsics " + options.extrinsics.string() +
                                    ": a KITTI raw drive takes its calibration from "
                                    "calib_imu_to_velo.txt");
      }
      KittiRawReader::Options ro;
      ro.first_frame = options.first_frame;
      ro.last_frame = options.last_frame;
      SLAM_MMS_ASSIGN_OR_RETURN(std::unique_ptr<KittiDriveReader> reader,
                                KittiDriveReader::Open(path, ro));
      return std::unique_ptr<DriveReader>(std::move(reader));
    }
    case DriveSourceKind::kFolder:
    case DriveSourceKind::kRosbag: break;
  }
  return Status(StatusCode::kUnimplemented,
                path.string() + ": " + DriveSourceKindName(kind) + " input not built in");
}

}  // namespace slam_mms
