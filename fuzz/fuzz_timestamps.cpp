// libFuzzer target: a KITTI timestamps.txt file's bytes -> stamps (sync: no blank lines; extract:
// blank = lost record), as KittiRawReader reads them; every stamp must round-trip through
// ToKittiString and the stamps must be strictly increasing.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/file_util.hpp"
#include "slam_mms/io/kitti_timestamp.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slam_mms;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const auto lines = io_internal::SplitLines(bytes);
  for (const bool allow_blank : {false, true}) {
    auto stamps = io_internal::ParseTimestampLines(lines, "timestamps.txt", allow_blank);
    if (!stamps.ok()) continue;
    const Timestamp* previous = nullptr;
    for (const auto& s : *stamps) {
      if (!s) continue;
      auto again = ParseKittiTimestamp(s->ToKittiString());
      if (!again.ok() || *again != *s) __builtin_trap();
      if (previous != nullptr && !(*previous < *s)) __builtin_trap();
      previous = &*s;
    }
  }
  return 0;
}
