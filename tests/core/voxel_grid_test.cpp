#include "core/voxel_grid.hpp"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <set>
#include <unordered_set>
#include <utility>
#include <vector>

namespace slam_mms::internal {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
__extension__ typedef __int128 Int128;

// Sign of c - k * s in exact arithmetic (an oracle independent of FloorQuotient's fma): both sides
// as integers times a common power of two in __int128. Returns 2 where the exponents are too far
// apart for 127 bits (the callers keep their values in range and check for it).
int ExactSign(double c, int64_t k, double s) {
  auto split = [](double v, int64_t* mantissa, int* exponent) {
    int e = 0;
    const double f = std::frexp(v, &e);  // v = f * 2^e, |f| in [0.5, 1)
    *mantissa = static_cast<int64_t>(std::ldexp(f, 53));
    *exponent = e - 53;
  };
  int64_t mc = 0, ms = 0;
  int ec = 0, es = 0;
  split(c, &mc, &ec);
  split(s, &ms, &es);
  if (c == 0.0) ec = es;
  const int e = std::min(ec, es);
  if (ec - e > 70 || es - e > 40) return 2;
  const Int128 one = 1;
  const Int128 a = static_cast<Int128>(mc) * (one << (ec - e));
  const Int128 b = static_cast<Int128>(k) * ms * (one << (es - e));
  return a < b ? -1 : (a > b ? 1 : 0);
}

// The oracle's floor: k with k * s <= c < (k + 1) * s.
bool IsExactFloor(double c, double s, int32_t k) {
  const int lo = ExactSign(c, k, s);
  const int hi = ExactSign(c, static_cast<int64_t>(k) + 1, s);
  EXPECT_NE(lo, 2);
  EXPECT_NE(hi, 2);
  return lo >= 0 && hi < 0;
}

// The grid's index (the multiplication fast path where it is safe) and FloorQuotient (the
// division): they must agree everywhere.
int32_t Index(double c, double s) {
  int32_t k = 0, fast = 0;
  EXPECT_TRUE(VoxelGrid::FloorQuotient(c, s, &k)) << c << " / " << s;
  EXPECT_TRUE(VoxelGrid(s).AxisIndex(c, 0, &fast)) << c << " / " << s;
  EXPECT_EQ(fast, k) << c << " / " << s;
  VoxelCell cell;  // the three-axis path, with c on one axis and easy values on the others
  EXPECT_TRUE(VoxelGrid(s).CellOf(Eigen::Vector3d(0.37 * s, c, -2.5 * s), &cell));
  EXPECT_EQ(cell, (VoxelCell{0, k, -3})) << c << " / " << s;
  return k;
}

TEST(VoxelGridTest, IndexIsTheExactFloorOfTheQuotient) {
  std::mt19937_64 rng(19);
  const double sizes[] = {0.1, 0.3, 0.05, 0.2, 0.25, 1.0, 10.0, 0.7, 1.0 / 3.0};
  std::uniform_real_distribution<double> u(-2000.0, 2000.0);
  int corrected = 0;  // cases where floor(c / s) alone is off by one
  for (double s : sizes) {
    for (int i = 0; i < 20000; ++i) {
      // Random points, the rounded faces fl(k * s) and their float neighbours (the hard cases).
      const double r = u(rng);
      const double face = std::floor(r / s) * s;
      for (double c : {r, face, std::nextafter(face, kInf), std::nextafter(face, -kInf),
                       static_cast<double>(static_cast<float>(face))}) {
        if (c != 0.0 && std::abs(c) < 1e-100) continue;  // the neighbours of 0: beyond the oracle
        const int32_t k = Index(c, s);
        EXPECT_TRUE(IsExactFloor(c, s, k)) << c << " / " << s << " -> " << k;
        if (static_cast<double>(k) != std::floor(c / s)) ++corrected;
      }
    }
  }
  EXPECT_GT(corrected, 0) << "no case exercised the correction";
}

TEST(VoxelGridTest, PointsOnFacesBelongToTheCellAbove) {
  // Power-of-two and integer sizes: the faces are doubles, the point on a face is in the cell
  // above it, on both sides of zero.
  for (double s : {0.125, 0.25, 0.5, 1.0, 2.0, 10.0}) {
    for (int k = -50; k <= 50; ++k) {
      const double face = k * s;
      EXPECT_EQ(Index(face, s), k) << face << " / " << s;
      EXPECT_EQ(Index(std::nextafter(face, -kInf), s), k - 1) << face << " / " << s;
      EXPECT_EQ(Index(std::nextafter(face, kInf), s), k) << face << " / " << s;
    }
  }
  // A decimal size is not a double: 0.1 is 0.1000000000000000055..., so 3.0 lies just below the
  // face of cell 30, although 3.0 / 0.1 rounds to exactly 30.
  EXPECT_EQ(3.0 / 0.1, 30.0);
  EXPECT_EQ(Index(3.0, 0.1), 29);
  EXPECT_EQ(30 * 0.1, 3.0);  // fl(30 * 0.1) rounds down below the face: cell 29 as well
  EXPECT_EQ(Index(30 * 0.1, 0.1), 29);
  EXPECT_EQ(Index(3 * 0.1, 0.1), 3);  // fl(3 * 0.1) = 0.30000000000000004, above the face
  EXPECT_EQ(Index(0.0, 0.1), 0);
  EXPECT_EQ(Index(-0.0, 0.1), 0);
}

TEST(VoxelGridTest, NegativeCoordinatesRoundDown) {
  EXPECT_EQ(Index(-0.05, 0.1), -1);
  EXPECT_EQ(Index(-1e-300, 0.1), -1);
  EXPECT_EQ(Index(-std::numeric_limits<double>::denorm_min(), 1.0), -1);
  EXPECT_EQ(Index(-0.25, 0.25), -1);
  EXPECT_EQ(Index(-0.2500001, 0.25), -2);
  EXPECT_EQ(Index(-2.5, 1.0), -3);
  VoxelGrid grid(0.5);
  VoxelCell c;
  ASSERT_TRUE(grid.CellOf(Eigen::Vector3f(-0.1f, -0.5f, -0.75f), &c));
  EXPECT_EQ(c, (VoxelCell{-1, -1, -2}));
}

TEST(VoxelGridTest, HugeAndNonFiniteCoordinatesAreRejected) {
  constexpr double kMax = VoxelGrid::kMaxIndex;
  int32_t k = 0;
  EXPECT_TRUE(VoxelGrid::FloorQuotient(kMax, 1.0, &k));
  EXPECT_EQ(k, VoxelGrid::kMaxIndex);
  EXPECT_EQ(Index(kMax, 1.0), VoxelGrid::kMaxIndex);
  EXPECT_EQ(Index(-kMax, 1.0), -VoxelGrid::kMaxIndex);
  EXPECT_FALSE(VoxelGrid(1.0).AxisIndex(kMax + 1.0, 0, &k));
  EXPECT_FALSE(VoxelGrid(1.0).AxisIndex(-kMax - 0.5, 0, &k));
  EXPECT_TRUE(VoxelGrid::FloorQuotient(kMax + 0.5, 1.0, &k));
  EXPECT_EQ(k, VoxelGrid::kMaxIndex);
  EXPECT_FALSE(VoxelGrid::FloorQuotient(kMax + 1.0, 1.0, &k));
  EXPECT_TRUE(VoxelGrid::FloorQuotient(-kMax, 1.0, &k));
  EXPECT_EQ(k, -VoxelGrid::kMaxIndex);
  EXPECT_FALSE(VoxelGrid::FloorQuotient(-kMax - 0.5, 1.0, &k));
  k = 7;
  for (double c : {1e300, -1e300, 1.1e8, -1.1e8, kInf, -kInf, kNaN}) {
    EXPECT_FALSE(VoxelGrid::FloorQuotient(c, 0.1, &k)) << c;
    EXPECT_FALSE(VoxelGrid(0.1).AxisIndex(c, 0, &k)) << c;
  }
  EXPECT_EQ(k, 7) << "a failed call must leave the index alone";
  // 1e8 m at 0.1 m is in range (index 1e9 < 2^30 - 1): no overflow far from the origin.
  EXPECT_EQ(Index(1e8, 0.1), 999999999);
  EXPECT_EQ(Index(-1e8, 0.1), -1000000000);

  VoxelGrid grid(0.1);
  VoxelCell c;
  EXPECT_FALSE(grid.CellOf(Eigen::Vector3d(0, kNaN, 0), &c));
  EXPECT_FALSE(grid.CellOf(Eigen::Vector3f(0, 0, std::numeric_limits<float>::infinity()), &c));
  EXPECT_FALSE(grid.CellOf(Eigen::Vector3f(3e8f, 0, 0), &c));
  EXPECT_TRUE(grid.CellOf(Eigen::Vector3f(1e7f, -1e7f, 0), &c));
  // 1e7 / 0.1 rounds to 1e8, but the exact quotient is 99999999.99999999...
  EXPECT_EQ(c, (VoxelCell{99999999, -100000000, 0}));

  // Saturation for containers that must file every point.
  EXPECT_EQ(grid.ClampedCellOf(Eigen::Vector3d(1e300, -kInf, kNaN)),
            (VoxelCell{VoxelGrid::kMaxIndex, -VoxelGrid::kMaxIndex, 0}));
  EXPECT_EQ(grid.ClampedCellOf(Eigen::Vector3d(0.15, -0.05, 0.0)), (VoxelCell{1, -1, 0}));
}

TEST(VoxelGridTest, InvalidSizesRejectEveryPoint) {
  EXPECT_FALSE(VoxelGrid::ValidSize(0.0));
  EXPECT_FALSE(VoxelGrid::ValidSize(-1.0));
  EXPECT_FALSE(VoxelGrid::ValidSize(kNaN));
  EXPECT_FALSE(VoxelGrid::ValidSize(kInf));
  EXPECT_TRUE(VoxelGrid::ValidSize(1e-9));
  VoxelCell c;
  for (double s : {0.0, -1.0, kNaN, kInf}) {
    EXPECT_FALSE(VoxelGrid(s).CellOf(Eigen::Vector3d(1, 2, 3), &c)) << s;
    EXPECT_FALSE(VoxelGrid(s).CellOf(Eigen::Vector3d(0, 0, 0), &c)) << s;
  }
}

TEST(VoxelGridTest, CellsContainTheirPointsAndHonourTheOrigin) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-500.0f, 500.0f);
  for (double s : {0.25, 0.5, 2.0}) {  // exact corners
    const VoxelGrid grid(s, Eigen::Vector3d(0.125, -0.375, 4.0));
    for (int i = 0; i < 5000; ++i) {
      const Eigen::Vector3f p(u(rng), u(rng), u(rng));
      VoxelCell c;
      ASSERT_TRUE(grid.CellOf(p, &c));
      const Eigen::Vector3d lo = grid.Corner(c);
      for (int a = 0; a < 3; ++a) {
        EXPECT_LE(lo[a], p[a]);
        EXPECT_LT(static_cast<double>(p[a]), lo[a] + s);
      }
    }
    VoxelCell c;
    ASSERT_TRUE(grid.CellOf(grid.origin(), &c));
    EXPECT_EQ(c, (VoxelCell{0, 0, 0}));
    ASSERT_TRUE(grid.CellOf(Eigen::Vector3d(grid.origin() - Eigen::Vector3d::Constant(1e-9)), &c));
    EXPECT_EQ(c, (VoxelCell{-1, -1, -1}));
  }
}

TEST(VoxelGridTest, HashSeparatesCellsTheOldPackedKeysConfused) {
  // A block of cells around the origin and the same block shifted by 2^21 cells per axis (what a
  // 21-bit key wrapped onto the first block): all hashes distinct, and the low bits spread.
  std::unordered_set<uint64_t> hashes;
  std::vector<int> buckets(1 << 12, 0);
  size_t cells = 0;
  for (int64_t shift : {int64_t{0}, int64_t{1} << 21}) {
    for (int x = -16; x < 16; ++x) {
      for (int y = -16; y < 16; ++y) {
        for (int z = -16; z < 16; ++z) {
          const VoxelCell c{static_cast<int32_t>(x + shift), static_cast<int32_t>(y + shift),
                            static_cast<int32_t>(z + shift)};
          const uint64_t h = HashVoxelCell(c);
          EXPECT_EQ(h, HashVoxelCell(VoxelCell{c.x, c.y, c.z}));
          hashes.insert(h);
          ++buckets[h & (buckets.size() - 1)];
          ++cells;
        }
      }
    }
  }
  EXPECT_EQ(hashes.size(), cells);
  // 65536 cells in 4096 buckets: 16 per bucket on average; a poor hash piles them up.
  EXPECT_LT(*std::max_element(buckets.begin(), buckets.end()), 48);
  EXPECT_EQ(VoxelCellHash()(VoxelCell{1, 2, 3}), static_cast<size_t>(HashVoxelCell({1, 2, 3})));
}

TEST(VoxelGridTest, PackedKeysAreExactOrderedAndNeverWrap) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int32_t> u(-(1 << 20), (1 << 20) - 1);
  std::vector<std::pair<uint64_t, VoxelCell>> keyed;
  for (int i = 0; i < 20000; ++i) {
    const VoxelCell c{u(rng), u(rng), u(rng)};
    uint64_t key = 0;
    ASSERT_TRUE(PackVoxelCell(c, kVoxelPackCentred, &key));
    EXPECT_EQ(UnpackVoxelCell(key, kVoxelPackCentred), c);
    EXPECT_EQ(key >> 63, 0u);
    keyed.emplace_back(key, c);
  }
  std::sort(keyed.begin(), keyed.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  for (size_t i = 1; i < keyed.size(); ++i) {
    EXPECT_FALSE(keyed[i].second < keyed[i - 1].second) << "key order != cell order at " << i;
  }
  // The span's edges, and one past them on each side: refused, key untouched.
  uint64_t key = 42;
  constexpr int32_t kHalf = 1 << 20;
  EXPECT_TRUE(PackVoxelCell({-kHalf, kHalf - 1, 0}, kVoxelPackCentred, &key));
  key = 42;
  EXPECT_FALSE(PackVoxelCell({kHalf, 0, 0}, kVoxelPackCentred, &key));
  EXPECT_FALSE(PackVoxelCell({0, -kHalf - 1, 0}, kVoxelPackCentred, &key));
  EXPECT_FALSE(PackVoxelCell({0, 0, VoxelGrid::kMaxIndex}, kVoxelPackCentred, &key));
  EXPECT_EQ(key, 42u);
  // A base moves the span: cells in [base, base + 2^21).
  const VoxelCell base{1000, -5, 1 << 25};
  ASSERT_TRUE(PackVoxelCell({1000, -5, 1 << 25}, base, &key));
  EXPECT_EQ(key, 0u);
  ASSERT_TRUE(PackVoxelCell({1001, (1 << 21) - 6, (1 << 25) + 7}, base, &key));
  EXPECT_EQ(UnpackVoxelCell(key, base), (VoxelCell{1001, (1 << 21) - 6, (1 << 25) + 7}));
  EXPECT_FALSE(PackVoxelCell({999, 0, 1 << 25}, base, &key));
}

// FittedCellKey: exact round trip of cell and payload, keys ordered like (cell, payload), widths
// from the bounds (a set that needs more than 64 bits does not fit).
TEST(FittedCellKeyTest, RoundTripAndOrder) {
  const VoxelCell lo{-1000, 5000, -3};
  const VoxelCell hi{2000, 5300, 60};
  const FittedCellKey layout(lo, hi, BitWidth(99999));
  ASSERT_TRUE(layout.fits());
  std::mt19937 rng(2);
  std::uniform_int_distribution<int32_t> x(lo.x, hi.x), y(lo.y, hi.y), z(lo.z, hi.z);
  std::uniform_int_distribution<uint32_t> payload(0, 99999);
  std::vector<std::pair<VoxelCell, uint32_t>> items(5000);
  for (auto& item : items) item = {{x(rng), y(rng), z(rng)}, payload(rng)};
  items.push_back({lo, 0});
  items.push_back({hi, 99999});
  for (const auto& [cell, p] : items) {
    const uint64_t key = layout.Pack(cell, p);
    ASSERT_TRUE(layout.Cell(key) == cell);
    ASSERT_EQ(layout.Payload(key), p);
  }
  for (size_t i = 1; i < items.size(); ++i) {
    const auto& a = items[i - 1];
    const auto& b = items[i];
    const bool less = a.first != b.first ? a.first < b.first : a.second < b.second;
    EXPECT_EQ(layout.Pack(a.first, a.second) < layout.Pack(b.first, b.second), less) << i;
  }
  // One cell, no payload: a zero-width key.
  const FittedCellKey one(lo, lo, 0);
  EXPECT_EQ(one.Pack(lo, 0), 0u);
  EXPECT_TRUE(one.Cell(0) == lo);
  // 3 x 22 bits of span: more than one 64-bit word.
  EXPECT_FALSE(FittedCellKey({0, 0, 0}, {1 << 21, 1 << 21, 1 << 21}, 0).fits());
  EXPECT_EQ(BitWidth(0), 0);
  EXPECT_EQ(BitWidth(1), 1);
  EXPECT_EQ(BitWidth(~uint64_t{0}), 64);
}

}  // namespace
}  // namespace slam_mms::internal
