#pragma once
// Spill files of submap point clouds: a small binary format private to the pipeline, written when
// a finished submap's cloud leaves memory (Localizer::Options::spill_dir) and read back on demand.
//
//   "SMMSCLD1" (8 bytes) | uint64 point count n | n x (float x, y, z, intensity), little endian
//
// Per-point time offsets are not stored (the accumulated map clouds have none).

#include <filesystem>
#include <string>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms::internal {

/// Writes `cloud` to `path` (replacing it). Unavailable naming the file when it cannot be written
/// completely (e.g. the disk is full); a partial file is removed.
Status WriteCloudFile(const std::filesystem::path& path, const PointCloud& cloud);

/// Reads a file written by WriteCloudFile. NotFound when it cannot be opened; DataLoss naming the
/// file and what is wrong (magic, count, size) when it is truncated or corrupt.
StatusOr<PointCloud> ReadCloudFile(const std::filesystem::path& path);

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
  Status Spill(const std::string& name, PointCloud* cloud, std::filesystem::path* file) const;

 private:
  void Remove();
  std::filesystem::path path_;
};

/// `cloud` when `file` is empty, else the cloud read back from `file`.
StatusOr<PointCloud> CloudFromMemoryOrFile(const PointCloud& cloud,
                                           const std::filesystem::path& file);

}  // namespace slam_mms::internal
