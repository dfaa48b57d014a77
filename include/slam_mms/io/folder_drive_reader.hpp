#pragma once
// FolderDriveReader: a plain drive folder (docs/drive_folder.md), readable without any other tool:
//
//   DIR/scans/             one file per scan: PCD v0.7 (DATA ascii or binary), PLY (ascii or
//                          binary_little_endian) or KITTI .bin (float32 x y z reflectance)
//   DIR/scans.csv          file,stamp_start_ns,stamp_end_ns          (UTC ns since the epoch)
//   DIR/imu.csv            stamp_ns,ax,ay,az,wx,wy,wz                (body frame; m/s^2, rad/s)
//   DIR/gnss.csv           stamp_ns,lat_deg,lon_deg,height_m,sigma_e_m,sigma_n_m,sigma_u_m,fix
//                          [,num_sats]                               (optional; or gnss.nmea)
//   DIR/gnss.nmea          NMEA 0183 GGA + GST + RMC/ZDA             (optional)
//   DIR/extrinsics.yaml    T_body_lidar, t_body_antenna_m            (extrinsics_yaml.hpp)
//   DIR/initial_state.csv  stamp_ns,roll_deg,pitch_deg,yaw_deg,v_east_mps,v_north_mps,v_up_mps
//                          (optional; first data row)
//   DIR/pos.csv            stamp_ns,lat_deg,lon_deg,height_m,roll_deg,pitch_deg,yaw_deg
//                          [,sigma_roll_deg,sigma_pitch_deg,sigma_yaw_deg][,sigma_e_m,sigma_n_m,
//                          sigma_u_m]                                (optional external POS)
//
// Scans. Files need fields x, y, z (any of F4/F8/I/U types, COUNT 1), optionally intensity (also
// reflectance or scalar_intensity; 0 where absent) and a per-point time named t, time or
// timestamp in seconds from the scan start (values outside [-1 s, duration + 1 s] are an error:
// a field in ns or absolute seconds is not silently misread). Other fields are skipped. Without a
// time field the time comes from the azimuth over [stamp_start, stamp_end] exactly as
// KittiRawReader (KittiAzimuthFraction, same float arithmetic), so a folder written from a KITTI
// drive gives bit-identical clouds. Bytes after the declared points are ignored (PCL's padding);
// fewer is kDataLoss naming the file and the counts; binary_compressed is kUnimplemented.
// stamp_trigger is the midpoint of start and end (the folder has no trigger).
//
// Streams. imu.csv is required unless pos.csv gives an external POS. No GNSS file = a drive
// without GNSS (logged); both gnss.csv and gnss.nmea: gnss.csv is used (logged at kWarning). NMEA
// bad sentences are skipped, counted (num_bad_nmea_sentences) and logged with their lines. IMU,
// GNSS and POS records are kept within [first scan start - margin, last scan end + margin].
//
// CSV files: header required and checked by name (a column out of place is an error naming it);
// blank lines and '#' lines skipped; every error names "<file>:<line>: field '<name>'" (wrong
// field count, non-number, non-finite, stamps going backwards or duplicated).
//
// Ownership: owns the scan index (one file name and two stamps per scan) and the streams; scan
// points are read from disk on each ReadScan call. Thread safety: const methods may be called
// concurrently (ReadScan reads its own file; the dropped-points counter is atomic).

#include <atomic>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"

namespace slam_mms {

class FolderDriveReader final : public DriveReader {
 public:
  struct Options {
    /// First scan (row of scans.csv, 0-based) to read, inclusive.
    int64_t first_frame = 0;
    /// Last scan to read, inclusive; -1 = the last one.
    int64_t last_frame = -1;
    /// Spin direction for the azimuth time of scans without a time field.
    SpinDirection spin = SpinDirection::kClockwise;
    /// Fill cloud.time_offsets_s (from the time field, else the azimuth); false: all 0.
    bool per_point_time = true;
    /// Rotate each point up by vertical_correction_deg about p x z (KITTI HDL-64 defect).
    bool vertical_angle_correction = false;
    /// The correction angle [deg], within [-5, 5].
    double vertical_correction_deg = 0.205;
    /// Without extrinsics.yaml: false = kNotFound, true = identity T_body_lidar (logged).
    bool allow_missing_extrinsics = false;
    /// UTC date "YYYY-MM-DD" for gnss.nmea GGA sentences before any RMC/ZDA date; "" = none (such
    /// a GGA is an error naming its line).
    std::string nmea_utc_date;
    /// IMU/GNSS/POS records are kept within the selected scans' span +- this margin [s], >= 0.
    double stream_time_margin_s = 1.0;

    [[nodiscard]] Status Validate() const;
  };

  /// Opens `dir`: reads scans.csv (checks every listed file exists), the streams and the
  /// extrinsics; does not read scans.
  [[nodiscard]] static StatusOr<std::unique_ptr<FolderDriveReader>> Open(
      const std::filesystem::path& dir, const Options& options);

  FolderDriveReader(const FolderDriveReader&) = delete;
  FolderDriveReader& operator=(const FolderDriveReader&) = delete;

  std::string Describe() const override;
  size_t NumScans() const override { return scans_.size(); }
  Timestamp ScanStart(size_t i) const override { return scans_.at(i).start; }
  Timestamp ScanEnd(size_t i) const override { return scans_.at(i).end; }
  std::string ScanSource(size_t i) const override;
  /// Scan i; Scan::index is its row in scans.csv (0-based). kDataLoss for a malformed file (naming
  /// it), kOutOfRange for a bad i.
  [[nodiscard]] StatusOr<Scan> ReadScan(size_t i) const override;
  const DriveStreams& streams() const override { return streams_; }
  uint64_t TotalDroppedPoints() const override { return dropped_.load(); }

  const Options& options() const { return options_; }
  const std::filesystem::path& dir() const { return dir_; }
  /// NMEA sentences skipped for a bad checksum or malformed fields (0 without gnss.nmea).
  size_t num_bad_nmea_sentences() const { return num_bad_nmea_; }

 private:
  struct ScanEntry {
    int64_t index;
    std::filesystem::path file;
    Timestamp start, end;
  };
  FolderDriveReader() = default;
  Status LoadStreams();

  Options options_;
  std::filesystem::path dir_;
  std::vector<ScanEntry> scans_;
  DriveStreams streams_;
  size_t num_bad_nmea_ = 0;
  mutable std::atomic<uint64_t> dropped_{0};
};

}  // namespace slam_mms
