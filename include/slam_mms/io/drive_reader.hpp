#pragma once
// DriveReader: the adaptor every drive input implements (KITTI raw, a plain drive folder, a ROS 1
// bag), so that hosts and apps feed MappingSystem the same way whatever the source
// (ARCHITECTURE.md, "Readers are adaptors").
//
// A reader opens its input once, indexes the scans (times and where each one is, not their
// points) and reads the non-scan streams (IMU, GNSS, an optional external POS), which fit in
// memory: an hour at 100 Hz IMU + 10 Hz GNSS is about 25 MB. Scans are read one at a time by
// ReadScan, so a drive of any length streams through in constant memory.
//
// Conventions shared by every reader:
// - scans: points in the `lidar` frame, not de-skewed, per-point time offsets from stamp_start
//   (from the input's own time field, else from the azimuth as for KITTI, see KittiRawReader);
//   non-finite points are dropped and counted; ScanStart/ScanEnd are known without reading points;
// - IMU: body frame, specific force with gravity [m/s^2], angular rate [rad/s];
// - GNSS: antenna position in WGS-84 with reported sigmas and fix type;
// - every stream strictly increasing in time (a reader refuses one that goes backwards, naming
//   the file/line or bag message);
// - each record has a `source` string ("file:line", "bag.bag: /imu message 12") that errors name.
//
// Thread safety: const methods may be called concurrently unless a reader says otherwise.
// Ownership: readers own their index and streams; ReadScan returns values.

#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "slam_mms/core/imu_noise.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms {

/// One record of an external POS solution (pos.csv, an INS's own output): the body's geodetic
/// position and its attitude in the local ENU frame at that position.
struct PosRecord {
  Timestamp stamp;
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;  ///< Ellipsoidal [m].
  /// Body attitude in local ENU (KITTI OXTS convention: R = Rz(yaw) Ry(pitch) Rx(roll), yaw 0 =
  /// east, counter-clockwise).
  Eigen::Matrix3d R_enu_body = Eigen::Matrix3d::Identity();
  /// 1-sigma of [roll, pitch, yaw] [rad] and [east, north, up] [m]; empty = not given.
  std::optional<Eigen::Vector3d> sigma_rpy_rad;
  std::optional<Eigen::Vector3d> sigma_enu_m;
};

/// The non-scan streams of a drive and its calibration.
struct DriveStreams {
  std::vector<ImuSample> imu;           ///< Strictly increasing stamps.
  std::vector<std::string> imu_source;  ///< One per sample: where it came from.
  std::vector<GnssFix> gnss;            ///< Strictly increasing stamps.
  std::vector<std::string> gnss_source;
  std::vector<PosRecord> pos;  ///< External POS instead of IMU + GNSS; empty = none.
  std::vector<std::string> pos_source;
  /// Attitude (R_world_body, local ENU) and velocity (ENU) at `stamp` for the POS start; empty:
  /// the filter aligns itself. Only the rotation of T_world_body and v_world_mps are meaningful.
  std::optional<InsState> initial_state;
  std::string initial_state_source;
  /// The 1-sigma roll, pitch, yaw [rad] of initial_state's attitude where its source states them
  /// (KITTI: the OXTS RT3003's specification; a folder: initial_state.csv's sigma columns); the
  /// POS starts with them (MappingSystem::InitializePos). Empty: the filter's init sigmas.
  std::optional<Eigen::Vector3d> initial_attitude_sigma_rpy_rad;
  /// The IMU's noise as the input states it (the drive folder's imu_noise.yaml, see
  /// io/imu_noise_yaml.hpp); RunDrive models the IMU with it (MappingSystem::Options::
  /// SetImuNoise) where MappingSystem::Options::use_stated_imu_noise is on. Empty: not stated
  /// (KITTI's own drives), the filter's defaults.
  std::optional<ImuNoiseSpec> imu_noise;
  std::string imu_noise_source;  ///< The file it came from.
  Eigen::Isometry3d T_body_lidar = Eigen::Isometry3d::Identity();
  /// GNSS antenna lever arm in body [m] where the input gives one.
  std::optional<Eigen::Vector3d> t_body_antenna_m;
  /// True where the input states that its IMU (body) frame is the vehicle's: x forward, z up,
  /// mounted on a wheeled vehicle, so that its sideways and vertical velocities stay near zero
  /// (the non-holonomic constraint, MappingSystem::Options::vehicle_nhc_sigma_mps). KITTI raw
  /// (the OXTS frame, also the simulator's drives): true. A folder: its extrinsics.yaml's
  /// `imu_frame_is_vehicle_frame` (slam_mms_convert writes it where the source states it), else
  /// false. A bag says nothing of the IMU's mounting: false, unless an --extrinsics file states it
  /// (DriveExtrinsics::imu_frame_is_vehicle_frame).
  bool imu_frame_is_vehicle_frame = false;
};

class DriveReader {
 public:
  virtual ~DriveReader() = default;

  /// What was opened, for messages: "KITTI raw /a/b", "folder /a/b", "ROS 1 bag /a/b.bag".
  virtual std::string Describe() const = 0;
  /// Number of scans (in the selected range).
  virtual size_t NumScans() const = 0;
  /// Times of scan i (0 <= i < NumScans()) without reading its points.
  virtual Timestamp ScanStart(size_t i) const = 0;
  virtual Timestamp ScanEnd(size_t i) const = 0;
  /// Where scan i is (file, or bag + topic + message number), for messages.
  virtual std::string ScanSource(size_t i) const = 0;
  /// Reads scan i. A malformed scan: kDataLoss naming its source (the caller may skip it);
  /// kOutOfRange for a bad i.
  [[nodiscard]] virtual StatusOr<Scan> ReadScan(size_t i) const = 0;
  /// The IMU/GNSS/POS streams and the calibration, read when the reader was opened.
  virtual const DriveStreams& streams() const = 0;
  /// Points dropped for non-finite values over all ReadScan calls so far.
  virtual uint64_t TotalDroppedPoints() const = 0;
  /// The reader this one adapts (OverrideExtrinsics' wrapper: the reader it wraps, recursively),
  /// else itself: what hosts inspect for the input's kind (the OXTS ground truth of KITTI raw).
  virtual const DriveReader& Underlying() const { return *this; }
};

}  // namespace slam_mms
