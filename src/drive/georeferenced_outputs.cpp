#include "slam_mms/drive/georeferenced_outputs.hpp"

#include <cmath>
#include <vector>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/io/georef.hpp"
#include "slam_mms/io/map_io.hpp"

namespace slam_mms {
namespace {

void KeepFirst(Status* first, const Status& s) {
  if (!s.ok()) {
    SLAM_MMS_LOG(kError) << s.ToString();
    if (first->ok()) *first = s;
  }
}

bool SameOrigin(const GeodeticPoint& a, const GeodeticPoint& b) {
  return a.latitude_deg == b.latitude_deg && a.longitude_deg == b.longitude_deg &&
         a.height_m == b.height_m;
}

std::string ProjectedCsvName(const std::string& method, const GeoOutputOptions& options,
                             const GeoReference& geo) {
  if (options.crs.empty()) return method + "_utm.csv";
  if (geo.epsg() > 0) return method + "_epsg" + std::to_string(geo.epsg()) + ".csv";
  return method + "_projected.csv";
}

}  // namespace

Status GeoOutputOptions::Validate() const {
  if (!(las_tile_size_m >= 0.0) || !std::isfinite(las_tile_size_m)) {
    return InvalidArgumentError("--las-tile-size " + std::to_string(las_tile_size_m) +
                                ": must be >= 0 (0 = one LAS file)");
  }
  return GeoReference::CheckCrs(crs).WithContext("--crs");
}

StatusOr<std::string> RunGeorefJson(const GeodeticPoint& origin, const GeoOutputOptions& options) {
  SLAM_MMS_ASSIGN_OR_RETURN(const GeoReference geo, GeoReference::Create(origin, options.crs));
  return GeoReferenceJson(geo);
}

Status WriteRunGeorefJson(const GeodeticPoint& origin, const GeoOutputOptions& options,
                          const std::filesystem::path& out_dir) {
  SLAM_MMS_ASSIGN_OR_RETURN(const GeoReference geo, GeoReference::Create(origin, options.crs));
  return WriteGeorefJson(geo, out_dir / "georef.json");
}

Status WriteGeoreferencedOutputs(const std::string& method, MappingMode mode,
                                 const Trajectory& trajectory, const PointCloud& map,
                                 const MapPointStamps& map_stamps,
                                 const std::optional<GeodeticPoint>& origin,
                                 const GeoOutputOptions& options,
                                 const std::filesystem::path& out_dir) {
  if (!origin) {
    SLAM_MMS_LOG(kWarning) << method
                           << ": world origin unknown, no WGS-84/projected CSV and no LAS written";
    return OkStatus();
  }
  StatusOr<GeoReference> created = GeoReference::Create(*origin, options.crs);
  if (!created.ok()) return created.status().WithContext(method);
  const GeoReference& geo = *created;
  Status first;
  if (options.run_origin && !SameOrigin(*options.run_origin, *origin)) {
    SLAM_MMS_LOG(kWarning) << method << ": world origin differs from georef.json's; its own is in "
                           << "georef_" << method << ".json";
    KeepFirst(&first, WriteGeorefJson(geo, out_dir / ("georef_" + method + ".json")));
  }
  if (!trajectory.empty()) {
    KeepFirst(&first, WriteTrajectoryWgs84Csv(trajectory, geo, out_dir / (method + "_wgs84.csv")));
    KeepFirst(&first, WriteTrajectoryProjectedCsv(
                          trajectory, geo, out_dir / ProjectedCsvName(method, options, geo)));
  }
  if (mode == MappingMode::kLidarOnly || map.empty()) return first;
  MapCloud cloud;
  cloud.cloud = map;
  if (map_stamps.size() == map.size() && map_stamps.scan_index.size() == map.size()) {
    cloud.time_ns = map_stamps.time_ns;
    cloud.source_id.reserve(map.size());
    for (const int64_t k : map_stamps.scan_index) {
      cloud.source_id.push_back(static_cast<uint16_t>(static_cast<uint64_t>(k) & 0xffff));
    }
  } else {
    SLAM_MMS_LOG(kWarning) << method << ": the map has no per-point times, LAS GPS time is 0";
  }
  const LasWriteOptions las;
  const std::string base = "map_" + method;
  if (options.las_tile_size_m > 0.0) {
    KeepFirst(&first,
              WriteLasTiles(cloud, geo, out_dir / (base + "_tiles"), options.las_tile_size_m, las)
                  .status());
  } else {
    KeepFirst(&first, WriteLas(cloud, geo, out_dir / (base + ".las"), las));
  }
  return first;
}

}  // namespace slam_mms
