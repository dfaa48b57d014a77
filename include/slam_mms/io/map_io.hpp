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
// LAS: version 1.4, point data record format 6 (30 bytes), scale 0.001 m, in the output CRS of a
// GeoReference (georef.hpp: ENU -> WGS-84 by GeographicLib LocalCartesian, exact, then PROJ to
// WGS 84 / UTM of the origin's zone by default or any projected CRS, e.g. EPSG:25832). X, Y are
// easting and northing; Z is the height above the WGS-84 ellipsoid (no geoid, no vertical CRS).
// The CRS is PROJ's OGC WKT1 (GDAL flavour) in a LASF_Projection VLR (record 2112) with the
// header's WKT global-encoding bit 4 set, as LAS 1.4 requires for format 6. Per point:
//  - intensity: [0, 1] -> 0..65535 (clamped); return 1 of 1;
//  - GPS time: adjusted standard GPS time (GPS seconds since 1980-01-06 - 1e9; global encoding
//    bit 0 set) of MapCloud::time_ns (UTC) plus the leap seconds of that date
//    (AdjustedGpsTimeFromUtc); 0 where the map has no times;
//  - point source ID: MapCloud::source_id (the run's map: the index of the scan the point was
//    first observed in, modulo 65536), else LasWriteOptions::point_source_id (e.g. a drive number);
//  - classification: MapCloud::classification, else 0 "created, never classified" (the map is not
//    classified); user data 0; scan angle 0; no synthetic/key-point/withheld flags.
// Points are written in order of their GPS time (stable) when the map has times, so the GPS time
// of the points of each scan (each point source ID) increases through the file.
// Tiles (WriteLasTiles): square cells of the output CRS, file tile_<E>_<N>.las named by the
// cell's lower-left corner (metres), each a complete LAS file as above, plus index.json listing
// them; every point is in exactly one tile (cell = floor(easting / size), floor(northing / size)).
//
// Thread safety: pure functions; distinct files may be written concurrently.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/io/georef.hpp"

namespace slam_mms {

/// A map: points (local ENU or any frame) with intensity and optional normals, times, source IDs
/// and classes (PLY and PCD store points, intensities and normals only; LAS all but normals).
struct MapCloud {
  PointCloud cloud;
  std::vector<Eigen::Vector3f> normals;  ///< Empty, or cloud.size() unit normals.
  /// Empty, or cloud.size() absolute times [ns since the Unix epoch, UTC] of each point.
  std::vector<int64_t> time_ns;
  /// Empty, or cloud.size() LAS point source IDs (the run's map: scan index modulo 65536).
  std::vector<uint16_t> source_id;
  /// Empty, or cloud.size() ASPRS classes (0..31 in format 6: 0 never classified, 2 ground, ...).
  std::vector<uint8_t> classification;

  bool has_normals() const { return !normals.empty(); }
  /// kInvalidArgument when normals, time_ns, source_id or classification is neither empty nor of
  /// cloud.size().
  [[nodiscard]] Status Validate() const;
};

[[nodiscard]] Status WritePly(const MapCloud& map, const std::filesystem::path& file);
[[nodiscard]] StatusOr<MapCloud> ReadPly(const std::filesystem::path& file);

[[nodiscard]] Status WritePcd(const MapCloud& map, const std::filesystem::path& file);
[[nodiscard]] StatusOr<MapCloud> ReadPcd(const std::filesystem::path& file);

struct LasWriteOptions {
  /// Coordinate resolution [m] (LAS scale of x, y, z); must be > 0.
  double scale_m = 0.001;
  /// Only for WriteLas(map, GeodeticPoint, ...): the output CRS ("" = WGS 84 / UTM of the origin's
  /// zone; "EPSG:25832", ...; see GeoReference::Create). Overrides utm_zone when not empty.
  std::string crs;
  /// Only for WriteLas(map, GeodeticPoint, ...) with crs "": a UTM zone 1..60 to force (WGS 84 /
  /// UTM, EPSG 326zz/327zz); 0 = the zone of the origin.
  int utm_zone = 0;
  /// Hemisphere when utm_zone is forced (ignored otherwise: taken from the origin's latitude).
  bool north = true;
  /// Point source ID of every point when MapCloud::source_id is empty (e.g. a drive number).
  uint16_t point_source_id = 0;
  /// Write the points in order of their GPS time when the map has times (see above).
  bool sort_by_time = true;
  /// Written into the header's "generating software".
  std::string generating_software = "slam_mms";

  [[nodiscard]] Status Validate() const;
};

/// Writes `map` (points in the world ENU frame of `geo`) as a LAS 1.4 file in geo's output CRS.
/// Normals are not stored. kInvalidArgument for a non-finite point, a point PROJ cannot transform,
/// a map spanning more than int32 * scale, or inconsistent MapCloud arrays; kOutOfRange for a time
/// before 1980-01-06.
[[nodiscard]] Status WriteLas(const MapCloud& map, const GeoReference& geo,
                              const std::filesystem::path& file, const LasWriteOptions& options);
/// The same with a GeoReference built from `origin` and options.crs / options.utm_zone.
[[nodiscard]] Status WriteLas(const MapCloud& map, const GeodeticPoint& origin,
                              const std::filesystem::path& file, const LasWriteOptions& options);
[[nodiscard]] Status WriteLas(const MapCloud& map, const GeodeticPoint& origin,
                              const std::filesystem::path& file);

/// One tile written by WriteLasTiles.
struct LasTile {
  std::string file;          ///< File name inside the folder ("tile_458800_5429000.las").
  int64_t column = 0;        ///< floor(easting / tile_size_m).
  int64_t row = 0;           ///< floor(northing / tile_size_m).
  double min_easting_m = 0;  ///< Lower-left corner of the cell.
  double min_northing_m = 0;
  size_t num_points = 0;
};

/// Writes `map` as square tiles of `tile_size_m` (> 0) in geo's output CRS into `folder` (created
/// if missing): tile_<E>_<N>.las (E, N: the cell's lower-left corner in metres, %.0f, or %.3f for
/// a size that is not a whole number of metres) and index.json (CRS, tile size, and per tile the
/// file, cell, corner, bounds and point count). Returns the tiles in file order (row-major from
/// the south-west). Errors as WriteLas, naming the tile.
[[nodiscard]] StatusOr<std::vector<LasTile>> WriteLasTiles(const MapCloud& map,
                                                           const GeoReference& geo,
                                                           const std::filesystem::path& folder,
                                                           double tile_size_m,
                                                           const LasWriteOptions& options);

/// What ReadLas returns: projected coordinates as stored (scaled and offset applied).
struct LasCloud {
  std::vector<Eigen::Vector3d> points_utm;  ///< easting, northing, height [m] (any CRS).
  std::vector<uint16_t> intensities;
  std::vector<double> gps_time;           ///< Per point (formats 1, 3, 6-8); empty otherwise.
  std::vector<uint16_t> point_source_id;  ///< Per point.
  std::vector<uint8_t> classification;    ///< Per point (5 bits in formats 0-3, 8 in 6-8).
  std::vector<uint8_t> user_data;         ///< Per point.
  std::string wkt;                        ///< From the LASF_Projection 2112 (E)VLR; "" where none.
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

/// PROJ's OGC WKT1 (GDAL flavour) of "WGS 84 / UTM zone <zone><N|S>" (EPSG 326zz / 327zz); ""
/// for a zone outside 1..60. Kept for existing callers; GeoReference::wkt1() is the general form.
std::string UtmZoneWkt(int zone, bool north);

}  // namespace slam_mms
