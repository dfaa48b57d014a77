#pragma once
// OxtsRecord: one line of a KITTI `oxts/data/NNNNNNNNNN.txt` file (OXTS RT3003 GNSS/INS), all 30
// fields with their units, and the conversions the rest of the library needs: GnssFix, ImuSample
// and the attitude R_enu_body.
//
// Field meanings follow KITTI's `oxts/dataformat.txt` and ../shared/SENSORS_AND_METRICS.md:
// body frame x forward, y left, z up; accelerations are specific force (az is about +9.8 at rest).
//
// Thread safety: value type and pure functions; safe from any thread.

#include <Eigen/Core>
#include <array>
#include <string>

#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms {

/// The 30 numbers of one OXTS record, in file order.
struct OxtsRecord {
  static constexpr int kNumFields = 30;

  double lat_deg = 0.0;    ///< 1  latitude of the OXTS unit, WGS-84 [deg].
  double lon_deg = 0.0;    ///< 2  longitude [deg].
  double alt_m = 0.0;      ///< 3  altitude [m].
  double roll_rad = 0.0;   ///< 4  roll [rad], 0 = level, + = left side up.
  double pitch_rad = 0.0;  ///< 5  pitch [rad], 0 = level, + = front down.
  double yaw_rad = 0.0;    ///< 6  heading [rad], 0 = east, + = counter-clockwise.
  double vn = 0.0;         ///< 7  velocity towards north [m/s].
  double ve = 0.0;         ///< 8  velocity towards east [m/s].
  double vf = 0.0;         ///< 9  forward velocity, parallel to the earth surface [m/s].
  double vl = 0.0;         ///< 10 leftward velocity, parallel to the earth surface [m/s].
  double vu = 0.0;         ///< 11 upward velocity [m/s].
  double ax = 0.0;         ///< 12 specific force along body x (front) [m/s^2].
  double ay = 0.0;         ///< 13 specific force along body y (left) [m/s^2].
  double az = 0.0;         ///< 14 specific force along body z (top) [m/s^2]; about +9.8 at rest.
  double af = 0.0;         ///< 15 forward acceleration, level frame [m/s^2].
  double al = 0.0;         ///< 16 leftward acceleration, level frame [m/s^2].
  double au = 0.0;         ///< 17 upward acceleration, level frame [m/s^2].
  double wx = 0.0;         ///< 18 angular rate about body x [rad/s].
  double wy = 0.0;         ///< 19 angular rate about body y [rad/s].
  double wz = 0.0;         ///< 20 angular rate about body z [rad/s].
  double wf = 0.0;         ///< 21 angular rate about the forward axis, level frame [rad/s].
  double wl = 0.0;         ///< 22 angular rate about the leftward axis, level frame [rad/s].
  double wu = 0.0;         ///< 23 angular rate about the upward axis, level frame [rad/s].
  double pos_accuracy_m = 0.0;    ///< 24 position accuracy, north/east, 1 sigma [m].
  double vel_accuracy_mps = 0.0;  ///< 25 velocity accuracy, north/east [m/s].
  int navstat = 0;                ///< 26 navigation status (NCOM): 4 = locked (INS solution valid).
  int numsats = 0;                ///< 27 satellites tracked by the primary receiver.
  int posmode = 0;                ///< 28 position mode (NCOM codes, see OxtsGnssMode).
  int velmode = 0;                ///< 29 velocity mode.
  int orimode = 0;                ///< 30 orientation mode.

  /// The 30 fields as doubles, in file order.
  std::array<double, kNumFields> ToArray() const;
  /// Inverse of ToArray (the 5 integer fields are rounded to the nearest integer).
  static OxtsRecord FromArray(const std::array<double, kNumFields>& values);
  /// The file's name of field `i` (0-based): "lat", "lon", ..., "orimode".
  static const char* FieldName(int i);
};

/// NCOM GNSS mode codes used by posmode/velmode/orimode.
enum class OxtsGnssMode : int {
  kNone = 0,
  kSearch = 1,
  kDoppler = 2,
  kSps = 3,
  kDifferential = 4,
  kRtkFloat = 5,
  kRtkInteger = 6,
  kWaas = 7,
  kOmnistarVbs = 8,
  kOmnistarHp = 9,
  kNoData = 10,
  kBlanked = 11,
};

/// The NCOM navstat value meaning "locked": the INS solution is valid.
constexpr int kOxtsNavstatLocked = 4;

/// Parses one OXTS line: exactly 30 whitespace-separated finite numbers (the 5 integer fields must
/// be integral). Errors (kDataLoss) name `file`, `line_number` (1-based) and the field ("field 7
/// (vn)").
[[nodiscard]] StatusOr<OxtsRecord> ParseOxtsLine(const std::string& line, const std::string& file,
                                                 int line_number);

/// Formats a record as one line of 30 space-separated numbers (no newline). Doubles use %.17g, so
/// ParseOxtsLine(FormatOxtsLine(r)) reproduces r bit for bit.
std::string FormatOxtsLine(const OxtsRecord& record);

/// Fix type from the record (documented mapping):
///   navstat != 4 (INS not locked)                    -> kNone
///   posmode 0 none, 1 search, 10 no data, 11 blanked -> kNone
///   posmode 2 Doppler, 3 SPS                         -> kSingle
///   posmode 4 differential, 7 WAAS, 8 OmniSTAR VBS   -> kDifferential
///   posmode 5 RTK float, 9 OmniSTAR HP               -> kRtkFloat
///   posmode 6 RTK integer                            -> kRtkFixed
///   any other posmode                                -> kNone
GnssFixType OxtsFixType(const OxtsRecord& record);

/// GnssFix of the record: lat/lon/alt as given, sigma_horizontal_m = pos_accuracy_m,
/// sigma_vertical_m = 1.5 * pos_accuracy_m, type = OxtsFixType, num_satellites = numsats.
GnssFix ToGnssFix(const OxtsRecord& record, Timestamp stamp);

/// ImuSample of the record: accel = (ax, ay, az) specific force, gyro = (wx, wy, wz), body frame.
ImuSample ToImuSample(const OxtsRecord& record, Timestamp stamp);

/// Attitude of the body in local ENU: R_enu_body = Rz(yaw) * Ry(pitch) * Rx(roll) (KITTI devkit).
Eigen::Matrix3d OxtsAttitude(const OxtsRecord& record);

/// Velocity in local ENU [m/s]: (ve, vn, vu).
Eigen::Vector3d OxtsVelocityEnu(const OxtsRecord& record);

/// Fills roll/pitch/yaw of `record` from R_enu_body (inverse of OxtsAttitude).
void SetOxtsAttitude(const Eigen::Matrix3d& R_enu_body, OxtsRecord* record);

/// The text of KITTI's oxts/dataformat.txt (30 lines, trailing newline).
const char* OxtsDataFormatText();

}  // namespace slam_mms
