// SurfelMap: removing whole submaps and compacting the slot storage (bounded memory on long
// drives).
#include <algorithm>
#include <map>

#include "slam_mms/surfel/surfel_map.hpp"
#include "surfel/surfel_map_impl.hpp"

namespace slam_mms {

size_t SurfelMap::RemoveSubmap(int32_t submap_id, std::vector<Surfel>* removed) {
  Impl& m = *impl_;
  size_t n = 0;
  for (uint32_t id = 0; id < m.surfels.size(); ++id) {
    if (!m.alive[id] || m.surfels[id].submap_id != submap_id) continue;
    if (removed != nullptr) removed->push_back(m.surfels[id]);
    m.RemoveSlot(id);
    ++n;
  }
  return n;
}

size_t SurfelMap::RemoveSurfels(const std::vector<uint32_t>& ids) {
  Impl& m = *impl_;
  size_t n = 0;
  for (uint32_t id : ids) {
    if (id >= m.surfels.size() || !m.alive[id]) continue;
    m.RemoveSlot(id);
    ++n;
  }
  return n;
}

size_t SurfelMap::RemoveSubmapsExcept(const std::vector<int32_t>& keep,
                                      std::vector<Surfel>* removed) {
  Impl& m = *impl_;
  std::vector<int32_t> sorted = keep;
  std::sort(sorted.begin(), sorted.end());
  size_t n = 0;
  for (uint32_t id = 0; id < m.surfels.size(); ++id) {
    if (!m.alive[id]) continue;
    const Surfel& s = m.surfels[id];
    if (std::binary_search(sorted.begin(), sorted.end(), s.submap_id)) continue;
    if (removed != nullptr) removed->push_back(s);
    m.RemoveSlot(id);
    ++n;
  }
  return n;
}

std::vector<std::pair<int32_t, size_t>> SurfelMap::SubmapSizes() const {
  const Impl& m = *impl_;
  std::map<int32_t, size_t> counts;
  for (uint32_t id = 0; id < m.surfels.size(); ++id) {
    if (m.alive[id]) ++counts[m.surfels[id].submap_id];
  }
  return {counts.begin(), counts.end()};
}

size_t SurfelMap::Compact() {
  Impl& m = *impl_;
  const size_t before = MemoryBytes();
  const size_t n = m.num_alive;
  // Fresh vectors (not clear + shrink_to_fit, which the standard lets an implementation ignore).
  std::vector<Surfel> live;
  live.reserve(n);
  for (uint32_t id = 0; id < m.surfels.size(); ++id) {
    if (m.alive[id]) live.push_back(m.surfels[id]);
  }
  m.surfels.swap(live);
  std::vector<Surfel>().swap(live);
  std::vector<uint8_t>(n, 1).swap(m.alive);
  // Conflict flags are all clear between Integrate calls (step 4 resets every flag it set).
  std::vector<uint8_t>(n, 0).swap(m.conflict);
  std::vector<uint32_t>().swap(m.free_ids);
  m.index = internal::VoxelIndex(m.index.cell_size());
  m.index.Reserve(n);
  for (uint32_t id = 0; id < n; ++id) m.index.Insert(id, m.surfels[id].position);
  const size_t after = MemoryBytes();
  return before > after ? before - after : 0;
}

}  // namespace slam_mms
