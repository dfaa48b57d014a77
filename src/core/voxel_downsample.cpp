#include "slam_mms/core/voxel_downsample.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

namespace slam_mms {
namespace {

struct VoxelKey {
  int32_t ix, iy, iz;
  uint32_t index;  // input point
};

// Sorts by (ix, iy, iz, index): the voxels in key order, each voxel's points in input order (a
// deterministic summation order). Where the indices span < 2^21 per axis (200 km at 0.1 m) they
// are packed into one 64-bit key in the same order, and (key, index) pairs are sorted: a third
// of the time of the three-way comparison.
void SortVoxelKeys(std::vector<VoxelKey>* keys) {
  if (keys->empty()) return;
  int32_t lo[3] = {keys->front().ix, keys->front().iy, keys->front().iz};
  int32_t hi[3] = {lo[0], lo[1], lo[2]};
  for (const VoxelKey& k : *keys) {
    const int32_t v[3] = {k.ix, k.iy, k.iz};
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], v[a]);
      hi[a] = std::max(hi[a], v[a]);
    }
  }
  constexpr int64_t kSpan = int64_t{1} << 21;
  for (int a = 0; a < 3; ++a) {
    if (static_cast<int64_t>(hi[a]) - lo[a] >= kSpan) {
      std::sort(keys->begin(), keys->end(), [](const VoxelKey& x, const VoxelKey& y) {
        if (x.ix != y.ix) return x.ix < y.ix;
        if (x.iy != y.iy) return x.iy < y.iy;
        if (x.iz != y.iz) return x.iz < y.iz;
        return x.index < y.index;
      });
      return;
    }
  }
  std::vector<std::pair<uint64_t, uint32_t>> packed(keys->size());
  for (size_t i = 0; i < keys->size(); ++i) {
    const VoxelKey& k = (*keys)[i];
    packed[i] = {(static_cast<uint64_t>(static_cast<int64_t>(k.ix) - lo[0]) << 42) |
                     (static_cast<uint64_t>(static_cast<int64_t>(k.iy) - lo[1]) << 21) |
                     static_cast<uint64_t>(static_cast<int64_t>(k.iz) - lo[2]),
                 k.index};
  }
  std::sort(packed.begin(), packed.end());
  for (size_t i = 0; i < packed.size(); ++i) {
    const uint64_t key = packed[i].first;
    VoxelKey& k = (*keys)[i];
    k.ix = static_cast<int32_t>(static_cast<int64_t>(key >> 42) + lo[0]);
    k.iy = static_cast<int32_t>(static_cast<int64_t>((key >> 21) & (kSpan - 1)) + lo[1]);
    k.iz = static_cast<int32_t>(static_cast<int64_t>(key & (kSpan - 1)) + lo[2]);
    k.index = packed[i].second;
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
  const double inv = 1.0 / voxel_size_m;
  constexpr double kMaxIndex = 2147483000.0;
  std::vector<VoxelKey> keys;
  keys.reserve(cloud.size);
  for (size_t i = 0; i < cloud.size; ++i) {
    const Eigen::Vector3f p = cloud.Point(i);
    if (!p.allFinite()) continue;
    const double fx = std::floor(p.x() * inv);
    const double fy = std::floor(p.y() * inv);
    const double fz = std::floor(p.z() * inv);
    if (std::abs(fx) > kMaxIndex || std::abs(fy) > kMaxIndex || std::abs(fz) > kMaxIndex) {
      return InvalidArgumentError("VoxelDownsample: point " + std::to_string(i) +
                                  " is too far from the origin for voxel_size_m = " +
                                  std::to_string(voxel_size_m) + " (voxel index overflows int32)");
    }
    keys.push_back({static_cast<int32_t>(fx), static_cast<int32_t>(fy), static_cast<int32_t>(fz),
                    static_cast<uint32_t>(i)});
  }
  SortVoxelKeys(&keys);
  PointCloud out;
  size_t begin = 0;
  while (begin < keys.size()) {
    size_t end = begin + 1;
    while (end < keys.size() && keys[end].ix == keys[begin].ix && keys[end].iy == keys[begin].iy &&
           keys[end].iz == keys[begin].iz) {
      ++end;
    }
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
