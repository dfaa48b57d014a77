#pragma once
// The geo-referenced files of one method's run (slam_mms_run and `python -m slam_mms run` write
// them through this one function, so both give the same bytes): <method>_wgs84.csv, the projected
// CSV (<method>_utm.csv by default, <method>_epsg<code>.csv with a CRS given) and the LAS map
// (map_<method>.las, or map_<method>_tiles/ with a tile size), plus georef.json once per run
// (WriteRunGeorefJson). Conventions: slam_mms/io/georef.hpp and docs/user_guide.md
// "Georeferencing of the outputs".
//
// Thread safety: free functions; distinct output folders may be written concurrently.

#include <filesystem>
#include <optional>
#include <string>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/pipeline/localization_result.hpp"
#include "slam_mms/pipeline/map_point_stamps.hpp"

namespace slam_mms {

struct GeoOutputOptions {
  /// Output CRS: "" = WGS 84 / UTM of the origin's zone (<method>_utm.csv), else any projected
  /// CRS PROJ knows ("EPSG:25832": <method>_epsg25832.csv; without an EPSG code
  /// <method>_projected.csv).
  std::string crs;
  /// > 0: the LAS map as square tiles of this size [m] (map_<method>_tiles/); 0: one file.
  double las_tile_size_m = 0.0;
  /// The origin georef.json was written for; a method whose own origin differs also gets
  /// georef_<method>.json (its ENU files are in its own frame). Unset: no check.
  std::optional<GeodeticPoint> run_origin;

  /// kInvalidArgument naming --crs / --las-tile-size (a geographic, unknown or non-metre CRS; a
  /// negative or non-finite tile size): call before any processing.
  [[nodiscard]] Status Validate() const;
};

/// georef.json's text for `origin` and options.crs (also report.json's "georef" object).
StatusOr<std::string> RunGeorefJson(const GeodeticPoint& origin, const GeoOutputOptions& options);
/// Writes out_dir/georef.json.
[[nodiscard]] Status WriteRunGeorefJson(const GeodeticPoint& origin,
                                        const GeoOutputOptions& options,
                                        const std::filesystem::path& out_dir);

/// One method's geo-referenced files into out_dir: the two trajectory CSVs when `trajectory` has
/// poses; the LAS map (file or tiles) for the modes with a map (not kLidarOnly) when `map` has
/// points, with GPS time and point source ID (scan index mod 65536) from `map_stamps` when it has
/// one per point (else 0, with a warning). Without `origin` nothing is written (a warning).
/// Returns the first failure; every file is attempted.
Status WriteGeoreferencedOutputs(const std::string& method, MappingMode mode,
                                 const Trajectory& trajectory, const PointCloud& map,
                                 const MapPointStamps& map_stamps,
                                 const std::optional<GeodeticPoint>& origin,
                                 const GeoOutputOptions& options,
                                 const std::filesystem::path& out_dir);

}  // namespace slam_mms
