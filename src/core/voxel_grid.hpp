#pragma once
// VoxelGrid: the one voxel-cell arithmetic of the library (issue #19). Every grid of cubic cells
// (VoxelDownsample, the pipeline's VoxelAccumulator, the surfel VoxelIndex, PointIcp's source
// reduction, the map-entropy neighbour grid, the calibration and simulator subsampling) takes its
// cell indices, cell corners, hashes and packed keys from here, so that one point falls in the
// same cell everywhere. Private to the library (src/core; not installed).
//
// Cell index. Along each axis, the cell of coordinate c is the EXACT floor of the real quotient
//     k = floor((c - origin) / size)
// of the double values (c - origin is rounded to double first; with the default zero origin it is
// exact). Equivalently, in exact arithmetic, origin + k * size <= c < origin + (k + 1) * size: a
// point exactly on a cell face belongs to the cell above the face. It costs one multiplication by
// 1 / size where the product is clearly inside a cell; only within 2^-50 (relative) of a face a
// division, corrected by one fused multiply-add where the division rounded up onto an integer
// (the only way the floor of a correctly rounded quotient can be off, and then by one). Note
// that a decimal voxel size is not a double: with size 0.1 (= 0.1000000000000000055...) the face
// of cell 30 lies 1.7e-16 m above 3.0, so the point x = 3.0 is in cell 29.
//
// Range. Indices are limited to [-kMaxIndex, kMaxIndex] (2^30 - 1: 1.07e8 m, a hundred thousand km,
// at 0.1 m), so that neighbour arithmetic (k +- 1, hi - lo + 1) never overflows int32. CellOf fails
// (returns false) for a non-finite coordinate and for one outside that range; ClampedCellOf
// saturates instead.
//
// Keys. A VoxelCell (three int32) is the exact key of a cell; HashVoxelCell mixes all 96 bits into
// 64 for hash tables (tables compare the full cell, so hash collisions cost time, never merge
// cells). PackVoxelCell is the one compact key of a fixed layout: 21 bits per axis of
// (cell - base), exact and ordered like (x, y, z) within a span of 2^21 cells per axis, and it
// fails outside that span (no silent wrap). FittedCellKey is the one key fitted to a known set of
// cells (as many bits per axis as the set spans, low bits left for a payload such as an index),
// for the voxel sorts that radix-sort one 64-bit word per point.
//
// Thread safety: value types and pure functions; safe to use concurrently.

#include <Eigen/Core>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

namespace slam_mms::internal {

/// Integer index of one cell. Ordered lexicographically by (x, y, z).
struct VoxelCell {
  int32_t x = 0, y = 0, z = 0;

  int32_t operator[](int axis) const { return axis == 0 ? x : (axis == 1 ? y : z); }
  friend bool operator==(const VoxelCell& a, const VoxelCell& b) {
    return a.x == b.x && a.y == b.y && a.z == b.z;
  }
  friend bool operator!=(const VoxelCell& a, const VoxelCell& b) { return !(a == b); }
  friend bool operator<(const VoxelCell& a, const VoxelCell& b) {
    if (a.x != b.x) return a.x < b.x;
    if (a.y != b.y) return a.y < b.y;
    return a.z < b.z;
  }
};

/// 64-bit hash of a cell (splitmix64 finaliser over the 96 bits): every input bit reaches every
/// output bit, so both the low bits (modulo tables) and the high bits (Fibonacci-style tables)
/// may index a table.
inline uint64_t HashVoxelCell(const VoxelCell& c) {
  uint64_t h = (static_cast<uint64_t>(static_cast<uint32_t>(c.x)) << 32) |
               static_cast<uint64_t>(static_cast<uint32_t>(c.y));
  h ^= static_cast<uint64_t>(static_cast<uint32_t>(c.z)) * 0x9E3779B97F4A7C15ull;
  h ^= h >> 30;
  h *= 0xBF58476D1CE4E5B9ull;
  h ^= h >> 27;
  h *= 0x94D049BB133111EBull;
  h ^= h >> 31;
  return h;
}

/// For std::unordered_map / std::unordered_set.
struct VoxelCellHash {
  size_t operator()(const VoxelCell& c) const { return static_cast<size_t>(HashVoxelCell(c)); }
};

/// Bits per axis of a packed key (3 x 21 = 63 bits; the top bit is always 0).
inline constexpr int kVoxelPackBits = 21;
/// Cells per axis a packed key spans: each axis of cell - base must lie in [0, kVoxelPackSpan).
inline constexpr int64_t kVoxelPackSpan = int64_t{1} << kVoxelPackBits;
/// The base that centres the packed span on the origin: indices in [-2^20, 2^20).
inline constexpr VoxelCell kVoxelPackCentred{-(1 << 20), -(1 << 20), -(1 << 20)};

/// Packs cell - base into (dx << 42) | (dy << 21) | dz. Exact and order-preserving (key order ==
/// VoxelCell order) where every axis of cell - base is in [0, 2^21); otherwise returns false and
/// leaves *key alone (never wraps).
[[nodiscard]] inline bool PackVoxelCell(const VoxelCell& cell, const VoxelCell& base,
                                        uint64_t* key) {
  const int64_t d[3] = {static_cast<int64_t>(cell.x) - base.x,
                        static_cast<int64_t>(cell.y) - base.y,
                        static_cast<int64_t>(cell.z) - base.z};
  for (int64_t v : d) {
    if (v < 0 || v >= kVoxelPackSpan) return false;
  }
  *key = (static_cast<uint64_t>(d[0]) << (2 * kVoxelPackBits)) |
         (static_cast<uint64_t>(d[1]) << kVoxelPackBits) | static_cast<uint64_t>(d[2]);
  return true;
}

/// Inverse of PackVoxelCell (key as packed with the same base).
inline VoxelCell UnpackVoxelCell(uint64_t key, const VoxelCell& base) {
  constexpr uint64_t kMask = static_cast<uint64_t>(kVoxelPackSpan - 1);
  return {
      static_cast<int32_t>(static_cast<int64_t>((key >> (2 * kVoxelPackBits)) & kMask) + base.x),
      static_cast<int32_t>(static_cast<int64_t>((key >> kVoxelPackBits) & kMask) + base.y),
      static_cast<int32_t>(static_cast<int64_t>(key & kMask) + base.z)};
}

/// Bits needed to write v (0 for 0).
inline int BitWidth(uint64_t v) { return v == 0 ? 0 : 64 - __builtin_clzll(v); }

/// A 64-bit key fitted to the cells in [lo, hi] (per axis): (cell - lo) with as many bits per
/// axis as hi - lo needs, x highest, then the payload in the low `payload_bits`. Exact, and keys
/// order like (cell, payload). Usable where fits(): the widths total <= 64.
class FittedCellKey {
 public:
  /// lo <= hi per axis (the bounds of the cells that will be packed).
  FittedCellKey(const VoxelCell& lo, const VoxelCell& hi, int payload_bits)
      : lo_(lo),
        bx_(Width(lo.x, hi.x)),
        by_(Width(lo.y, hi.y)),
        bz_(Width(lo.z, hi.z)),
        bp_(payload_bits) {}
  bool fits() const { return bx_ + by_ + bz_ + bp_ <= 64; }
  /// `cell` in [lo, hi], `payload` < 2^payload_bits.
  uint64_t Pack(const VoxelCell& cell, uint64_t payload) const {
    uint64_t key = Offset(cell.x, lo_.x);
    key = (key << by_) | Offset(cell.y, lo_.y);
    key = (key << bz_) | Offset(cell.z, lo_.z);
    return bp_ == 0 ? key : (key << bp_) | payload;
  }
  uint64_t Payload(uint64_t key) const { return Field(key, 0, bp_); }
  VoxelCell Cell(uint64_t key) const {
    return {static_cast<int32_t>(static_cast<int64_t>(Field(key, bp_ + bz_ + by_, bx_)) + lo_.x),
            static_cast<int32_t>(static_cast<int64_t>(Field(key, bp_ + bz_, by_)) + lo_.y),
            static_cast<int32_t>(static_cast<int64_t>(Field(key, bp_, bz_)) + lo_.z)};
  }

 private:
  static int Width(int32_t lo, int32_t hi) {
    return hi <= lo ? 0 : BitWidth(static_cast<uint64_t>(static_cast<int64_t>(hi) - lo));
  }
  static uint64_t Offset(int32_t v, int32_t lo) {
    return static_cast<uint64_t>(static_cast<int64_t>(v) - lo);
  }
  static uint64_t Field(uint64_t key, int shift, int width) {
    return width == 0 ? uint64_t{0} : (key >> shift) & (~uint64_t{0} >> (64 - width));
  }
  VoxelCell lo_;
  int bx_, by_, bz_, bp_;
};

/// Cubic cells of edge size() with a corner at origin() (see the top of this file).
class VoxelGrid {
 public:
  /// The largest |index| of a cell.
  static constexpr int32_t kMaxIndex = (int32_t{1} << 30) - 1;

  /// Unit cells at the world origin.
  VoxelGrid() = default;
  /// size_m must be finite and > 0 (ValidSize); with any other size every CellOf fails.
  explicit VoxelGrid(double size_m, const Eigen::Vector3d& origin = Eigen::Vector3d::Zero())
      : size_(ValidSize(size_m) ? size_m : std::numeric_limits<double>::quiet_NaN()),
        inv_(1.0 / size_),
        origin_(origin) {}

  [[nodiscard]] static bool ValidSize(double size_m) {
    return size_m > 0.0 && size_m <= std::numeric_limits<double>::max();
  }

  double size() const { return size_; }
  const Eigen::Vector3d& origin() const { return origin_; }

  /// Index along `axis` of coordinate c: floor((c - origin[axis]) / size), exact; false where c
  /// is not finite or the index is outside [-kMaxIndex, kMaxIndex].
  [[nodiscard]] bool AxisIndex(double c, int axis, int32_t* index) const {
    const double d = c - origin_[axis];
    // Fast path: d * (1 / size) is within 2.3e-16 |q| of the real quotient (two roundings), so
    // where it lies farther than 2^-50 |q| from every integer its floor is the exact one. Near a
    // face (and for |q| below DBL_MIN, where products lose relative precision) the exact path.
    const double q = d * inv_;
    if (!(q > -kFastLimit && q < kFastLimit)) return FloorQuotient(d, size_, index);  // NaN, range
    const double k = Floor(q);
    const double frac = q - k;  // exact: q and k share their exponent range
    const double tol = std::abs(q) * 0x1p-50 + std::numeric_limits<double>::min();
    if (frac < tol || frac > 1.0 - tol) return FloorQuotient(d, size_, index);
    *index = static_cast<int32_t>(k);
    return true;
  }

  [[nodiscard]] bool CellOf(const Eigen::Vector3d& p, VoxelCell* cell) const {
    // AxisIndex's fast path on the three axes without branches, then one test; any axis near a
    // face, out of range or NaN sends the point through AxisIndex (the same result, slower).
    double k[3];
    bool fast = true;
    for (int a = 0; a < 3; ++a) {
      const double q = (p[a] - origin_[a]) * inv_;
      const bool in_range = q > -kFastLimit && q < kFastLimit;
      const double qr = in_range ? q : 0.0;
      k[a] = Floor(qr);
      const double frac = qr - k[a];
      const double tol = std::abs(qr) * 0x1p-50 + std::numeric_limits<double>::min();
      fast &= in_range & (frac >= tol) & (frac <= 1.0 - tol);
    }
    if (fast) {
      *cell = {static_cast<int32_t>(k[0]), static_cast<int32_t>(k[1]), static_cast<int32_t>(k[2])};
      return true;
    }
    return AxisIndex(p.x(), 0, &cell->x) && AxisIndex(p.y(), 1, &cell->y) &&
           AxisIndex(p.z(), 2, &cell->z);
  }
  /// A float point, widened to double exactly.
  [[nodiscard]] bool CellOf(const Eigen::Vector3f& p, VoxelCell* cell) const {
    return CellOf(Eigen::Vector3d(p.cast<double>()), cell);
  }

  /// The cell of p with every index saturated to [-kMaxIndex, kMaxIndex] (a NaN coordinate gives
  /// index 0), for containers that must file every point somewhere.
  VoxelCell ClampedCellOf(const Eigen::Vector3d& p) const {
    VoxelCell c;
    int32_t* out[3] = {&c.x, &c.y, &c.z};
    for (int a = 0; a < 3; ++a) {
      if (AxisIndex(p[a], a, out[a])) continue;
      const double q = (p[a] - origin_[a]) / size_;
      *out[a] = q > 0.0 ? kMaxIndex : (q < 0.0 ? -kMaxIndex : 0);
    }
    return c;
  }
  VoxelCell ClampedCellOf(const Eigen::Vector3f& p) const {
    return ClampedCellOf(Eigen::Vector3d(p.cast<double>()));
  }

  /// Lower face of cell `index` along `axis`: origin[axis] + index * size, rounded to double
  /// (exact where the product is representable, e.g. power-of-two or integer sizes).
  double Lower(int32_t index, int axis) const {
    return origin_[axis] + static_cast<double>(index) * size_;
  }
  /// The cell's lowest corner (Lower on each axis).
  Eigen::Vector3d Corner(const VoxelCell& c) const {
    return {Lower(c.x, 0), Lower(c.y, 1), Lower(c.z, 2)};
  }

  /// floor(c / s) of the real quotient of the doubles c and s > 0; false where it is not finite or
  /// outside [-kMaxIndex, kMaxIndex]. Public for the tests.
  [[nodiscard]] static bool FloorQuotient(double c, double s, int32_t* index) {
    const double q = c / s;
    if (!(q > -kLimit && q < kLimit)) return false;  // also NaN: every comparison with it is false
    double k = Floor(q);
    // A correctly rounded quotient is >= the exact one's floor and below floor + 1 unless it
    // rounded up onto an integer; only then check the sign of the exact c - k * s (one rounding:
    // the sign survives it).
    if (k == q && std::fma(-k, s, c) < 0.0) k -= 1.0;
    if (k < -static_cast<double>(kMaxIndex) || k > static_cast<double>(kMaxIndex)) return false;
    *index = static_cast<int32_t>(k);
    return true;
  }

 private:
  /// floor(q) for |q| < kLimit by truncation (std::floor is a library call on baseline x86-64).
  static double Floor(double q) {
    const double t = static_cast<double>(static_cast<int32_t>(q));
    return q < t ? t - 1.0 : t;
  }
  /// |quotients| at or beyond this are out of range (kMaxIndex + 2: the floor decides the rest).
  static constexpr double kLimit = static_cast<double>(kMaxIndex) + 2.0;
  /// The fast paths take |q| < kMaxIndex only (their floor is then in range without a check).
  static constexpr double kFastLimit = static_cast<double>(kMaxIndex);

  double size_ = 1.0;
  double inv_ = 1.0;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
};

}  // namespace slam_mms::internal
