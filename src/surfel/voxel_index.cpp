#include "surfel/voxel_index.hpp"

#include <cmath>
#include <limits>

namespace slam_mms::internal {

void VoxelIndex::Clear() {
  cells_.clear();
  where_.clear();
}

void VoxelIndex::EnsureSlot(uint32_t id) {
  if (where_.size() <= id) where_.resize(static_cast<size_t>(id) + 1);
}

void VoxelIndex::Insert(uint32_t id, const Eigen::Vector3f& position) {
  EnsureSlot(id);
  const Key key = KeyOf(position);
  std::vector<uint32_t>& cell = cells_[key];
  where_[id] = {key, static_cast<uint32_t>(cell.size()), true};
  cell.push_back(id);
}

void VoxelIndex::Erase(uint32_t id) {
  if (id >= where_.size() || !where_[id].present) return;
  Where& w = where_[id];
  auto it = cells_.find(w.key);
  std::vector<uint32_t>& cell = it->second;
  const uint32_t last = cell.back();
  cell[w.slot] = last;
  where_[last].slot = w.slot;
  cell.pop_back();
  if (cell.empty()) cells_.erase(it);
  w.present = false;
}

void VoxelIndex::Update(uint32_t id, const Eigen::Vector3f& position) {
  const Key key = KeyOf(position);
  if (id < where_.size() && where_[id].present && where_[id].key == key) return;
  Erase(id);
  Insert(id, position);
}

void VoxelIndex::CandidatesInSphere(const Eigen::Vector3f& center, float radius,
                                    std::vector<uint32_t>* ids) const {
  const Key lo = KeyOf(center - Eigen::Vector3f::Constant(radius));
  const Key hi = KeyOf(center + Eigen::Vector3f::Constant(radius));
  const double r2 = static_cast<double>(radius) * radius;
  const long long span = static_cast<long long>(hi.x - lo.x + 1) * (hi.y - lo.y + 1) *
                         static_cast<long long>(hi.z - lo.z + 1);
  constexpr double kInf = std::numeric_limits<double>::infinity();
  auto visit = [&](const Key& key, const std::vector<uint32_t>& cell) {
    // Squared distance from the centre to the cell's box (in double: the box contains every
    // position filed in the cell; the outermost cells hold everything beyond them).
    double d2 = 0.0;
    for (int a = 0; a < 3; ++a) {
      const int32_t k = key[a];
      const double lo_a = k == -VoxelGrid::kMaxIndex ? -kInf : grid_.Lower(k, a);
      const double hi_a = k == VoxelGrid::kMaxIndex ? kInf : grid_.Lower(k + 1, a);
      const double c = center[a];
      const double d = c < lo_a ? lo_a - c : (c > hi_a ? c - hi_a : 0.0);
      d2 += d * d;
    }
    if (d2 <= r2) ids->insert(ids->end(), cell.begin(), cell.end());
  };
  if (span > static_cast<long long>(cells_.size())) {
    for (const auto& [key, cell] : cells_) visit(key, cell);
    return;
  }
  for (int32_t x = lo.x; x <= hi.x; ++x) {
    for (int32_t y = lo.y; y <= hi.y; ++y) {
      for (int32_t z = lo.z; z <= hi.z; ++z) {
        const auto it = cells_.find(Key{x, y, z});
        if (it != cells_.end()) visit(it->first, it->second);
      }
    }
  }
}

size_t VoxelIndex::MemoryBytes() const {
  size_t bytes = where_.capacity() * sizeof(Where);
  for (const auto& [key, cell] : cells_) {
    bytes += sizeof(Key) + sizeof(cell) + cell.capacity() * sizeof(uint32_t) + 2 * sizeof(void*);
  }
  bytes += cells_.bucket_count() * sizeof(void*);
  return bytes;
}

}  // namespace slam_mms::internal
