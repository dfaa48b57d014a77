#pragma once
// KittiRawReader: reads one drive folder in KITTI raw layout and streams its scans one at a time.
// Files:
// - calib_imu_to_velo.txt in Options::calib_dir, else the drive folder, else its parent (date);
// - velodyne_points/data/NNNNNNNNNN.bin (sync: float32 x y z reflectance, little endian) or
//   NNNNNNNNNN.txt (extract: text lines "x y z reflectance");
// - velodyne_points/timestamps.txt (trigger), timestamps_start.txt, timestamps_end.txt;
// - oxts/data/NNNNNNNNNN.txt and oxts/timestamps.txt (sync: 10 Hz, one per scan; extract: 100 Hz,
//   irregular); optional (a drive without oxts/ has no GNSS/INS records, logged);
// - oxts_100hz/data/NNNNNNNNNN.txt and oxts_100hz/timestamps.txt: optional 100 Hz IMU records
//   (written by KittiRawWriter / the simulator).
//
// Layouts. kSync: binary scans and 10 Hz OXTS with one record per scan (the counts must match).
// kExtract: text scans and 100 Hz OXTS with irregular timing; an empty line in a timestamps file
// marks a lost record/scan, which is skipped (counted and logged). The layout is detected from the
// scan files' extension.
//
// Streams: OxtsRecords() are the POS records (10 Hz in sync, 100 Hz in extract) -> GnssFixes().
// ImuOxtsRecords() are the records used as IMU: oxts_100hz/ when present, else the OXTS records
// themselves -> ImuSamples(), each stamped Options::oxts_inertial_delay_s before its record: by
// default the delay EstimateOxtsInertialDelay finds in those records where it is clear (KITTI's
// own: 50-55 ms; the simulator's records: 0), see slam_mms/io/oxts_timing.hpp.
//
// Per-point time (KITTI scans carry none): t = 0.5 (-atan2(y, x)/pi + 1) in [0, 1] for a clockwise
// spin (KISS-ICP / CT-ICP; confirmed on drive 0013, see ARCHITECTURE.md), 0.5 (atan2(y, x)/pi + 1)
// for counter-clockwise, scaled to [0, stamp_end - stamp_start] with stamp_start/end from
// timestamps_start.txt / timestamps_end.txt. Points are otherwise returned as recorded (not
// de-skewed), apart from the optional 0.205 deg vertical-angle correction of KITTI's HDL-64
// (each point rotated up by 0.205 deg about p x z, as KISS-ICP).
//
// Validation is strict: any malformed input returns a Status naming the file, line and field
// (a .bin size not a multiple of 16, an OXTS line without 30 numbers, timestamps going backwards or
// duplicated, a missing or malformed calib file, a frame range outside the drive). Points with a
// NaN/Inf coordinate or reflectance are dropped, counted (TotalDroppedPoints) and logged at
// kWarning. An empty scan file, or one with no finite point, is kDataLoss.
//
// Ownership: owns its index of file names and timestamps (a few hundred bytes per scan) and the
// OXTS records of the frame range; scan points are read from disk on each ReadScan call.
// Thread safety: const methods may be called concurrently (ReadScan opens its own file handle);
// the counters of dropped points are atomic.

#include <Eigen/Geometry>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/io/oxts_record.hpp"
#include "slam_mms/io/oxts_timing.hpp"

namespace slam_mms {

/// Rotation direction of the scanner seen from above (z up).
enum class SpinDirection { kClockwise, kCounterClockwise };

/// Which KITTI raw layout a drive folder uses.
enum class KittiRawLayout { kSync, kExtract };

/// One OXTS record with its time and file index.
struct StampedOxts {
  Timestamp stamp;
  int64_t index = -1;  ///< File number in oxts/data (or oxts_100hz/data).
  OxtsRecord record;
};

class KittiRawReader {
 public:
  struct Options {
    /// First frame (file number) to read, inclusive.
    int64_t first_frame = 0;
    /// Last frame (file number) to read, inclusive; -1 = the drive's last frame.
    int64_t last_frame = -1;
    /// Spin direction used for per-point time (KITTI's HDL-64: clockwise).
    SpinDirection spin = SpinDirection::kClockwise;
    /// Rotate each point up by vertical_correction_deg about p x z (KITTI HDL-64 defect).
    bool vertical_angle_correction = false;
    /// The correction angle [deg] (KISS-ICP / CT-ICP: 0.205).
    double vertical_correction_deg = 0.205;
    /// Fill cloud.time_offsets_s from azimuth; false: all offsets 0.
    bool per_point_time = true;
    /// Folder holding calib_imu_to_velo.txt; "" = the drive folder, then its parent.
    std::string calib_dir;
    /// Without calib_imu_to_velo.txt: false = kNotFound error, true = identity (logged).
    bool allow_missing_calibration = false;
    /// OXTS records used for IMU (ImuOxtsRecords) are kept within
    /// [first scan start - margin, last scan end + margin] [s]. Sync 10 Hz records are instead
    /// restricted to the frame range.
    double imu_time_margin_s = 1.0;
    /// How long before its record's time an IMU sample (ImuSamples) is stamped [s]: KITTI's OXTS
    /// rates and accelerations lag its positions, attitudes and the LiDAR (oxts_timing.hpp).
    /// Unset (the default): EstimateOxtsInertialDelay on ImuOxtsRecords(), applied where the
    /// estimate is clear, else 0. 0 = as recorded. Within [-0.5, 0.5] s.
    std::optional<double> oxts_inertial_delay_s;

    [[nodiscard]] Status Validate() const;
  };

  /// Opens `drive_dir` (e.g. .../2011_09_26/2011_09_26_drive_0013_sync): reads the timestamps, the
  /// OXTS records and the calibration, checks the layout; does not read scans.
  [[nodiscard]] static StatusOr<KittiRawReader> Open(const std::filesystem::path& drive_dir,
                                                     const Options& options);
  [[nodiscard]] static StatusOr<KittiRawReader> Open(const std::filesystem::path& drive_dir);

  KittiRawReader(KittiRawReader&&) noexcept;
  KittiRawReader& operator=(KittiRawReader&&) noexcept;
  KittiRawReader(const KittiRawReader&) = delete;
  KittiRawReader& operator=(const KittiRawReader&) = delete;
  ~KittiRawReader();

  const Options& options() const;
  KittiRawLayout layout() const;
  const std::filesystem::path& drive_dir() const;

  /// Number of scans in the frame range (lost scans of the extract layout excluded).
  size_t NumScans() const;
  /// Frame index (file number) of scan i (0 <= i < NumScans()).
  int64_t FrameIndex(size_t i) const;
  /// Times of scan i without reading it.
  Timestamp ScanStart(size_t i) const;
  Timestamp ScanEnd(size_t i) const;
  Timestamp ScanTrigger(size_t i) const;

  /// Reads scan i (0 <= i < NumScans()) from disk: points in the lidar frame, intensities =
  /// reflectance, time offsets from stamp_start (see the file comment). kOutOfRange for a bad i.
  [[nodiscard]] StatusOr<Scan> ReadScan(size_t i) const;

  /// POS records (sync: one per scan of the frame range; extract: 100 Hz within the scans' span
  /// +- imu_time_margin_s), strictly increasing stamps.
  const std::vector<StampedOxts>& OxtsRecords() const;
  /// Records used as IMU: oxts_100hz/ when present, else OxtsRecords(); strictly increasing.
  const std::vector<StampedOxts>& ImuOxtsRecords() const;
  /// True when oxts_100hz/ was found.
  bool HasImu100Hz() const;

  /// ToGnssFix of every OxtsRecords() entry.
  std::vector<GnssFix> GnssFixes() const;
  /// ToImuSample of every ImuOxtsRecords() entry, stamped oxts_inertial_delay_s() before it.
  std::vector<ImuSample> ImuSamples() const;
  /// The delay applied to ImuSamples() [s] (Options::oxts_inertial_delay_s or the clear estimate).
  double oxts_inertial_delay_s() const;
  /// The estimate where the option was unset and there were records to estimate from.
  const std::optional<OxtsInertialDelay>& oxts_inertial_delay_estimate() const;

  /// From calib_imu_to_velo.txt: maps points of the IMU/OXTS (body) frame into the lidar frame.
  const Eigen::Isometry3d& T_lidar_body() const;
  Eigen::Isometry3d T_body_lidar() const { return T_lidar_body().inverse(); }
  /// The calibration file read ("" where allow_missing_calibration gave identity).
  const std::filesystem::path& calibration_file() const;

  /// Points dropped for non-finite values, over all ReadScan calls so far.
  uint64_t TotalDroppedPoints() const;

 private:
  struct Impl;
  explicit KittiRawReader(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

/// Reads a KITTI "R: 9 numbers / T: 3 numbers" rigid calibration (calib_imu_to_velo.txt,
/// calib_velo_to_cam.txt) as the isometry [R T]. Errors name the file, line and key; R must be a
/// rotation within 1e-4 (the files carry 7 digits).
[[nodiscard]] StatusOr<Eigen::Isometry3d> ReadKittiRigidCalibration(
    const std::filesystem::path& file);

/// Reads one scan file (.bin binary or .txt text), keeping NaN/Inf points (for tools and tests).
/// kDataLoss for a .bin whose size is not a multiple of 16 (naming file and size) or a bad text
/// line.
[[nodiscard]] StatusOr<PointCloud> ReadKittiScanFile(const std::filesystem::path& file);

/// Per-point time fraction in [0, 1] of a point at (x, y) for the given spin (see file comment).
double KittiAzimuthFraction(double x, double y, SpinDirection spin);

}  // namespace slam_mms
