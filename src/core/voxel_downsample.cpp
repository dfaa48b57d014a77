#include "slam_mms/core/voxel_downsample.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "core/voxel_grid.hpp"

namespace slam_mms {
namespace {

using internal::VoxelCell;

struct VoxelKey {
  VoxelCell cell;
  uint32_t index;  // input point
};

// Sorts by (cell, index): the voxels in cell order, each voxel's points in input order (a
// deterministic summation order). Where the cells span < 2^21 per axis (200 km at 0.1 m) they
// are packed relative to the lowest cell (PackVoxelCell: the same order) and (key, index) pairs
// are sorted: a third of the time of the three-way comparison.
void SortVoxelKeys(std::vector<VoxelKey>* keys) {
  if (keys->empty()) return;
  // A cloud already in cell order (one that VoxelDownsample wrote, downsampled again at the same
  // size: the map entropy of a final map) needs no sort; the check is one pass.
  if (std::is_sorted(keys->begin(), keys->end(), [](const VoxelKey& x, const VoxelKey& y) {
        return x.cell < y.cell;
      })) {
    return;
  }
  VoxelCell lo = keys->front().cell;
  for (const VoxelKey& k : *keys) {
    lo.x = std::min(lo.x, k.cell.x);
    lo.y = std::min(lo.y, k.cell.y);
    lo.z = std::min(lo.z, k.cell.z);
  }
  std::vector<std::pair<uint64_t, uint32_t>> packed(keys->size());
  for (size_t i = 0; i < keys->size(); ++i) {
    const VoxelKey& k = (*keys)[i];
    if (!internal::PackVoxelCell(k.cell, lo, &packed[i].first)) {
      std::sort(keys->begin(), keys->end(), [](const VoxelKey& x, const VoxelKey& y) {
        if (x.cell != y.cell) return x.cell < y.cell;
        return x.index < y.index;
      });
      return;
    }
    packed[i].second = k.index;
  }
  std::sort(packed.begin(), packed.end());
  for (size_t i = 0; i < packed.size(); ++i) {
    (*keys)[i] = {internal::UnpackVoxelCell(packed[i].first, lo), packed[i].second};
  }
}

}  // namespace

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
  std::vector<VoxelKey> keys;
  keys.reserve(cloud.size);
  for (size_t i = 0; i < cloud.size; ++i) {
    const Eigen::Vector3f p = cloud.Point(i);
    if (!p.allFinite()) continue;
    VoxelKey k;
    if (!grid.CellOf(p, &k.cell)) {
      return InvalidArgumentError(
          "VoxelDownsample: point " + std::to_string(i) +
          " is too far from the origin for voxel_size_m = " + std::to_string(voxel_size_m) +
          " (voxel index beyond +-" + std::to_string(internal::VoxelGrid::kMaxIndex) + ")");
    }
    k.index = static_cast<uint32_t>(i);
    keys.push_back(k);
  }
  SortVoxelKeys(&keys);
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
