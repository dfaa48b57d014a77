#pragma once
// Private helpers of the io module: little/big-endian scalar reads and writes on byte buffers.

#include <cstdint>
#include <cstring>
#include <string>

namespace slam_mms::io_internal {

constexpr bool kHostIsLittleEndian = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

template <typename T>
T ReadScalar(const char* p, bool little_endian) {
  T v;
  if (little_endian == kHostIsLittleEndian) {
    std::memcpy(&v, p, sizeof(T));
  } else {
    char tmp[sizeof(T)];
    for (size_t i = 0; i < sizeof(T); ++i) tmp[i] = p[sizeof(T) - 1 - i];
    std::memcpy(&v, tmp, sizeof(T));
  }
  return v;
}

/// Appends `v` in little-endian byte order.
template <typename T>
void AppendLe(std::string* out, T v) {
  char tmp[sizeof(T)];
  std::memcpy(tmp, &v, sizeof(T));
  if (!kHostIsLittleEndian) {
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(tmp[i], tmp[sizeof(T) - 1 - i]);
  }
  out->append(tmp, sizeof(T));
}

/// Writes `v` little-endian at `p`.
template <typename T>
void PutLe(char* p, T v) {
  std::memcpy(p, &v, sizeof(T));
  if (!kHostIsLittleEndian) {
    for (size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(p[i], p[sizeof(T) - 1 - i]);
  }
}

}  // namespace slam_mms::io_internal
