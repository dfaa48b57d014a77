#pragma once
// Spill files of submap point clouds: a small binary format private to the pipeline, written when
// a finished submap's cloud leaves memory (Localizer::Options::spill_dir) and read back on demand.
//
//   "SMMSCLD1" (8 bytes) | uint64 point count n | n x (float x, y, z, intensity), little endian
//   "SMMSCLD2": the same, then n x int64 first-observation time [ns], n x int64 scan index
//               (MapPointStamps), written when the cloud has stamps.
//
// Per-point time offsets are not stored (the accumulated map clouds have none).

#include <filesystem>
#include <string>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/map_point_stamps.hpp"

namespace slam_mms::internal {

/// Writes `cloud` to `path` (replacing it). Unavailable naming the file when it cannot be written
/// completely (e.g. the disk is full); a partial file is removed.
/// `stamps` (may be null or empty; else one per point) makes it an SMMSCLD2 file.
Status WriteCloudFile(const std::filesystem::path& path, const PointCloud& cloud,
                      const MapPointStamps* stamps = nullptr);

/// Reads a file written by WriteCloudFile. NotFound when it cannot be opened; DataLoss naming the
/// file and what is wrong (magic, count, size) when it is truncated or corrupt.
/// `stamps` (may be null) gets the file's stamps (cleared for an SMMSCLD1 file).
StatusOr<PointCloud> ReadCloudFile(const std::filesystem::path& path,
                                   MapPointStamps* stamps = nullptr);

/// A private folder of spill files, removed with everything in it when the object goes (move-only).
/// A default-constructed one is disabled: clouds stay in memory.
class SpillFolder {
 public:
  SpillFolder() = default;
  /// Creates "slam_mms_spill_<pid>_<n>_<t>" inside `parent` (unique per process and call).
  /// Unavailable naming the folder when it cannot be created.
  static StatusOr<SpillFolder> Create(const std::filesystem::path& parent);
  SpillFolder(SpillFolder&& other) noexcept;
  SpillFolder& operator=(SpillFolder&& other) noexcept;
  SpillFolder(const SpillFolder&) = delete;
  SpillFolder& operator=(const SpillFolder&) = delete;
  ~SpillFolder();

  bool enabled() const { return !path_.empty(); }
  const std::filesystem::path& path() const { return path_; }

  /// Moves `*cloud` to the file `name` in the folder: then `*file` names it and `*cloud` is empty.
  /// Does nothing when disabled or `*file` is already set; on a write error both stay as they were
  /// and the error is returned.
  /// `stamps` (may be null) go with the cloud (and are emptied with it).
  Status Spill(const std::string& name, PointCloud* cloud, std::filesystem::path* file,
               MapPointStamps* stamps = nullptr) const;

 private:
  void Remove();
  std::filesystem::path path_;
};

/// `cloud` when `file` is empty, else the cloud read back from `file`; `stamps_out` (may be null)
/// gets `stamps` (memory) or the file's.
StatusOr<PointCloud> CloudFromMemoryOrFile(const PointCloud& cloud,
                                           const std::filesystem::path& file,
                                           const MapPointStamps* stamps = nullptr,
                                           MapPointStamps* stamps_out = nullptr);

}  // namespace slam_mms::internal
