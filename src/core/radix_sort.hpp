#pragma once
// RadixSortBy / RadixSortByKey / RadixSort: a stable least-significant-digit radix sort of records
// by a 64-bit key, for the library's voxel sorts (VoxelAccumulator::Cloud, VoxelDownsample, the
// final map's stamps, the map-entropy grid), which sort hundreds of thousands to millions of
// (packed cell key, index) pairs. std::sort compares and swaps its way through log2(n) ~ 20 passes
// over them; the radix sort makes one counting pass and one scatter pass per 11-bit digit, and
// skips every digit that is the same in all keys (packed cell keys of a local cloud vary in 3-5 of
// the 6 digits).
//
// Order: stable, so records given in ascending `second` order come out in (first, second)
// order: exactly the order std::sort gives the pairs, bit for bit (tests/core/radix_sort_test).
// Written here rather than taken from a package: Boost's integer_sort (spreadsort, in Debian's
// boost headers, not a dependency of this library) is not stable, and (key, index) pairs with
// repeated keys need the stable order; the sort is 30 lines.
//
// Memory: a scratch buffer of the input's size (the caller's, reused across calls).
// Private to the library (src/core; not installed). Thread safety: none needed (no state).

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace slam_mms::internal {

/// Sorts `items` by key_of(item) (a uint64_t), stably. `scratch` is resized to items->size() and
/// its contents are left unspecified; the two vectors may be swapped (their capacities travel
/// with them).
template <typename T, typename KeyOf>
void RadixSortBy(std::vector<T>* items, std::vector<T>* scratch, KeyOf key_of) {
  const size_t n = items->size();
  if (n < 2) return;
  uint64_t any = 0;
  uint64_t all = ~uint64_t{0};
  for (const T& t : *items) {
    any |= key_of(t);
    all &= key_of(t);
  }
  const uint64_t varying = any ^ all;  // the bits that differ between some two keys
  if (varying == 0) return;
  constexpr int kDigitBits = 11;
  constexpr uint64_t kDigitMask = (uint64_t{1} << kDigitBits) - 1;
  scratch->resize(n);
  std::vector<size_t> start(size_t{1} << kDigitBits);
  T* src = items->data();
  T* dst = scratch->data();
  for (int shift = 0; shift < 64; shift += kDigitBits) {
    if (((varying >> shift) & kDigitMask) == 0) continue;  // one digit value: order unchanged
    std::fill(start.begin(), start.end(), 0);
    for (size_t i = 0; i < n; ++i) ++start[(key_of(src[i]) >> shift) & kDigitMask];
    size_t offset = 0;
    for (size_t& s : start) {
      const size_t c = s;
      s = offset;
      offset += c;
    }
    for (size_t i = 0; i < n; ++i) dst[start[(key_of(src[i]) >> shift) & kDigitMask]++] = src[i];
    std::swap(src, dst);
  }
  if (src != items->data()) items->swap(*scratch);
}

/// Sorts records by their `first` member (uint64_t), stably.
template <typename T>
void RadixSortByKey(std::vector<T>* items, std::vector<T>* scratch) {
  RadixSortBy(items, scratch, [](const T& t) -> uint64_t { return t.first; });
}

/// Sorts plain keys.
inline void RadixSort(std::vector<uint64_t>* keys, std::vector<uint64_t>* scratch) {
  RadixSortBy(keys, scratch, [](uint64_t k) { return k; });
}

}  // namespace slam_mms::internal
