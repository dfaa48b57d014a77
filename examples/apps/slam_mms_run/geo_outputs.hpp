#pragma once
// Geo-referenced outputs of slam_mms_run (issue 22): georef.json once per run, and per method the
// WGS-84 and projected trajectory CSVs and the LAS map (one file or tiles), through the library's
// slam_mms/drive/georeferenced_outputs.hpp (the Python package writes the same files with it).

#include <filesystem>
#include <string>

#include "slam_mms/core/status.hpp"
#include "slam_mms/drive/georeferenced_outputs.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms_run/run_mode.hpp"

namespace slam_mms::app {

using slam_mms::GeoOutputOptions;

/// GeoOutputOptions::Validate(): --crs / --las-tile-size checked before any processing.
[[nodiscard]] Status CheckGeoOutputOptions(const GeoOutputOptions& opt);

/// Writes out_dir/georef.json for `origin` (once per run: the origin of the first method that has
/// one); RunGeorefJson(origin, opt) gives the same text for report.json's "georef".
[[nodiscard]] Status WriteRunGeoref(const GeodeticPoint& origin, const GeoOutputOptions& opt,
                                    const std::filesystem::path& out_dir);

/// Per method: <name>_wgs84.csv, <name>_utm.csv | <name>_epsg<code>.csv, map_<name>.las or
/// map_<name>_tiles/ (see WriteGeoreferencedOutputs). `map_stamps`: the run's
/// DriveRun::map_stamps (one per point of run.map), for the LAS GPS time and point source ID.
Status WriteGeoOutputs(const ModeRun& run, const GeoOutputOptions& opt,
                       const std::filesystem::path& out_dir,
                       const MapPointStamps& map_stamps = MapPointStamps());

}  // namespace slam_mms::app
