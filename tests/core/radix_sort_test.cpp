#include "core/radix_sort.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "core/voxel_grid.hpp"

namespace slam_mms::internal {
namespace {

using Pair = std::pair<uint64_t, uint32_t>;

// The callers' contract: pairs given in ascending index order come out exactly as std::sort
// orders them, (key, index).
void ExpectSameAsStdSort(std::vector<Pair> pairs) {
  for (size_t i = 0; i < pairs.size(); ++i) pairs[i].second = static_cast<uint32_t>(i);
  std::vector<Pair> expected = pairs;
  std::sort(expected.begin(), expected.end());
  std::vector<Pair> scratch;
  RadixSortByKey(&pairs, &scratch);
  ASSERT_EQ(pairs.size(), expected.size());
  EXPECT_TRUE(pairs == expected);
}

TEST(RadixSortTest, EmptyOneAndAllEqual) {
  ExpectSameAsStdSort({});
  ExpectSameAsStdSort({{5, 0}});
  ExpectSameAsStdSort(std::vector<Pair>(1000, Pair{42, 0}));
}

TEST(RadixSortTest, RandomKeysWithRepeatsOverEveryDigit) {
  std::mt19937_64 rng(7);
  for (int bits : {1, 5, 11, 12, 22, 33, 44, 55, 63, 64}) {
    const uint64_t mask = bits == 64 ? ~uint64_t{0} : (uint64_t{1} << bits) - 1;
    std::vector<Pair> pairs(20000);
    // Half the keys drawn from a small set (repeated keys: stability decides their order).
    for (size_t i = 0; i < pairs.size(); ++i) {
      pairs[i].first = (i % 2 == 0 ? rng() % 97 : rng()) & mask;
    }
    SCOPED_TRACE(bits);
    ExpectSameAsStdSort(pairs);
  }
}

TEST(RadixSortTest, PackedVoxelCellsSortLikeCells) {
  // Cells of a local cloud around a far-off point, packed against their lowest cell, as the
  // voxel sorts use it: the order of the packed keys is the order of the cells.
  std::mt19937 rng(3);
  std::uniform_int_distribution<int32_t> dxy(-1500, 1500);
  std::uniform_int_distribution<int32_t> dz(-40, 260);
  std::vector<VoxelCell> cells(50000);
  for (VoxelCell& c : cells) c = {3000000 + dxy(rng), -2000000 + dxy(rng), 100 + dz(rng)};
  cells.push_back(cells[10]);  // a repeat
  VoxelCell lo = cells.front();
  for (const VoxelCell& c : cells) {
    lo = {std::min(lo.x, c.x), std::min(lo.y, c.y), std::min(lo.z, c.z)};
  }
  std::vector<Pair> pairs(cells.size());
  for (size_t i = 0; i < cells.size(); ++i) {
    ASSERT_TRUE(PackVoxelCell(cells[i], lo, &pairs[i].first));
    pairs[i].second = static_cast<uint32_t>(i);
  }
  std::vector<Pair> scratch;
  RadixSortByKey(&pairs, &scratch);
  std::vector<std::pair<VoxelCell, uint32_t>> expected(cells.size());
  for (size_t i = 0; i < cells.size(); ++i) expected[i] = {cells[i], static_cast<uint32_t>(i)};
  std::sort(expected.begin(), expected.end(), [](const auto& a, const auto& b) {
    if (a.first != b.first) return a.first < b.first;
    return a.second < b.second;
  });
  for (size_t i = 0; i < cells.size(); ++i) {
    ASSERT_EQ(pairs[i].second, expected[i].second) << i;
    ASSERT_TRUE(UnpackVoxelCell(pairs[i].first, lo) == expected[i].first) << i;
  }
}

TEST(RadixSortTest, ScratchIsReusedAcrossCalls) {
  std::mt19937_64 rng(11);
  std::vector<Pair> scratch;
  for (int round = 0; round < 3; ++round) {
    std::vector<Pair> pairs(5000 + 1000 * round);
    for (size_t i = 0; i < pairs.size(); ++i) pairs[i] = {rng() >> 20, static_cast<uint32_t>(i)};
    std::vector<Pair> expected = pairs;
    std::sort(expected.begin(), expected.end());
    RadixSortByKey(&pairs, &scratch);
    EXPECT_TRUE(pairs == expected) << round;
  }
}

}  // namespace
}  // namespace slam_mms::internal
