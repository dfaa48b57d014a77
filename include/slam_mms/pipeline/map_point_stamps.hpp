#pragma once
// MapPointStamps: per point of a map cloud, when and in which scan it was first observed.
//
// The map clouds (SubmapRecord::cloud, MappingSystem::FinalMap) are voxel centroids of many
// scans' points; each voxel keeps the absolute time of its first point (the scan's start plus
// that point's own firing offset) and that scan's index. Map writers use them for the LAS GPS
// time and point source ID. Thread safety: value type.

#include <cstddef>
#include <cstdint>
#include <vector>

namespace slam_mms {

struct MapPointStamps {
  std::vector<int64_t> time_ns;     ///< UTC nanoseconds since the Unix epoch (Timestamp).
  std::vector<int64_t> scan_index;  ///< Scan::index of that point's scan (the drive's frame).

  size_t size() const { return time_ns.size(); }
  bool empty() const { return time_ns.empty(); }
  void clear() {
    time_ns.clear();
    scan_index.clear();
  }
};

}  // namespace slam_mms
