#include "slam_mms_run/geo_outputs.hpp"

namespace slam_mms::app {

Status CheckGeoOutputOptions(const GeoOutputOptions& opt) { return opt.Validate(); }

Status WriteRunGeoref(const GeodeticPoint& origin, const GeoOutputOptions& opt,
                      const std::filesystem::path& out_dir) {
  return WriteRunGeorefJson(origin, opt, out_dir);
}

Status WriteGeoOutputs(const ModeRun& run, const GeoOutputOptions& opt,
                       const std::filesystem::path& out_dir, const MapPointStamps& map_stamps) {
  return WriteGeoreferencedOutputs(run.name, run.mode, run.trajectory, run.map, map_stamps,
                                   run.origin, opt, out_dir);
}

}  // namespace slam_mms::app
