#include "pipeline/voxel_accumulator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>
#include <vector>

#include "core/radix_sort.hpp"

namespace slam_mms::internal {
namespace {

// The top bits of the cell's hash (HashVoxelCell mixes every bit of the cell into them).
size_t Slot(const VoxelCell& cell, size_t mask) {
  const int bits = __builtin_popcountll(mask);
  return static_cast<size_t>(HashVoxelCell(cell) >> (64 - bits));
}

}  // namespace

void VoxelAccumulator::Reset() {
  // order_[slot] is written whenever a slot takes a voxel, and read only for taken slots.
  std::fill(table_.begin(), table_.end(), Entry());
  size_ = 0;
  out_of_range_ = 0;
  first_time_ns_.clear();
  first_scan_.clear();
}

void VoxelAccumulator::Reserve(size_t voxels) {
  if (2 * voxels <= table_.size()) return;
  size_t capacity = table_.empty() ? size_t{1} << 16 : table_.size();
  while (2 * voxels > capacity) capacity *= 2;
  std::vector<Entry> old = std::move(table_);
  std::vector<uint32_t> old_order = std::move(order_);
  table_.assign(capacity, Entry());
  if (track_) {  // the stamps grow with the voxels: no reallocation between table growths
    order_.assign(capacity, 0);
    first_time_ns_.reserve(capacity / 2);
    first_scan_.reserve(capacity / 2);
  }
  const size_t mask = capacity - 1;
  for (size_t i = 0; i < old.size(); ++i) {
    const Entry& e = old[i];
    if (e.count == 0) continue;
    size_t slot = Slot(e.cell, mask);
    while (table_[slot].count != 0) slot = (slot + 1) & mask;
    table_[slot] = e;
    if (track_) order_[slot] = old_order[i];
  }
}

VoxelAccumulator::Entry& VoxelAccumulator::Find(const VoxelCell& cell, size_t slot) {
  const size_t mask = table_.size() - 1;
  while (true) {
    Entry& e = table_[slot];
    if (e.count == 0) {  // the caller adds its point at once: count > 0 before the next Find
      e.cell = cell;
      if (track_) order_[slot] = static_cast<uint32_t>(size_);
      ++size_;
      return e;
    }
    if (e.cell == cell) return e;
    slot = (slot + 1) & mask;
  }
}

void VoxelAccumulator::Add(const PointCloud& cloud, const Eigen::Isometry3d& T_frame_c,
                           double max_range_m, const ScanStamp* stamp) {
  const Eigen::Matrix3f R = T_frame_c.linear().cast<float>();
  const Eigen::Vector3d t = T_frame_c.translation();
  const float max_range_sq = static_cast<float>(max_range_m * max_range_m);
  constexpr size_t kBatch = 32;
  std::array<VoxelCell, kBatch> cells;
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
      if (!grid_.CellOf(p, &cells[b])) {
        ++out_of_range_;
        continue;
      }
      offsets[b] = (p - grid_.Corner(cells[b])).cast<float>();
      intensities[b] = cloud.intensities()[i];
      slots[b] = Slot(cells[b], mask);
      index[b] = i;
      __builtin_prefetch(&table_[slots[b]], 1);
      ++b;
    }
    for (size_t k = 0; k < b; ++k) {
      Entry& e = Find(cells[k], slots[k]);
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
  // The occupied slots in cell order (cells are unique): each cell's offsets from the lowest
  // cell with as many bits per axis as the cloud spans and the slot below them (FittedCellKey),
  // radix-sorted (8 bytes a voxel, and as many for the sort's scratch).
  // A submap's key takes about 55 bits (a 1.6 km x 1.6 km x 51 m box at 0.1 m, 14 + 14 + 9 bits,
  // and 18-23 bits of slot); a cloud too wide for 64 has its cells compared instead.
  VoxelCell lo{std::numeric_limits<int32_t>::max(), std::numeric_limits<int32_t>::max(),
               std::numeric_limits<int32_t>::max()};
  VoxelCell hi{std::numeric_limits<int32_t>::min(), std::numeric_limits<int32_t>::min(),
               std::numeric_limits<int32_t>::min()};
  for (const Entry& e : table_) {
    if (e.count == 0) continue;
    lo = {std::min(lo.x, e.cell.x), std::min(lo.y, e.cell.y), std::min(lo.z, e.cell.z)};
    hi = {std::max(hi.x, e.cell.x), std::max(hi.y, e.cell.y), std::max(hi.z, e.cell.z)};
  }
  const FittedCellKey layout(lo, hi, BitWidth(table_.size() == 0 ? 0 : table_.size() - 1));
  PointCloud out;
  out.reserve(size_);
  if (stamps && first_time_ns != nullptr) first_time_ns->reserve(size_);
  if (stamps && first_scan != nullptr) first_scan->reserve(size_);
  // The voxels in the order given by slot_at(0 .. n-1): each is up to four cache misses (its
  // entry, its creation index, its two stamps) in tables far larger than the cache, so the
  // entries kAhead voxels on are prefetched, and their stamps once the index is likely in.
  auto emit_all = [&](size_t n, auto slot_at) {
    constexpr size_t kAhead = 16;
    for (size_t k = 0; k < n; ++k) {
      if (k + kAhead < n) {
        const size_t ahead = slot_at(k + kAhead);
        __builtin_prefetch(&table_[ahead]);
        if (stamps) __builtin_prefetch(&order_[ahead]);
      }
      if (stamps && k + kAhead / 2 < n) {
        const uint32_t created = order_[slot_at(k + kAhead / 2)];
        __builtin_prefetch(&first_time_ns_[created]);
        __builtin_prefetch(&first_scan_[created]);
      }
      const size_t slot = slot_at(k);
      const Entry* e = &table_[slot];
      const double count = e->count;
      const Eigen::Vector3d corner = grid_.Corner(e->cell);
      const Eigen::Vector3d mean = corner + Eigen::Vector3d(e->dx, e->dy, e->dz) / count;
      out.Add(mean.cast<float>(), e->intensity / static_cast<float>(count));
      if (stamps && first_time_ns != nullptr) {
        first_time_ns->push_back(first_time_ns_[order_[slot]]);
      }
      if (stamps && first_scan != nullptr) first_scan->push_back(first_scan_[order_[slot]]);
    }
  };
  if (size_ > 0 && layout.fits()) {
    std::vector<uint64_t> keys;
    keys.reserve(size_);
    for (size_t slot = 0; slot < table_.size(); ++slot) {
      if (table_[slot].count != 0) keys.push_back(layout.Pack(table_[slot].cell, slot));
    }
    {
      std::vector<uint64_t> scratch;
      RadixSort(&keys, &scratch);
    }
    emit_all(keys.size(), [&](size_t k) { return static_cast<size_t>(layout.Payload(keys[k])); });
  } else {
    std::vector<std::pair<VoxelCell, size_t>> order;  // contiguous cells, not a pointer each
    order.reserve(size_);
    for (size_t slot = 0; slot < table_.size(); ++slot) {
      if (table_[slot].count != 0) order.emplace_back(table_[slot].cell, slot);
    }
    std::sort(order.begin(), order.end(),
              [](const auto& a, const auto& b) { return a.first < b.first; });
    emit_all(order.size(), [&](size_t k) { return order[k].second; });
  }
  return out;
}

}  // namespace slam_mms::internal
