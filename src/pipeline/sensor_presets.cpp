#include "slam_mms/pipeline/sensor_presets.hpp"

namespace slam_mms {
namespace {

struct Geometry {
  LidarPreset preset;
  const char* name;
  int beams;
  double top_beam_deg;     // elevation of the highest beam
  double bottom_beam_deg;  // elevation of the lowest beam
};

// The data sheets' beam layouts (sensor_presets.hpp). hdl64e is not built from its beams: it is
// SuMa's KITTI image (the library's default), +3 / -25 deg.
constexpr Geometry kGeometries[] = {
    {LidarPreset::kHdl64e, "hdl64e", 64, 0.0, 0.0},
    {LidarPreset::kHdl32e, "hdl32e", 32, 10.67, -30.67},
    {LidarPreset::kVlp16, "vlp16", 16, 15.0, -15.0},
    {LidarPreset::kOs1_64, "os1_64", 64, 16.6, -16.6},
};

const Geometry& Find(LidarPreset preset) {
  for (const Geometry& g : kGeometries) {
    if (g.preset == preset) return g;
  }
  return kGeometries[0];
}

}  // namespace

const char* LidarPresetName(LidarPreset preset) { return Find(preset).name; }

std::vector<LidarPreset> AllLidarPresets() {
  std::vector<LidarPreset> out;
  for (const Geometry& g : kGeometries) out.push_back(g.preset);
  return out;
}

StatusOr<LidarPreset> ParseLidarPreset(std::string_view name) {
  std::string names;
  for (const Geometry& g : kGeometries) {
    if (name == g.name) return g.preset;
    names += names.empty() ? "" : ", ";
    names += g.name;
  }
  return InvalidArgumentError("preset = '" + std::string(name) + "'; must be one of " + names);
}

void ApplyLidarPreset(LidarPreset preset, MappingSystem::Options* options) {
  RangeProjectionOptions& p = options->localizer.surfels.renderer.projection;
  const RangeProjectionOptions defaults = DefaultLevel1SurfelOptions().renderer.projection;
  p.cols = defaults.cols;
  if (preset == LidarPreset::kHdl64e) {
    p.rows = defaults.rows;
    p.fov_up_deg = defaults.fov_up_deg;
    p.fov_down_deg = defaults.fov_down_deg;
    return;
  }
  const Geometry& g = Find(preset);
  // One row per beam: the edges half a beam spacing beyond the outermost beams.
  const double half_spacing = 0.5 * (g.top_beam_deg - g.bottom_beam_deg) / (g.beams - 1);
  p.rows = g.beams;
  p.fov_up_deg = g.top_beam_deg + half_spacing;
  p.fov_down_deg = g.bottom_beam_deg - half_spacing;
}

}  // namespace slam_mms
