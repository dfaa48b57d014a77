#include "slam_mms/io/kitti_drive_reader.hpp"

#include <cmath>
#include <cstdio>

#include "io/drive_imu_noise.hpp"
#include "slam_mms/io/oxts_record.hpp"

namespace slam_mms {
namespace {

// The accuracy of an OXTS RT3003 attitude (KITTI's POS): 0.03 deg roll and pitch, 0.1 deg heading
// (1 sigma; the RT3000 datasheet's figures, and KITTI's "0.1 deg" (Geiger et al. 2013); see
// ../shared/SENSORS_AND_METRICS.md). The POS starts from the first record with it.
const Eigen::Vector3d kOxtsAttitudeSigmaRpyRad = Eigen::Vector3d(0.03, 0.03, 0.1) * (M_PI / 180.0);

std::string NumberedFile(const std::filesystem::path& drive_dir, const char* folder, int64_t index,
                         const char* extension) {
  char name[40];
  std::snprintf(name, sizeof(name), "%010lld%s", static_cast<long long>(index), extension);
  return (drive_dir / folder / "data" / name).string();
}

}  // namespace

StatusOr<std::unique_ptr<KittiDriveReader>> KittiDriveReader::Open(
    const std::filesystem::path& drive_dir, const KittiRawReader::Options& options) {
  SLAM_MMS_ASSIGN_OR_RETURN(KittiRawReader reader, KittiRawReader::Open(drive_dir, options));
  std::unique_ptr<KittiDriveReader> out(new KittiDriveReader(std::move(reader)));
  // Not part of KITTI: a drive written by slam_mms_sim (or a user) may state its IMU's noise.
  SLAM_MMS_RETURN_IF_ERROR(
      io_internal::ReadDriveImuNoise(out->reader_.drive_dir(), &out->streams_));
  return out;
}

KittiDriveReader::KittiDriveReader(KittiRawReader reader) : reader_(std::move(reader)) {
  const std::filesystem::path& dir = reader_.drive_dir();
  DriveStreams& s = streams_;
  s.imu = reader_.ImuSamples();
  s.gnss = reader_.GnssFixes();
  const char* imu_folder = reader_.HasImu100Hz() ? "oxts_100hz" : "oxts";
  for (const StampedOxts& r : reader_.ImuOxtsRecords()) {
    s.imu_source.push_back(NumberedFile(dir, imu_folder, r.index, ".txt"));
  }
  for (const StampedOxts& r : reader_.OxtsRecords()) {
    s.gnss_source.push_back(NumberedFile(dir, "oxts", r.index, ".txt"));
  }
  // The POS starts from the earliest OXTS record: attitude and velocity (the position comes from
  // the first valid fix, which anchors the world frame).
  const StampedOxts* first = nullptr;
  const char* first_folder = "oxts";
  if (!reader_.OxtsRecords().empty()) first = &reader_.OxtsRecords().front();
  if (!reader_.ImuOxtsRecords().empty() &&
      (first == nullptr || reader_.ImuOxtsRecords().front().stamp < first->stamp)) {
    first = &reader_.ImuOxtsRecords().front();
    first_folder = imu_folder;
  }
  if (first != nullptr) {
    InsState state;
    state.stamp = first->stamp;
    state.T_world_body.linear() = OxtsAttitude(first->record);
    state.v_world_mps = OxtsVelocityEnu(first->record);
    s.initial_state = state;
    s.initial_state_source = NumberedFile(dir, first_folder, first->index, ".txt");
    s.initial_attitude_sigma_rpy_rad = kOxtsAttitudeSigmaRpyRad;
  }
  s.T_body_lidar = reader_.T_body_lidar();
  // The OXTS RT3003's frame: x forward, y left, z up, on the car (KITTI's setup).
  s.imu_frame_is_vehicle_frame = true;
}

std::string KittiDriveReader::Describe() const {
  return "KITTI raw " + reader_.drive_dir().string();
}

std::string KittiDriveReader::ScanSource(size_t i) const {
  return NumberedFile(reader_.drive_dir(), "velodyne_points", reader_.FrameIndex(i),
                      reader_.layout() == KittiRawLayout::kSync ? ".bin" : ".txt");
}

}  // namespace slam_mms
