#pragma once
// Local tangent frames on the WGS-84 ellipsoid: the rotation between an ENU (east, north, up)
// frame at a geodetic latitude/longitude and ECEF. Positions go through GeographicLib
// (LocalCartesian) where they are needed; this is the one rotation the library shares between
// external POS records (drive/drive_runner) and ground truth (eval/ground_truth).
//
// Thread safety: pure functions.

#include <Eigen/Core>

namespace slam_mms {

/// WGS-84 point [deg, deg, m]; the height is above the WGS-84 ellipsoid. The one geodetic point
/// type of the library: GNSS fixes' origin, the world frame's origin (GeoReference), converted
/// coordinates.
struct GeodeticPoint {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;
};

/// Rotation of the ENU tangent frame at (latitude, longitude) [deg] into ECEF: its columns are
/// east, north and up in ECEF. R_enu2_enu1 = R_ecef_enu(p2)^T * R_ecef_enu(p1).
Eigen::Matrix3d R_ecef_enu(double latitude_deg, double longitude_deg);

}  // namespace slam_mms
