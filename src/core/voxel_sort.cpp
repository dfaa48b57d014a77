#include "core/voxel_sort.hpp"

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/radix_sort.hpp"

namespace slam_mms::internal {
namespace {

// A cloud whose cells and indices do not fit one 64-bit key: (PackVoxelCell key, index) pairs
// radix-sorted where the cells span < 2^21 per axis (32 bytes a point at the peak), else the
// cells compared in place.
void SortWideCloud(std::vector<CellIndex>* keys, const VoxelCell& lo) {
  std::vector<std::pair<uint64_t, uint32_t>> packed(keys->size());
  for (size_t i = 0; i < keys->size(); ++i) {
    const CellIndex& k = (*keys)[i];
    if (!PackVoxelCell(k.cell, lo, &packed[i].first)) {
      std::vector<std::pair<uint64_t, uint32_t>>().swap(packed);
      std::sort(keys->begin(), keys->end(), [](const CellIndex& x, const CellIndex& y) {
        if (x.cell != y.cell) return x.cell < y.cell;
        return x.index < y.index;
      });
      return;
    }
    packed[i].second = k.index;
  }
  const size_t n = keys->size();
  std::vector<CellIndex>().swap(*keys);
  {
    std::vector<std::pair<uint64_t, uint32_t>> scratch;
    RadixSortByKey(&packed, &scratch);  // stable: the pairs came in index order
  }
  keys->resize(n);
  for (size_t i = 0; i < n; ++i) {
    (*keys)[i] = {UnpackVoxelCell(packed[i].first, lo), packed[i].second};
  }
}

}  // namespace

void SortByCellThenIndex(std::vector<CellIndex>* keys) {
  if (keys->empty()) return;
  // A cloud already in cell order (one that VoxelDownsample wrote, downsampled again at the same
  // size: the map entropy of a final map) needs no sort; the check is one pass.
  if (std::is_sorted(keys->begin(), keys->end(),
                     [](const CellIndex& x, const CellIndex& y) { return x.cell < y.cell; })) {
    return;
  }
  VoxelCell lo = keys->front().cell;
  VoxelCell hi = lo;
  uint32_t max_index = 0;
  for (const CellIndex& k : *keys) {
    lo = {std::min(lo.x, k.cell.x), std::min(lo.y, k.cell.y), std::min(lo.z, k.cell.z)};
    hi = {std::max(hi.x, k.cell.x), std::max(hi.y, k.cell.y), std::max(hi.z, k.cell.z)};
    max_index = std::max(max_index, k.index);
  }
  const FittedCellKey layout(lo, hi, BitWidth(max_index));
  if (!layout.fits()) {
    SortWideCloud(keys, lo);
    return;
  }
  // One 64-bit key per point (the cell, then the index: FittedCellKey). The keys are unique, so
  // their order is (cell, index). The points' records are freed during the sort and rebuilt from
  // the keys: with them the peak is 24 bytes a point (std::sort needed the 16 of the records
  // alone; the final map runs this sort for VoxelDownsample and for its stamps at once, and
  // together they need what they needed before, 48 bytes a point).
  std::vector<uint64_t> sorted(keys->size());
  for (size_t i = 0; i < keys->size(); ++i) {
    sorted[i] = layout.Pack((*keys)[i].cell, (*keys)[i].index);
  }
  const size_t n = keys->size();
  std::vector<CellIndex>().swap(*keys);
  {
    std::vector<uint64_t> scratch;
    RadixSort(&sorted, &scratch);
  }
  keys->resize(n);
  for (size_t i = 0; i < n; ++i) {
    (*keys)[i] = {layout.Cell(sorted[i]), static_cast<uint32_t>(layout.Payload(sorted[i]))};
  }
}

}  // namespace slam_mms::internal
