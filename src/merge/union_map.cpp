#include "slam_mms/merge/union_map.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/option_error.hpp"
#include "core/voxel_grid.hpp"
#include "slam_mms/core/voxel_downsample.hpp"
#include "slam_mms/merge/drive_result_io.hpp"

namespace slam_mms {
namespace {

int64_t FloorDiv(int64_t a, int64_t b) {
  const int64_t q = a / b;
  return (a % b != 0 && (a < 0) != (b < 0)) ? q - 1 : q;
}

struct Placed {
  PointCloud cloud;  // the submap's map cloud
  Eigen::Matrix3f R;
  Eigen::Vector3f t;
};

StatusOr<Placed> Load(const UnionMapSubmap& s) {
  Placed p;
  SLAM_MMS_ASSIGN_OR_RETURN(p.cloud,
                            ReadDriveResultCloud(s.drive_result_dir, s.id, DriveResultCloud::kMap));
  p.R = s.T_world_submap.linear().cast<float>();
  p.t = s.T_world_submap.translation().cast<float>();
  return p;
}

}  // namespace

Status UnionMapOptions::Validate() const {
  if (!(voxel_m > 0.0) || !std::isfinite(voxel_m)) {
    return internal::OptionError("UnionMapOptions", "voxel_m", voxel_m, "must be finite and > 0");
  }
  if (!(strip_m > 0.0) || !std::isfinite(strip_m)) {
    return internal::OptionError("UnionMapOptions", "strip_m", strip_m, "must be finite and > 0");
  }
  return OkStatus();
}

StatusOr<PointCloud> DownsampledUnionMap(const std::vector<UnionMapSubmap>& submaps,
                                         const UnionMapOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  const internal::VoxelGrid grid(options.voxel_m);
  const int64_t voxels_per_strip =
      std::max<int64_t>(1, std::llround(std::min(options.strip_m / options.voxel_m, 1e9)));
  // Pass 1: each submap's range of voxel indices along x and y (VoxelDownsample's cells).
  struct Range {
    int64_t lo[2] = {std::numeric_limits<int64_t>::max(), std::numeric_limits<int64_t>::max()};
    int64_t hi[2] = {std::numeric_limits<int64_t>::min(), std::numeric_limits<int64_t>::min()};
    bool empty() const { return lo[0] > hi[0]; }
  };
  std::vector<Range> ranges(submaps.size());
  Range all;
  for (size_t k = 0; k < submaps.size(); ++k) {
    SLAM_MMS_ASSIGN_OR_RETURN(Placed p, Load(submaps[k]));
    const auto& pts = p.cloud.points();
    for (const Eigen::Vector3f& q : pts) {
      internal::VoxelCell c;
      const Eigen::Vector3f w = PlaceInWorld(p.R, p.t, q);
      if (!grid.CellOf(w, &c)) {
        // Not finite: VoxelDownsample skips it. Too far out for the grid: its error.
        if (!w.allFinite()) continue;
        PointCloud one;
        one.Add(w);
        return VoxelDownsample(one, options.voxel_m)
            .status()
            .WithContext("DownsampledUnionMap: submap " + std::to_string(submaps[k].id) + " of " +
                         submaps[k].drive_result_dir.string());
      }
      for (int a = 0; a < 2; ++a) {
        ranges[k].lo[a] = std::min<int64_t>(ranges[k].lo[a], c[a]);
        ranges[k].hi[a] = std::max<int64_t>(ranges[k].hi[a], c[a]);
      }
    }
    for (int a = 0; a < 2; ++a) {
      all.lo[a] = std::min(all.lo[a], ranges[k].lo[a]);
      all.hi[a] = std::max(all.hi[a], ranges[k].hi[a]);
    }
  }
  PointCloud out;
  if (all.empty()) return out;
  // Strips across the longer horizontal extent.
  const int axis = (all.hi[0] - all.lo[0]) >= (all.hi[1] - all.lo[1]) ? 0 : 1;
  const int64_t first = FloorDiv(all.lo[axis], voxels_per_strip);
  const int64_t last = FloorDiv(all.hi[axis], voxels_per_strip);
  // Pass 2: strip by strip, the points of every submap reaching into it, in the given order.
  for (int64_t strip = first; strip <= last; ++strip) {
    PointCloud gathered;
    for (size_t k = 0; k < submaps.size(); ++k) {
      const Range& r = ranges[k];
      if (r.empty() || FloorDiv(r.lo[axis], voxels_per_strip) > strip ||
          FloorDiv(r.hi[axis], voxels_per_strip) < strip) {
        continue;
      }
      SLAM_MMS_ASSIGN_OR_RETURN(Placed p, Load(submaps[k]));
      const auto& pts = p.cloud.points();
      const auto& in = p.cloud.intensities();
      for (size_t i = 0; i < pts.size(); ++i) {
        const Eigen::Vector3f w = PlaceInWorld(p.R, p.t, pts[i]);
        internal::VoxelCell c;
        // A point without a cell is not finite (pass 1 refused the others): skipped.
        if (grid.CellOf(w, &c) && FloorDiv(c[axis], voxels_per_strip) == strip) {
          gathered.Add(w, in[i]);
        }
      }
    }
    if (gathered.empty()) continue;
    SLAM_MMS_ASSIGN_OR_RETURN(PointCloud down, VoxelDownsample(gathered, options.voxel_m));
    gathered = PointCloud();
    for (size_t i = 0; i < down.size(); ++i) {
      out.Add(down.points()[i], down.intensities()[i], down.time_offsets_s()[i]);
    }
  }
  return out;
}

}  // namespace slam_mms
