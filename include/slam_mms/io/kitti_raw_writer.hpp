#pragma once
// KittiRawWriter: writes a drive folder in KITTI raw "sync" layout that KittiRawReader reads back
// (used by the simulator). Files:
// - <parent>/calib_imu_to_velo.txt, calib_velo_to_cam.txt, calib_cam_to_cam.txt (WriteCalibration);
// - <drive>/velodyne_points/data/%010d.bin and timestamps.txt, timestamps_start.txt,
//   timestamps_end.txt (AddScan);
// - <drive>/oxts/data/%010d.txt, timestamps.txt, dataformat.txt (AddOxts, 10 Hz; the folder is
//   created at the first AddOxts);
// - <drive>/oxts_100hz/data/%010d.txt, timestamps.txt, dataformat.txt (AddImuOxts, 100 Hz).
//
// Scans are numbered 0, 1, ... in the order added (Scan::index is ignored), points written as
// float32 x y z reflectance (intensity); per-point times are not stored (KITTI has none; the reader
// derives them from azimuth). Timestamp files use the KITTI format (Timestamp::ToKittiString).
// OXTS lines are written with %.17g (lossless). calib_velo_to_cam.txt and calib_cam_to_cam.txt are
// minimal placeholders (KITTI's velo->cam axis permutation without offset, KITTI-like intrinsics)
// so tools expecting them find them; only calib_imu_to_velo.txt carries information.
//
// Ownership: owns its open files; move-only. Thread safety: none (one thread per writer).

#include <Eigen/Geometry>
#include <filesystem>
#include <memory>

#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/io/oxts_record.hpp"

namespace slam_mms {

class KittiRawWriter {
 public:
  struct Options {
    /// Replace an existing non-empty drive folder (its contents are deleted); false:
    /// kInvalidArgument.
    bool overwrite = false;
    /// Where a scan's stamp_trigger is unset (0), write the midpoint of start and end.
    bool trigger_defaults_to_midpoint = true;

    [[nodiscard]] Status Validate() const { return OkStatus(); }
  };

  /// Creates `drive_dir` (and its parent) and the sub-folders, opens the timestamp files.
  [[nodiscard]] static StatusOr<KittiRawWriter> Create(const std::filesystem::path& drive_dir,
                                                       const Options& options);
  [[nodiscard]] static StatusOr<KittiRawWriter> Create(const std::filesystem::path& drive_dir);

  KittiRawWriter(KittiRawWriter&&) noexcept;
  KittiRawWriter& operator=(KittiRawWriter&&) noexcept;
  KittiRawWriter(const KittiRawWriter&) = delete;
  KittiRawWriter& operator=(const KittiRawWriter&) = delete;
  ~KittiRawWriter();  ///< Calls Finish() if not yet done (errors are logged).

  /// Writes calib_imu_to_velo.txt (R, T of T_lidar_body with %.9e) and the two placeholder camera
  /// calib files into the drive's parent folder.
  [[nodiscard]] Status WriteCalibration(const Eigen::Isometry3d& T_lidar_body);

  /// Appends a scan. Requires stamp_start <= stamp_trigger <= stamp_end (trigger unset: see
  /// Options), stamp_start strictly after the previous scan's, finite points and intensities.
  [[nodiscard]] Status AddScan(const Scan& scan);

  /// Appends a 10 Hz POS record to oxts/ (strictly increasing stamps). In sync layout the reader
  /// expects exactly one per scan.
  [[nodiscard]] Status AddOxts(Timestamp stamp, const OxtsRecord& record);

  /// Appends a 100 Hz IMU record to oxts_100hz/ (strictly increasing stamps).
  [[nodiscard]] Status AddImuOxts(Timestamp stamp, const OxtsRecord& record);

  /// Flushes and closes every file; kFailedPrecondition when OXTS records were added but their
  /// count differs from the scan count. Further Add* calls fail.
  [[nodiscard]] Status Finish();

  size_t NumScans() const;
  size_t NumOxts() const;
  size_t NumImuOxts() const;
  const std::filesystem::path& drive_dir() const;

 private:
  struct Impl;
  explicit KittiRawWriter(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
