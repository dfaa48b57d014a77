#pragma once
// Geo-referenced outputs of slam_mms_run (issue 22): georef.json once per run, and per method the
// WGS-84 and projected trajectory CSVs and the LAS map (one file or tiles), all through one
// slam_mms::GeoReference (GeographicLib + PROJ; see slam_mms/io/georef.hpp and docs/user_guide.md).

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/pipeline/map_point_stamps.hpp"
#include "slam_mms_run/run_mode.hpp"

namespace slam_mms::app {

struct GeoOutputOptions {
  /// --crs: "" = WGS 84 / UTM of the origin's zone (files <method>_utm.csv), else any projected
  /// CRS PROJ knows (files <method>_epsg<code>.csv, or <method>_projected.csv without a code).
  std::string crs;
  /// --las-tile-size M: > 0 writes map_<method>_tiles/tile_<E>_<N>.las + index.json instead of
  /// map_<method>.las.
  double las_tile_size_m = 0.0;
  /// The origin georef.json was written for (WriteRunGeoref); a method whose own origin differs
  /// also gets georef_<method>.json (its ENU outputs are in its own frame).
  std::optional<GeodeticPoint> run_origin;
};

/// kInvalidArgument naming the CRS when opt.crs is unusable (geographic, unknown, not metres...)
/// or las_tile_size_m < 0: call before any processing (exit 2 in main).
[[nodiscard]] Status CheckGeoOutputOptions(const GeoOutputOptions& opt);

/// The georef.json text of `origin` (the same object goes into report.json under "georef").
StatusOr<std::string> RunGeorefJson(const GeodeticPoint& origin, const GeoOutputOptions& opt);

/// Writes out_dir/georef.json for `origin` (once per run, the origin of the first method that
/// has one).
[[nodiscard]] Status WriteRunGeoref(const GeodeticPoint& origin, const GeoOutputOptions& opt,
                                    const std::filesystem::path& out_dir);

/// Per method: <name>_wgs84.csv and the projected CSV (when it has poses), map_<name>.las or its
/// tiles (full, gnss_ins, gnss_ins_smoothed with a map). `map_stamps`: empty or one per point of
/// run.map (DriveRun::map_stamps: each map point's first-observation time and scan, written as
/// the LAS GPS time and point source ID = scan index mod 65536; empty: GPS time 0, source ID 0,
/// with a warning). A run without origin writes nothing and warns. Returns the first failure
/// (all files are attempted).
Status WriteGeoOutputs(const ModeRun& run, const GeoOutputOptions& opt,
                       const std::filesystem::path& out_dir,
                       const MapPointStamps& map_stamps = MapPointStamps());

}  // namespace slam_mms::app
