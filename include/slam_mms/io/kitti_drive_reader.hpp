#pragma once
// KittiDriveReader: a KITTI raw drive folder (KittiRawReader) as a DriveReader. The streams are
// the OXTS records as IMU samples (oxts_100hz/ when present) and GNSS fixes, the initial state is
// the attitude and ENU velocity of the earliest OXTS record, T_body_lidar comes from
// calib_imu_to_velo.txt; sources name the oxts/data/NNNNNNNNNN.txt files.
//
// Ownership: owns the KittiRawReader. Thread safety: as KittiRawReader (const methods concurrent).

#include <filesystem>
#include <memory>

#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"

namespace slam_mms {

class KittiDriveReader final : public DriveReader {
 public:
  [[nodiscard]] static StatusOr<std::unique_ptr<KittiDriveReader>> Open(
      const std::filesystem::path& drive_dir, const KittiRawReader::Options& options);

  std::string Describe() const override;
  size_t NumScans() const override { return reader_.NumScans(); }
  Timestamp ScanStart(size_t i) const override { return reader_.ScanStart(i); }
  Timestamp ScanEnd(size_t i) const override { return reader_.ScanEnd(i); }
  std::string ScanSource(size_t i) const override;
  [[nodiscard]] StatusOr<Scan> ReadScan(size_t i) const override { return reader_.ReadScan(i); }
  const DriveStreams& streams() const override { return streams_; }
  uint64_t TotalDroppedPoints() const override { return reader_.TotalDroppedPoints(); }

  /// The underlying reader (OXTS records, layout, calibration file).
  const KittiRawReader& kitti() const { return reader_; }

 private:
  explicit KittiDriveReader(KittiRawReader reader);
  KittiRawReader reader_;
  DriveStreams streams_;
};

}  // namespace slam_mms

namespace slam_mms {

/// Writes any DriveReader as a KITTI raw "sync" drive folder (KittiRawWriter) that
/// KittiDriveReader reads back: velodyne_points/ (.bin, per-point times not stored: the reader
/// derives them from azimuth), calib_imu_to_velo.txt in the parent folder, oxts_100hz/ with every
/// IMU sample, and oxts/ with one record per scan, as the sync layout demands: the GNSS fix
/// nearest the scan's trigger (mid) time not used by an earlier scan (position, pos_accuracy =
/// sigma_horizontal, fix type as NCOM navstat/posmode), stamped at the fix's time; a scan without
/// such a fix gets a record with navstat 0 (no fix) at its trigger time. GNSS at another rate than
/// the scans therefore loses fixes, and the records' attitude and velocity are only those of the
/// initial state (the first record of oxts/ and of oxts_100hz/) or of an external POS (interpolated
/// at the record), else zero: KITTI raw has no field for "unknown". A lever arm is not
/// representable (logged). Returns the number of GNSS fixes that found no scan in `fixes_dropped`
/// (may be null).
[[nodiscard]] Status WriteKittiRawDrive(const DriveReader& reader,
                                        const std::filesystem::path& drive_dir,
                                        size_t* fixes_dropped = nullptr);

}  // namespace slam_mms
