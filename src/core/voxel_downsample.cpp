#include "slam_mms/core/voxel_downsample.hpp"

#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "core/voxel_grid.hpp"
#include "core/voxel_sort.hpp"

namespace slam_mms {

StatusOr<PointCloud> VoxelDownsample(const PointCloudView& cloud, double voxel_size_m) {
  if (!(voxel_size_m > 0.0) || !std::isfinite(voxel_size_m)) {
    return InvalidArgumentError("VoxelDownsample: voxel_size_m = " + std::to_string(voxel_size_m) +
                                "; must be finite and > 0");
  }
  if (cloud.size > std::numeric_limits<uint32_t>::max()) {
    return InvalidArgumentError("VoxelDownsample: " + std::to_string(cloud.size) +
                                " points; at most 2^32 - 1 are supported");
  }
  const internal::VoxelGrid grid(voxel_size_m);
  std::vector<internal::CellIndex> keys;
  keys.reserve(cloud.size);
  for (size_t i = 0; i < cloud.size; ++i) {
    const Eigen::Vector3f p = cloud.Point(i);
    if (!p.allFinite()) continue;
    internal::CellIndex k;
    if (!grid.CellOf(p, &k.cell)) {
      return InvalidArgumentError(
          "VoxelDownsample: point " + std::to_string(i) +
          " is too far from the origin for voxel_size_m = " + std::to_string(voxel_size_m) +
          " (voxel index beyond +-" + std::to_string(internal::VoxelGrid::kMaxIndex) + ")");
    }
    k.index = static_cast<uint32_t>(i);
    keys.push_back(k);
  }
  internal::SortByCellThenIndex(&keys);
  PointCloud out;
  size_t begin = 0;
  while (begin < keys.size()) {
    size_t end = begin + 1;
    while (end < keys.size() && keys[end].cell == keys[begin].cell) ++end;
    Eigen::Vector3d sum_p = Eigen::Vector3d::Zero();
    double sum_i = 0.0;
    double sum_t = 0.0;
    for (size_t k = begin; k < end; ++k) {
      const uint32_t idx = keys[k].index;
      sum_p += cloud.Point(idx).cast<double>();
      sum_i += cloud.Intensity(idx);
      sum_t += cloud.TimeOffset(idx);
    }
    const double n = static_cast<double>(end - begin);
    out.Add((sum_p / n).cast<float>(), static_cast<float>(sum_i / n),
            static_cast<float>(sum_t / n));
    begin = end;
  }
  return out;
}

StatusOr<PointCloud> VoxelDownsample(const PointCloud& cloud, double voxel_size_m) {
  return VoxelDownsample(cloud.View(), voxel_size_m);
}

}  // namespace slam_mms
