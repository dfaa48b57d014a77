#include "pipeline/voxel_accumulator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace slam_mms::internal {
namespace {

// 21 bits per axis, offset so negative indices fit: +-1M voxels (+-100 km at 0.1 m).
constexpr int64_t kOffset = 1 << 20;
constexpr uint64_t kMask = (1u << 21) - 1;

uint64_t Key(int64_t ix, int64_t iy, int64_t iz) {
  return ((static_cast<uint64_t>(ix + kOffset) & kMask) << 42) |
         ((static_cast<uint64_t>(iy + kOffset) & kMask) << 21) |
         (static_cast<uint64_t>(iz + kOffset) & kMask);
}

int64_t Axis(uint64_t key, int shift) {
  return static_cast<int64_t>((key >> shift) & kMask) - kOffset;
}

// Fibonacci hashing: the top bits of the product depend on every bit of the key (the low bits of a
// product do not depend on the key's high bits, where x lives: slots from them collided by x).
size_t Slot(uint64_t key, size_t mask) {
  const int bits = __builtin_popcountll(mask);
  return static_cast<size_t>((key * 0x9E3779B97F4A7C15ull) >> (64 - bits));
}

}  // namespace

void VoxelAccumulator::Clear() {
  table_ = std::vector<Entry>();
  size_ = 0;
  first_time_ns_ = std::vector<int64_t>();
  first_scan_ = std::vector<int64_t>();
}

void VoxelAccumulator::Reserve(size_t voxels) {
  if (2 * voxels <= table_.size()) return;
  size_t capacity = table_.empty() ? size_t{1} << 16 : table_.size();
  while (2 * voxels > capacity) capacity *= 2;
  std::vector<Entry> old = std::move(table_);
  table_.assign(capacity, Entry());
  if (track_) {  // the stamps grow with the voxels: no reallocation between table growths
    first_time_ns_.reserve(capacity / 2);
    first_scan_.reserve(capacity / 2);
  }
  const size_t mask = capacity - 1;
  for (const Entry& e : old) {
    if (e.key == kEmpty) continue;
    size_t slot = Slot(e.key, mask);
    while (table_[slot].key != kEmpty) slot = (slot + 1) & mask;
    table_[slot] = e;
  }
}

VoxelAccumulator::Entry& VoxelAccumulator::Find(uint64_t key, size_t slot) {
  const size_t mask = table_.size() - 1;
  while (true) {
    Entry& e = table_[slot];
    if (e.key == key) return e;
    if (e.key == kEmpty) {
      e.key = key;
      e.order = static_cast<uint32_t>(size_);
      ++size_;
      return e;
    }
    slot = (slot + 1) & mask;
  }
}

void VoxelAccumulator::Add(const PointCloud& cloud, const Eigen::Isometry3d& T_frame_c,
                           double max_range_m, const ScanStamp* stamp) {
  const Eigen::Matrix3f R = T_frame_c.linear().cast<float>();
  const Eigen::Vector3d t = T_frame_c.translation();
  const float max_range_sq = static_cast<float>(max_range_m * max_range_m);
  constexpr size_t kBatch = 32;
  std::array<uint64_t, kBatch> keys;
  std::array<Eigen::Vector3f, kBatch> offsets;
  std::array<float, kBatch> intensities;
  std::array<size_t, kBatch> slots;
  std::array<size_t, kBatch> index;  // of each batch point in `cloud` (first-observation times)
  const bool track = track_ && stamp != nullptr;
  const std::vector<float>* dt = track ? stamp->dt_from_scan_start_s : nullptr;
  if (dt != nullptr && dt->size() != cloud.size()) dt = nullptr;
  const size_t n = cloud.size();
  size_t i = 0;
  while (i < n) {
    // Keys and slots of the next batch, prefetching each slot; then the updates.
    Reserve(size_ + kBatch);
    const size_t mask = table_.size() - 1;
    size_t b = 0;
    for (; i < n && b < kBatch; ++i) {
      const Eigen::Vector3f& p_c = cloud.points()[i];
      if (!p_c.allFinite() || p_c.squaredNorm() > max_range_sq) continue;
      const Eigen::Vector3d p = (R * p_c).cast<double>() + t;
      const Eigen::Vector3d cell = (p * inv_voxel_).array().floor();
      keys[b] = Key(static_cast<int64_t>(cell.x()), static_cast<int64_t>(cell.y()),
                    static_cast<int64_t>(cell.z()));
      offsets[b] = (p - cell * voxel_).cast<float>();
      intensities[b] = cloud.intensities()[i];
      slots[b] = Slot(keys[b], mask);
      index[b] = i;
      __builtin_prefetch(&table_[slots[b]], 1);
      ++b;
    }
    for (size_t k = 0; k < b; ++k) {
      Entry& e = Find(keys[k], slots[k]);
      if (track && e.count == 0) {  // a new voxel: its first observation
        const double offset_s = dt != nullptr ? static_cast<double>((*dt)[index[k]]) : 0.0;
        first_time_ns_.push_back(stamp->scan_start_ns + std::llround(offset_s * 1e9));
        first_scan_.push_back(stamp->scan_index);
      } else if (track_ && e.count == 0) {
        first_time_ns_.push_back(0);
        first_scan_.push_back(0);
      }
      e.dx += offsets[k].x();
      e.dy += offsets[k].y();
      e.dz += offsets[k].z();
      e.intensity += intensities[k];
      ++e.count;
    }
  }
}

PointCloud VoxelAccumulator::Cloud() const { return Cloud(nullptr, nullptr); }

PointCloud VoxelAccumulator::Cloud(std::vector<int64_t>* first_time_ns,
                                   std::vector<int64_t>* first_scan) const {
  const bool stamps = track_ && first_time_ns_.size() == size_;
  if (first_time_ns != nullptr) first_time_ns->clear();
  if (first_scan != nullptr) first_scan->clear();
  // (key, slot) pairs sorted by key (keys are unique): the sort compares contiguous keys instead
  // of chasing a pointer into the table per comparison.
  std::vector<std::pair<uint64_t, size_t>> sorted;
  sorted.reserve(size_);
  for (size_t slot = 0; slot < table_.size(); ++slot) {
    if (table_[slot].key != kEmpty) sorted.emplace_back(table_[slot].key, slot);
  }
  std::sort(sorted.begin(), sorted.end());
  PointCloud out;
  out.reserve(sorted.size());
  for (const auto& [key, slot] : sorted) {
    const Entry* e = &table_[slot];
    const double n = e->count;
    const Eigen::Vector3d corner(static_cast<double>(Axis(e->key, 42)) * voxel_,
                                 static_cast<double>(Axis(e->key, 21)) * voxel_,
                                 static_cast<double>(Axis(e->key, 0)) * voxel_);
    const Eigen::Vector3d mean = corner + Eigen::Vector3d(e->dx, e->dy, e->dz) / n;
    out.Add(mean.cast<float>(), e->intensity / static_cast<float>(n));
    if (stamps && first_time_ns != nullptr) first_time_ns->push_back(first_time_ns_[e->order]);
    if (stamps && first_scan != nullptr) first_scan->push_back(first_scan_[e->order]);
  }
  return out;
}

}  // namespace slam_mms::internal
