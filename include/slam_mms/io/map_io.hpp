#pragma once
// Map files: binary PLY and PCD (x y z intensity, optional normals), their readers, and LAS 1.4
// geo-referenced in UTM.
//
// MapCloud is the map type of these files: a PointCloud (positions in the local ENU world frame,
// intensities; per-point time offsets are not stored) plus optional unit normals (empty, or one per
// point). PLY properties: float x y z intensity [nx ny nz]; PCD fields: x y z intensity
// [normal_x normal_y normal_z], DATA binary.
// Readers accept binary_little_endian and ascii PLY (float/double/int/uchar/... properties; a
// missing intensity reads as 0; extra properties are skipped) and ascii/binary PCD
// (binary_compressed: kUnimplemented).
//
// LAS: version 1.4, point data record format 6 (x y z int32, intensity uint16, return 1 of 1,
// GPS time = 0), scale 0.001 m. Points given in local ENU about a WGS-84 origin are converted
// through GeographicLib LocalCartesian (exact) to geodetic, then to UTM easting/northing (UTMUPS,
// the zone of the origin unless forced); Z is the height above the ellipsoid in the same datum as
// the origin's height. The CRS is stored as OGC WKT of "WGS 84 / UTM zone <n><N|S>" (EPSG
// 326nn/327nn) in a LASF_Projection VLR (record 2112) with the header's WKT global-encoding bit
// set, as LAS 1.4 requires for format 6, so CloudCompare/PDAL place the cloud. Intensities in [0,
// 1] map to 0..65535 (clamped).
//
// Thread safety: pure functions; distinct files may be written concurrently.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms {

/// A map: points (local ENU or any frame) with intensity and optional normals.
struct MapCloud {
  PointCloud cloud;
  std::vector<Eigen::Vector3f> normals;  ///< Empty, or cloud.size() unit normals.

  bool has_normals() const { return !normals.empty(); }
  /// kInvalidArgument when normals is neither empty nor of cloud.size().
  [[nodiscard]] Status Validate() const;
};

[[nodiscard]] Status WritePly(const MapCloud& map, const std::filesystem::path& file);
[[nodiscard]] StatusOr<MapCloud> ReadPly(const std::filesystem::path& file);

[[nodiscard]] Status WritePcd(const MapCloud& map, const std::filesystem::path& file);
[[nodiscard]] StatusOr<MapCloud> ReadPcd(const std::filesystem::path& file);

/// WGS-84 origin of the local ENU world frame.
struct GeoOrigin {
  double latitude_deg = 0.0;
  double longitude_deg = 0.0;
  double height_m = 0.0;
};

struct LasWriteOptions {
  /// Coordinate resolution [m] (LAS scale of x, y, z); must be > 0.
  double scale_m = 0.001;
  /// UTM zone 1..60 to force; 0 = the zone of the origin (GeographicLib UTMUPS::StandardZone).
  int utm_zone = 0;
  /// Hemisphere when utm_zone is forced (ignored otherwise: taken from the origin's latitude).
  bool north = true;
  /// Written into the header's "generating software".
  std::string generating_software = "slam_mms";

  [[nodiscard]] Status Validate() const;
};

/// Writes `map` (points in local ENU about `origin`) as a LAS 1.4 file in UTM. Normals are not
/// stored. kInvalidArgument for an origin outside UTM's latitude band (-80..84 deg).
[[nodiscard]] Status WriteLas(const MapCloud& map, const GeoOrigin& origin,
                              const std::filesystem::path& file, const LasWriteOptions& options);
[[nodiscard]] Status WriteLas(const MapCloud& map, const GeoOrigin& origin,
                              const std::filesystem::path& file);

/// What ReadLas returns: UTM coordinates as stored (scaled and offset applied).
struct LasCloud {
  std::vector<Eigen::Vector3d> points_utm;  ///< easting, northing, height [m].
  std::vector<uint16_t> intensities;
  std::string wkt;  ///< From the LASF_Projection 2112 (E)VLR; "" where none.
  Eigen::Vector3d scale = Eigen::Vector3d::Zero();
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  Eigen::Vector3d min = Eigen::Vector3d::Zero();  ///< Header bounds.
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
  int version_major = 0;
  int version_minor = 0;
  int point_format = -1;
  uint16_t global_encoding = 0;
};

/// Reads LAS 1.2-1.4 files with point formats 0-3 and 6-8 (uncompressed); enough for round trips.
[[nodiscard]] StatusOr<LasCloud> ReadLas(const std::filesystem::path& file);

/// OGC WKT (WKT1) of "WGS 84 / UTM zone <zone><N|S>" with its EPSG authority (326zz / 327zz).
std::string UtmZoneWkt(int zone, bool north);

}  // namespace slam_mms
