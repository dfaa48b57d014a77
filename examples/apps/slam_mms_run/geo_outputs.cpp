#include "slam_mms_run/geo_outputs.hpp"

#include <cmath>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/io/georef.hpp"
#include "slam_mms/io/map_io.hpp"

namespace slam_mms::app {
namespace {

void KeepFirst(Status* first, const Status& s) {
  if (!s.ok()) {
    SLAM_MMS_LOG(kError) << s.ToString();
    if (first->ok()) *first = s;
  }
}

GeoOrigin ToGeoOrigin(const GeodeticPoint& p) {
  return GeoOrigin{p.latitude_deg, p.longitude_deg, p.height_m};
}

bool SameOrigin(const GeodeticPoint& a, const GeodeticPoint& b) {
  return a.latitude_deg == b.latitude_deg && a.longitude_deg == b.longitude_deg &&
         a.height_m == b.height_m;
}

std::string ProjectedCsvName(const std::string& method, const GeoOutputOptions& opt,
                             const GeoReference& geo) {
  if (opt.crs.empty()) return method + "_utm.csv";
  if (geo.epsg() > 0) return method + "_epsg" + std::to_string(geo.epsg()) + ".csv";
  return method + "_projected.csv";
}

}  // namespace

Status CheckGeoOutputOptions(const GeoOutputOptions& opt) {
  if (!(opt.las_tile_size_m >= 0.0) || !std::isfinite(opt.las_tile_size_m)) {
    return InvalidArgumentError("--las-tile-size " + std::to_string(opt.las_tile_size_m) +
                                ": must be >= 0 (0 = one LAS file)");
  }
  return GeoReference::CheckCrs(opt.crs).WithContext("--crs");
}

StatusOr<std::string> RunGeorefJson(const GeodeticPoint& origin, const GeoOutputOptions& opt) {
  SLAM_MMS_ASSIGN_OR_RETURN(const GeoReference geo,
                            GeoReference::Create(ToGeoOrigin(origin), opt.crs));
  return GeoReferenceJson(geo);
}

Status WriteRunGeoref(const GeodeticPoint& origin, const GeoOutputOptions& opt,
                      const std::filesystem::path& out_dir) {
  SLAM_MMS_ASSIGN_OR_RETURN(const GeoReference geo,
                            GeoReference::Create(ToGeoOrigin(origin), opt.crs));
  return WriteGeorefJson(geo, out_dir / "georef.json");
}

Status WriteGeoOutputs(const ModeRun& run, const GeoOutputOptions& opt,
                       const std::filesystem::path& out_dir, const MapPointStamps& map_stamps) {
  if (!run.origin) {
    SLAM_MMS_LOG(kWarning) << run.name
                           << ": world origin unknown, no WGS-84/projected CSV and no LAS written";
    return OkStatus();
  }
  StatusOr<GeoReference> created = GeoReference::Create(ToGeoOrigin(*run.origin), opt.crs);
  if (!created.ok()) return created.status().WithContext(run.name);
  const GeoReference& geo = *created;
  Status first;
  if (opt.run_origin && !SameOrigin(*opt.run_origin, *run.origin)) {
    SLAM_MMS_LOG(kWarning) << run.name
                           << ": world origin differs from georef.json's; its own is in "
                           << "georef_" << run.name << ".json";
    KeepFirst(&first, WriteGeorefJson(geo, out_dir / ("georef_" + run.name + ".json")));
  }
  if (!run.trajectory.empty()) {
    KeepFirst(&first,
              WriteTrajectoryWgs84Csv(run.trajectory, geo, out_dir / (run.name + "_wgs84.csv")));
    KeepFirst(&first, WriteTrajectoryProjectedCsv(run.trajectory, geo,
                                                  out_dir / ProjectedCsvName(run.name, opt, geo)));
  }
  const bool map_wanted = run.mode != MappingMode::kLidarOnly;
  if (map_wanted && !run.map.empty()) {
    MapCloud map;
    map.cloud = run.map;
    if (map_stamps.size() == run.map.size() && map_stamps.scan_index.size() == run.map.size()) {
      map.time_ns = map_stamps.time_ns;
      map.source_id.reserve(map.time_ns.size());
      for (const int64_t k : map_stamps.scan_index) {
        map.source_id.push_back(static_cast<uint16_t>(static_cast<uint64_t>(k) & 0xffff));
      }
    }
    if (map.time_ns.empty()) {
      SLAM_MMS_LOG(kWarning) << run.name << ": the map has no per-point times, LAS GPS time is 0";
    }
    LasWriteOptions las;
    const std::string base = "map_" + run.name;
    if (opt.las_tile_size_m > 0.0) {
      StatusOr<std::vector<LasTile>> tiles =
          WriteLasTiles(map, geo, out_dir / (base + "_tiles"), opt.las_tile_size_m, las);
      KeepFirst(&first, tiles.status());
    } else {
      KeepFirst(&first, WriteLas(map, geo, out_dir / (base + ".las"), las));
    }
  }
  return first;
}

}  // namespace slam_mms::app
