#include "core/voxel_sort.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

namespace slam_mms::internal {
namespace {

// SortByCellThenIndex against std::sort by (cell, index) on the three paths: one 64-bit key per
// point (a local cloud), (packed cell, index) pairs (cells and indices too wide for one key), and
// cells compared (a span of 2^21 cells or more), with repeated cells and dropped indices.
TEST(VoxelSortTest, SameOrderAsStdSortOnEveryPath) {
  struct Case {
    int32_t span_xy;
    int32_t span_z;
    const char* name;
  };
  for (const Case& c : {Case{3000, 400, "one key"}, Case{1500000, 1500000, "pairs"},
                        Case{1 << 29, 1000, "cells compared"}}) {
    SCOPED_TRACE(c.name);
    std::mt19937 rng(5);
    std::uniform_int_distribution<int32_t> xy(-c.span_xy / 2, c.span_xy / 2);
    std::uniform_int_distribution<int32_t> z(-c.span_z / 2, c.span_z / 2);
    std::vector<CellIndex> keys;
    for (uint32_t i = 0; i < 60000; ++i) {
      if (i % 7 == 3) continue;  // indices with gaps (points dropped before the sort)
      CellIndex k;
      k.cell = i % 5 == 0 && !keys.empty() ? keys[i % keys.size()].cell
                                           : VoxelCell{xy(rng) + 7000, xy(rng) - 9000, z(rng)};
      k.index = i;
      keys.push_back(k);
    }
    std::vector<CellIndex> expected = keys;
    std::sort(expected.begin(), expected.end(), [](const CellIndex& a, const CellIndex& b) {
      if (a.cell != b.cell) return a.cell < b.cell;
      return a.index < b.index;
    });
    SortByCellThenIndex(&keys);
    ASSERT_EQ(keys.size(), expected.size());
    for (size_t i = 0; i < keys.size(); ++i) {
      ASSERT_TRUE(keys[i].cell == expected[i].cell) << i;
      ASSERT_EQ(keys[i].index, expected[i].index) << i;
    }
  }
}

TEST(VoxelSortTest, EmptyAndSorted) {
  std::vector<CellIndex> none;
  SortByCellThenIndex(&none);
  EXPECT_TRUE(none.empty());
  std::vector<CellIndex> sorted = {
      {{0, 0, 0}, 0}, {{0, 0, 0}, 1}, {{0, 1, -5}, 2}, {{3, -1, 0}, 3}};
  const std::vector<CellIndex> copy = sorted;
  SortByCellThenIndex(&sorted);
  for (size_t i = 0; i < copy.size(); ++i) EXPECT_EQ(sorted[i].index, copy[i].index);
}

}  // namespace
}  // namespace slam_mms::internal
