#pragma once
// SortByCellThenIndex: points' voxel cells sorted by (cell, index): the voxels in cell order
// (VoxelCell's (x, y, z) order), each voxel's points in input order (a deterministic summation
// order). The one sort of VoxelDownsample and of the final map's per-voxel stamps
// (MappingSystem::FinalMap), which must put the same points in the same voxels in the same order.
//
// Where each point's cell (its offsets from the lowest cell, as many bits per axis as the cloud
// spans) and index fit one 64-bit key (a map of 1.6 km x 1.6 km x 50 m at 0.1 m with up to 2^24
// points takes 14 + 14 + 9 + 24 = 61 bits), the keys are radix-sorted (RadixSort; 24 bytes a
// point at the peak). A wider cloud sorts (cell key, index) pairs (32 bytes a point), and one
// spanning 2^21 cells or more along an axis compares the cells in place. A cloud already in cell
// order is left as it is after one pass. Private to the library (src/core; not installed).

#include <cstdint>
#include <vector>

#include "core/voxel_grid.hpp"

namespace slam_mms::internal {

/// A point's cell and its index in the input.
struct CellIndex {
  VoxelCell cell;
  uint32_t index = 0;
};

/// Sorts `keys` by (cell, index). Equal (cell, index) pairs are not expected (indices are
/// unique).
void SortByCellThenIndex(std::vector<CellIndex>* keys);

}  // namespace slam_mms::internal
