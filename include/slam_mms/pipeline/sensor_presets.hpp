#pragma once
// Sensor presets: the range-image geometry of common spinning LiDARs, so that a user names the
// sensor instead of setting localizer.surfels.renderer.projection.* by hand (slam_mms_run
// --preset NAME, config key `preset`).
//
// A preset sets only the image geometry (rows = beams, the elevation edges half a beam spacing
// beyond the outermost beams, and 1024 azimuth bins as the default HDL-64E image); every other
// option keeps its value. Beam layouts are the manufacturers' data sheets:
//   hdl64e  Velodyne HDL-64E (KITTI): the default; SuMa's +3 / -25 deg edges around the sensor's
//           +2 .. -24.8 deg beams.
//   hdl32e  Velodyne HDL-32E: 32 beams, +10.67 .. -30.67 deg, 1.33 deg apart.
//   vlp16   Velodyne VLP-16 (Puck): 16 beams, +15 .. -15 deg, 2 deg apart.
//   os1_64  Ouster OS1-64 (gen 1): 64 beams over 33.2 deg (+16.6 .. -16.6 deg), 0.53 deg apart.
// Validated on data: hdl64e only (KITTI raw and the simulator, docs/results.md). The others are
// the geometry only: the level-1 defaults (SuMa's, tuned for 64 beams) were not measured on
// their sparser images.
//
// Thread safety: pure functions.

#include <string>
#include <string_view>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"

namespace slam_mms {

enum class LidarPreset { kHdl64e, kHdl32e, kVlp16, kOs1_64 };

/// "hdl64e", "hdl32e", "vlp16", "os1_64".
const char* LidarPresetName(LidarPreset preset);
/// Every preset, in the order above.
std::vector<LidarPreset> AllLidarPresets();
/// The preset of a name above; InvalidArgument listing the names for anything else.
StatusOr<LidarPreset> ParseLidarPreset(std::string_view name);
/// Sets the preset's image geometry in `options` (localizer.surfels.renderer.projection).
void ApplyLidarPreset(LidarPreset preset, MappingSystem::Options* options);

}  // namespace slam_mms
