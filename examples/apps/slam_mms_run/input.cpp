#include "slam_mms_run/input.hpp"

#include "slam_mms/drive/open_drive.hpp"

namespace slam_mms::app {

std::filesystem::path InputPath(const RunArgs& args) {
  if (!args.folder.empty()) return args.folder;
  if (!args.rosbag.empty()) return args.rosbag;
  return args.kitti_raw;
}

StatusOr<std::unique_ptr<DriveReader>> OpenRunInput(const RunArgs& args,
                                                    const std::filesystem::path& path) {
  DriveSourceOptions o;
  o.kind = !args.folder.empty()   ? DriveSourceKind::kFolder
           : !args.rosbag.empty() ? DriveSourceKind::kRosbag
                                  : DriveSourceKind::kKittiRaw;
  o.first_frame = args.first_frame;
  o.last_frame = args.last_frame;
  o.lidar_topic = args.lidar_topic;
  o.imu_topic = args.imu_topic;
  o.gnss_topic = args.gnss_topic;
  o.extrinsics = args.extrinsics;
  o.imu_noise = args.imu_noise;
  o.kitti_vertical_correction_deg = args.kitti_vertical_correction_deg;
  o.kitti_oxts_inertial_delay_s = args.kitti_oxts_inertial_delay_s;
  return OpenDrive(path, o);
}

std::filesystem::path GroundTruthDir(const RunArgs& args, const std::filesystem::path& path) {
  return args.rosbag.empty() ? path : path.parent_path();
}

}  // namespace slam_mms::app
