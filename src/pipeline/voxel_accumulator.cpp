#include "pipeline/voxel_accumulator.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace slam_mms::internal {
namespace {
// 21 bits per axis, offset so negative indices fit: +-1M voxels (+-100 km at 0.1 m).
uint64_t Key(int64_t ix, int64_t iy, int64_t iz) {
  constexpr int64_t kOffset = 1 << 20;
  constexpr uint64_t kMask = (1u << 21) - 1;
  return ((static_cast<uint64_t>(ix + kOffset) & kMask) << 42) |
         ((static_cast<uint64_t>(iy + kOffset) & kMask) << 21) |
         (static_cast<uint64_t>(iz + kOffset) & kMask);
}
}  // namespace

void VoxelAccumulator::Add(const PointCloud& cloud, const Eigen::Isometry3d& T_frame_c,
                           double max_range_m) {
  const Eigen::Matrix3f R = T_frame_c.linear().cast<float>();
  const Eigen::Vector3d t = T_frame_c.translation();
  const float max_range_sq = static_cast<float>(max_range_m * max_range_m);
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p_c = cloud.points()[i];
    if (!p_c.allFinite() || p_c.squaredNorm() > max_range_sq) continue;
    const Eigen::Vector3d p = (R * p_c).cast<double>() + t;
    const uint64_t key = Key(static_cast<int64_t>(std::floor(p.x() * inv_voxel_)),
                             static_cast<int64_t>(std::floor(p.y() * inv_voxel_)),
                             static_cast<int64_t>(std::floor(p.z() * inv_voxel_)));
    Voxel& v = voxels_[key];
    v.x += p.x();
    v.y += p.y();
    v.z += p.z();
    v.intensity += cloud.intensities()[i];
    ++v.count;
  }
}

PointCloud VoxelAccumulator::Cloud() const {
  std::vector<std::pair<uint64_t, const Voxel*>> sorted;
  sorted.reserve(voxels_.size());
  for (const auto& kv : voxels_) sorted.emplace_back(kv.first, &kv.second);
  std::sort(sorted.begin(), sorted.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  PointCloud out;
  out.reserve(sorted.size());
  for (const auto& [key, v] : sorted) {
    const double n = v->count;
    out.Add(Eigen::Vector3f(static_cast<float>(v->x / n), static_cast<float>(v->y / n),
                            static_cast<float>(v->z / n)),
            v->intensity / static_cast<float>(n));
  }
  return out;
}

}  // namespace slam_mms::internal
