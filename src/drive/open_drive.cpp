#include "slam_mms/drive/open_drive.hpp"

#include <cmath>
#include <optional>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/io/folder_drive_reader.hpp"
#include "slam_mms/io/imu_noise_yaml.hpp"
#include "slam_mms/io/kitti_calibration.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#if defined(SLAM_MMS_HAVE_ROSBAG)
#include "slam_mms/rosbag/rosbag_drive_reader.hpp"
#endif

namespace slam_mms {
namespace {

// A reader whose calibration (--extrinsics) or IMU noise (--imu-noise) is replaced: see
// OverrideExtrinsics and OverrideImuNoise.
class StreamsOverride final : public DriveReader {
 public:
  StreamsOverride(std::unique_ptr<DriveReader> owned, const DriveReader* base,
                  const DriveExtrinsics& extrinsics)
      : owned_(std::move(owned)),
        base_(base),
        streams_(base_->streams()),
        lidar_offset_ns_(std::llround(extrinsics.lidar_time_offset_s * 1e9)) {
    streams_.T_body_lidar = extrinsics.T_body_lidar;
    if (extrinsics.t_body_antenna_m) streams_.t_body_antenna_m = extrinsics.t_body_antenna_m;
    if (extrinsics.imu_frame_is_vehicle_frame) {
      streams_.imu_frame_is_vehicle_frame = *extrinsics.imu_frame_is_vehicle_frame;
    }
  }
  StreamsOverride(std::unique_ptr<DriveReader> owned, const DriveReader* base,
                  const ImuNoiseSpec& imu_noise, const std::string& source)
      : owned_(std::move(owned)), base_(base), streams_(base_->streams()) {
    streams_.imu_noise = imu_noise;
    streams_.imu_noise_source = source;
  }
  std::string Describe() const override { return base_->Describe(); }
  size_t NumScans() const override { return base_->NumScans(); }
  Timestamp ScanStart(size_t i) const override { return OnImuClock(base_->ScanStart(i)); }
  Timestamp ScanEnd(size_t i) const override { return OnImuClock(base_->ScanEnd(i)); }
  std::string ScanSource(size_t i) const override { return base_->ScanSource(i); }
  StatusOr<Scan> ReadScan(size_t i) const override {
    SLAM_MMS_ASSIGN_OR_RETURN(Scan scan, base_->ReadScan(i));
    // Per-point times are offsets from stamp_start: they move with it.
    scan.stamp_start = OnImuClock(scan.stamp_start);
    scan.stamp_end = OnImuClock(scan.stamp_end);
    scan.stamp_trigger = OnImuClock(scan.stamp_trigger);
    return scan;
  }
  const DriveStreams& streams() const override { return streams_; }
  uint64_t TotalDroppedPoints() const override { return base_->TotalDroppedPoints(); }
  const DriveReader& Underlying() const override { return base_->Underlying(); }

 private:
  // A LiDAR stamp s is s + lidar_time_offset_s on the IMU clock.
  Timestamp OnImuClock(Timestamp lidar_stamp) const {
    return Timestamp::FromNanoseconds(lidar_stamp.nanoseconds() + lidar_offset_ns_);
  }

  std::unique_ptr<DriveReader> owned_;  // empty where the caller keeps base_
  const DriveReader* base_;
  DriveStreams streams_;
  int64_t lidar_offset_ns_ = 0;
};

}  // namespace

std::unique_ptr<DriveReader> OverrideExtrinsics(std::unique_ptr<DriveReader> base,
                                                const DriveExtrinsics& extrinsics) {
  const DriveReader* b = base.get();
  return std::make_unique<StreamsOverride>(std::move(base), b, extrinsics);
}

std::unique_ptr<DriveReader> OverrideExtrinsics(const DriveReader& base,
                                                const DriveExtrinsics& extrinsics) {
  return std::make_unique<StreamsOverride>(nullptr, &base, extrinsics);
}

std::unique_ptr<DriveReader> OverrideImuNoise(std::unique_ptr<DriveReader> base,
                                              const ImuNoiseSpec& imu_noise,
                                              const std::string& source) {
  const DriveReader* b = base.get();
  return std::make_unique<StreamsOverride>(std::move(base), b, imu_noise, source);
}

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
  std::optional<DriveExtrinsics> extrinsics;
  if (!options.extrinsics.empty()) {
    SLAM_MMS_ASSIGN_OR_RETURN(extrinsics, ReadExtrinsicsFile(options.extrinsics));
  }
  std::optional<ImuNoiseSpec> imu_noise;
  if (!options.imu_noise.empty()) {
    SLAM_MMS_ASSIGN_OR_RETURN(imu_noise, ReadImuNoiseYaml(options.imu_noise));
  }
  // The drive's own calibration and IMU noise, then --extrinsics and --imu-noise over them
  // (`reader_took_extrinsics`: the reader applied them itself).
  auto with_overrides = [&](std::unique_ptr<DriveReader> reader,
                            bool reader_took_extrinsics = false) {
    if (extrinsics && !reader_took_extrinsics) {
      reader = OverrideExtrinsics(std::move(reader), *extrinsics);
    }
    if (imu_noise) reader = OverrideImuNoise(std::move(reader), *imu_noise, options.imu_noise);
    return reader;
  };
  switch (kind) {
    case DriveSourceKind::kAuto:
    case DriveSourceKind::kKittiRaw: {
      KittiRawReader::Options ro;
      ro.first_frame = options.first_frame;
      ro.last_frame = options.last_frame;
      ro.vertical_angle_correction = options.kitti_vertical_correction_deg != 0.0;
      ro.vertical_correction_deg = options.kitti_vertical_correction_deg;
      ro.oxts_inertial_delay_s = options.kitti_oxts_inertial_delay_s;
      SLAM_MMS_ASSIGN_OR_RETURN(std::unique_ptr<KittiDriveReader> reader,
                                KittiDriveReader::Open(path, ro));
      return with_overrides(std::move(reader));
    }
    case DriveSourceKind::kFolder: {
      FolderDriveReader::Options fo;
      fo.first_frame = options.first_frame;
      fo.last_frame = options.last_frame;
      fo.allow_missing_extrinsics = extrinsics.has_value();
      fo.vertical_angle_correction = options.kitti_vertical_correction_deg != 0.0;
      fo.vertical_correction_deg = options.kitti_vertical_correction_deg;
      SLAM_MMS_ASSIGN_OR_RETURN(std::unique_ptr<FolderDriveReader> folder,
                                FolderDriveReader::Open(path, fo));
      return with_overrides(std::move(folder));
    }
    case DriveSourceKind::kRosbag: {
      if (options.kitti_vertical_correction_deg != 0.0) {
        return InvalidArgumentError(
            "DriveSourceOptions::kitti_vertical_correction_deg is for KITTI raw drives and "
            "folders of KITTI .bin scans, not for a bag ('" +
            path.string() + "')");
      }
#if defined(SLAM_MMS_HAVE_ROSBAG)
      RosbagDriveReader::Options bo;
      bo.lidar_topic = options.lidar_topic;
      bo.imu_topic = options.imu_topic;
      bo.gnss_topic = options.gnss_topic;
      bo.first_scan = options.first_frame;
      bo.last_scan = options.last_frame;
      if (extrinsics) {
        // Also given to the bag reader, which checks them.
        bo.T_body_lidar = extrinsics->T_body_lidar;
        bo.t_body_antenna_m = extrinsics->t_body_antenna_m;
        bo.imu_frame_is_vehicle_frame = extrinsics->imu_frame_is_vehicle_frame.value_or(false);
      } else {
        SLAM_MMS_LOG(kWarning) << path.string()
                               << ": no extrinsics given (--extrinsics FILE): T_body_lidar = "
                                  "identity";
      }
      SLAM_MMS_ASSIGN_OR_RETURN(std::unique_ptr<RosbagDriveReader> bag,
                                RosbagDriveReader::Open(path, bo));
      // The bag reader took T_body_lidar, the antenna and the IMU frame's statement: only a clock
      // offset needs the wrapper (hosts see the RosbagDriveReader itself otherwise).
      return with_overrides(std::move(bag), extrinsics && extrinsics->lidar_time_offset_s == 0.0);
#else
      break;
#endif
    }
  }
  return Status(StatusCode::kUnimplemented,
                path.string() +
                    ": ROS 1 bags are not built into this slam_mms (configure with "
                    "SLAM_MMS_WITH_ROSBAG=ON and librosbag-storage-dev installed)");
}

}  // namespace slam_mms
