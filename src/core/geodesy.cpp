#include "slam_mms/core/geodesy.hpp"

#include <cmath>

namespace slam_mms {

Eigen::Matrix3d R_ecef_enu(double latitude_deg, double longitude_deg) {
  constexpr double kDegToRad = M_PI / 180.0;
  const double slat = std::sin(latitude_deg * kDegToRad), clat = std::cos(latitude_deg * kDegToRad);
  const double slon = std::sin(longitude_deg * kDegToRad),
               clon = std::cos(longitude_deg * kDegToRad);
  Eigen::Matrix3d R;  // columns: east, north, up in ECEF
  R.col(0) << -slon, clon, 0.0;
  R.col(1) << -slat * clon, -slat * slon, clat;
  R.col(2) << clat * clon, clat * slon, slat;
  return R;
}

}  // namespace slam_mms
