#pragma once
// WriteDriveFolder: any DriveReader (a KITTI raw drive, a ROS bag, another folder) written as a
// plain drive folder that FolderDriveReader reads back (layout in folder_drive_reader.hpp and
// docs/drive_folder.md). Writes scans/NNNNNNNNNN.<ext>, scans.csv, imu.csv, gnss.csv or gnss.nmea
// (only where the drive has GNSS fixes), extrinsics.yaml, initial_state.csv (where the drive has
// an initial state) and pos.csv (where it has an external POS); nothing else.
//
// What round-trips bit for bit: scan points and intensities (float32), per-point times (with
// write_point_time; without it the reader re-derives them from the azimuth, bit-identical to
// KittiRawReader for a KITTI drive read without vertical correction), scan start/end stamps, IMU,
// gnss.csv fixes (stamps, lat/lon/height, sigmas, fix type, satellites), T_body_lidar and the
// antenna lever arm (%.17g). Attitudes go through degrees (initial_state.csv, pos.csv): within
// ~1e-15 rad. Lost: stamp_trigger (the reader uses the scan midpoint), sources. gnss.nmea loses
// precision (see FolderWriteOptions::nmea_time_decimals): positions <= 1 um (1e-9 minutes),
// heights and sigmas <= 0.5 um (6 decimals), stamps to the written decimals; an unequal
// east/north sigma pair becomes one horizontal sigma (GST lat/lon sigma both = sigma_horizontal).
//
// Points are written as the reader returns them: open a KITTI drive without
// vertical_angle_correction to keep the recorded points.
//
// Thread safety: reads `reader` through its const methods; one call per output folder.

#include <filesystem>

#include "slam_mms/core/status.hpp"
#include "slam_mms/io/drive_reader.hpp"

namespace slam_mms {

struct FolderWriteOptions {
  enum class ScanFormat { kPcdBinary, kPcdAscii, kPlyBinary, kPlyAscii, kBin };
  enum class GnssFormat { kCsv, kNmea };

  /// Scan files: PCD v0.7 or PLY (float32 x y z intensity [t]) or KITTI .bin (x y z reflectance).
  ScanFormat scan_format = ScanFormat::kPcdBinary;
  GnssFormat gnss_format = GnssFormat::kCsv;
  /// Write each point's time offset as a float32 field `t` [s from the scan start]. Not with kBin.
  bool write_point_time = false;
  /// Decimals of the NMEA time of day, 0..9 (3: stamps within 0.5 ms; 9: exact).
  int nmea_time_decimals = 3;
  /// An existing non-empty `dir` is deleted first; false: kInvalidArgument.
  bool overwrite = false;

  [[nodiscard]] Status Validate() const;
};

/// Writes every scan and stream of `reader` into `dir` (created). A scan the reader cannot read
/// stops the write with its Status (prefixed with the scan's source).
[[nodiscard]] Status WriteDriveFolder(const DriveReader& reader, const std::filesystem::path& dir,
                                      const FolderWriteOptions& options);

}  // namespace slam_mms
