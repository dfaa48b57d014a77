#pragma once
// GeoReference: how the outputs of a run (poses and map points in the local ENU world frame) map to
// the Earth, and the geo-referenced exports built on it (georef.json, WGS-84 and projected
// trajectory CSVs, GPS time of LAS points).
//
// The world frame is the local ENU frame of the run: x east, y north, z up, tangent to the WGS-84
// ellipsoid at the origin (GeodeticPoint: latitude, longitude, ellipsoidal height; the first valid
// GNSS fix). A point p_world goes to geodetic WGS-84 coordinates through GeographicLib's
// LocalCartesian (exact, no approximation), then to the output CRS through PROJ:
// proj_create_crs_to_crs from EPSG:4979 (WGS 84 geographic 3D) to the target, normalised for
// visualisation so that the axes are always (easting, northing). The output CRS is any projected
// CRS PROJ knows with metre axes east and north: "" picks WGS 84 / UTM of the origin's zone (EPSG
// 326zz north, 327zz south), "EPSG:25832" ETRS89 / UTM 32N, "EPSG:32632", ... Geographic,
// geocentric, compound or unknown CRSs are rejected with kInvalidArgument naming the string.
//
// Heights stay ellipsoidal (height above the WGS-84 ellipsoid, as the GNSS gives it): no geoid
// model is applied and no vertical CRS is attached (georef.json says so under "vertical"). For a
// target on another datum than WGS 84 (ETRS89, ...), PROJ's chosen operation is used as is; for
// WGS 84 -> ETRS89 that is a null transformation of 1 m accuracy (georef.json gives its name and
// accuracy): the ~0.8 m of plate motion since 1989 is not applied.
//
// Time: every output time is the library's Timestamp, integer nanoseconds since the Unix epoch in
// UTC (POSIX, leap seconds not counted), written as t_utc_ns; float seconds (t_s) are added where a
// format wants them (TUM keeps its float seconds). LAS GPS time is adjusted standard GPS time,
// GpsSecondsFromUtc(t) - 1e9.
//
// Ownership: move-only; each object owns its PROJ context and transformation (no global PROJ
// state). Thread safety: PROJ objects are not re-entrant, so one GeoReference must not be used by
// two threads at once; distinct objects may be used concurrently.

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "slam_mms/core/geodesy.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/core/trajectory.hpp"

namespace slam_mms {

/// Attitude of the body frame w.r.t. the local level frame at the body's own position (Applanix
/// SBET convention): z-y'-x'' Tait-Bryan angles of the body's forward-right-down axes (the
/// library's forward-left-up body frame with y and z negated) relative to north-east-down at that
/// point. heading clockwise from true north in [0, 360), pitch nose-up positive, roll
/// right-side-down positive.
struct LocalAttitude {
  double roll_deg = 0.0;
  double pitch_deg = 0.0;
  double heading_deg = 0.0;
};

class GeoReference {
 public:
  /// `crs`: "" (WGS 84 / UTM zone of the origin) or anything PROJ accepts for a projected CRS
  /// ("EPSG:25832", a WKT, ...). kInvalidArgument for a bad origin (non-finite, |lat| > 90, or
  /// outside UTM's -80..84 deg when crs is ""), an unknown CRS, or one that is not projected with
  /// east/north metre axes; the message names the CRS string and PROJ's reason.
  static StatusOr<GeoReference> Create(const GeodeticPoint& origin, const std::string& crs = "");
  /// Checks `crs` as Create would, before the origin is known (at the centre of the CRS's area of
  /// use): lets an app refuse a bad --crs before any processing. OK for "".
  [[nodiscard]] static Status CheckCrs(const std::string& crs);

  GeoReference(GeoReference&& other) noexcept;
  GeoReference& operator=(GeoReference&& other) noexcept;
  GeoReference(const GeoReference&) = delete;
  GeoReference& operator=(const GeoReference&) = delete;
  ~GeoReference();

  const GeodeticPoint& origin() const { return origin_; }
  /// The CRS string given to Create ("" for the default UTM).
  const std::string& crs_request() const { return crs_request_; }
  /// EPSG code of the output CRS; 0 where the CRS has none.
  int epsg() const { return epsg_; }
  /// PROJ's name of the output CRS ("WGS 84 / UTM zone 32N").
  const std::string& crs_name() const { return crs_name_; }
  /// OGC WKT1 (GDAL flavour, one line) of the output CRS, as LAS readers expect it.
  const std::string& wkt1() const { return wkt1_; }
  /// ISO 19162:2019 WKT2 of the output CRS (one line).
  const std::string& wkt2() const { return wkt2_; }
  /// Name and accuracy [m] (-1 unknown) of the WGS 84 -> CRS operation PROJ chose at the origin.
  const std::string& operation_name() const { return operation_name_; }
  double operation_accuracy_m() const { return operation_accuracy_m_; }

  /// p_world (ENU) -> WGS-84 geodetic (GeographicLib LocalCartesian, exact).
  GeodeticPoint EnuToGeodetic(const Eigen::Vector3d& p_world) const;
  /// WGS-84 geodetic -> p_world (ENU).
  Eigen::Vector3d GeodeticToEnu(const GeodeticPoint& g) const;
  /// Geodetic -> (easting, northing, ellipsoidal height) in the output CRS. kInvalidArgument
  /// naming the point when PROJ cannot transform it.
  StatusOr<Eigen::Vector3d> GeodeticToProjected(const GeodeticPoint& g) const;
  /// (easting, northing, height) -> geodetic (PROJ inverse).
  StatusOr<GeodeticPoint> ProjectedToGeodetic(const Eigen::Vector3d& enh) const;
  /// p_world -> (easting, northing, height).
  StatusOr<Eigen::Vector3d> EnuToProjected(const Eigen::Vector3d& p_world) const;
  /// Many points at once (one PROJ call); `out` gets points.size() rows.
  Status EnuToProjected(const std::vector<Eigen::Vector3d>& p_world,
                        std::vector<Eigen::Vector3d>* out) const;
  /// EnuToProjected for the points of a map, at a fraction of its cost: exact (as above) at the
  /// corners of the cubic cells of edge `cell_m` that hold points, trilinear inside a cell. The
  /// mapping's second derivatives are about 1 / (Earth radius), so a cell of 8 m leaves a few
  /// micrometres (measured: tests/io/georef_test.cpp); the LAS writer's choice, whose coordinates
  /// are kept to a millimetre. Errors as EnuToProjected's (a non-finite point names its index).
  Status EnuToProjectedInterpolated(const std::vector<Eigen::Vector3d>& p_world,
                                    std::vector<Eigen::Vector3d>* out, double cell_m = 8.0) const;
  /// (easting, northing, height) -> p_world.
  StatusOr<Eigen::Vector3d> ProjectedToEnu(const Eigen::Vector3d& enh) const;

  /// R_world_level: the rotation from the local ENU frame at `g` to the world ENU frame (the
  /// two differ by the meridian convergence and the curvature of the Earth).
  Eigen::Matrix3d R_world_level(const GeodeticPoint& g) const;
  /// Angle of true north measured clockwise from grid north at `g` [deg], from PROJ on two points
  /// 1e-6 deg apart: grid heading = true heading + this angle.
  StatusOr<double> TrueNorthFromGridNorthDeg(const GeodeticPoint& g) const;

 private:
  GeoReference() = default;
  struct Proj;
  GeodeticPoint origin_;
  std::string crs_request_;
  int epsg_ = 0;
  std::string crs_name_, wkt1_, wkt2_, operation_name_;
  double operation_accuracy_m_ = -1.0;
  std::unique_ptr<Proj> proj_;
};

/// Attitude of T_world_body at its own position (see LocalAttitude).
LocalAttitude LocalAttitudeOf(const GeoReference& geo, const Eigen::Isometry3d& T_world_body);

/// GPS minus UTC [s] at `utc` (leap seconds): 0 from 1980-01-06, ..., 15 from 2009-01-01, 16 from
/// 2012-07-01, 17 from 2015-07-01, 18 from 2017-01-01 (IERS Bulletin C; no leap second announced
/// through 2026, so later times also get 18). kOutOfRange before the GPS epoch 1980-01-06.
StatusOr<int> GpsMinusUtcSeconds(Timestamp utc);
/// Seconds since the GPS epoch (1980-01-06 00:00:00 UTC) of `utc`, leap seconds included.
StatusOr<double> GpsSecondsFromUtc(Timestamp utc);
/// Adjusted standard GPS time (LAS, global encoding bit 0): GpsSecondsFromUtc(utc) - 1e9.
StatusOr<double> AdjustedGpsTimeFromUtc(Timestamp utc);

/// georef.json as text (nlohmann-json, indented): origin, ENU definition, CRS (EPSG code, name,
/// WKT1 and WKT2, operation), vertical datum, units and the time convention of the outputs.
StatusOr<std::string> GeoReferenceJson(const GeoReference& geo);
/// Writes GeoReferenceJson to `file` (kUnavailable naming it when it cannot be written).
[[nodiscard]] Status WriteGeorefJson(const GeoReference& geo, const std::filesystem::path& file);

/// <method>_wgs84.csv (SBET-export style), header line then one row per pose:
///   t_utc_ns,t_s,lat_deg,lon_deg,h_ellipsoid_m,roll_deg,pitch_deg,heading_deg,
///   sigma_east_m,sigma_north_m,sigma_up_m,sigma_roll_deg,sigma_pitch_deg,sigma_heading_deg
/// t_s = t_utc_ns * 1e-9 (convenience; t_utc_ns is exact); attitude as LocalAttitude; sigmas from
/// the pose covariance (first order, position sigmas in the local ENU frame at the pose), empty
/// cells where the pose has no covariance. Latitude and longitude with 10 decimals (~10 um).
[[nodiscard]] Status WriteTrajectoryWgs84Csv(const Trajectory& trajectory, const GeoReference& geo,
                                             const std::filesystem::path& file);
/// <method>_utm.csv / <method>_epsg<code>.csv: the same rows in the output CRS:
///   t_utc_ns,t_s,easting_m,northing_m,h_m,roll_deg,pitch_deg,grid_heading_deg,
///   sigma_easting_m,sigma_northing_m,sigma_up_m,sigma_roll_deg,sigma_pitch_deg,sigma_heading_deg
/// grid_heading_deg: clockwise from grid north (true heading + TrueNorthFromGridNorthDeg); h_m
/// is the ellipsoidal height; sigma_easting/northing rotated into grid axes.
[[nodiscard]] Status WriteTrajectoryProjectedCsv(const Trajectory& trajectory,
                                                 const GeoReference& geo,
                                                 const std::filesystem::path& file);

}  // namespace slam_mms
