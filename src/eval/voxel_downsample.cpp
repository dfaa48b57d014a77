#include "slam_mms/eval/voxel_downsample.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace slam_mms::eval {
namespace {

struct VoxelKey {
  int32_t ix, iy, iz;
  uint32_t index;  // input point
};

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
  std::sort(keys.begin(), keys.end(), [](const VoxelKey& a, const VoxelKey& b) {
    if (a.ix != b.ix) return a.ix < b.ix;
    if (a.iy != b.iy) return a.iy < b.iy;
    if (a.iz != b.iz) return a.iz < b.iz;
    return a.index < b.index;  // deterministic summation order
  });
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

}  // namespace slam_mms::eval
