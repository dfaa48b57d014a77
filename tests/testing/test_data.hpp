#pragma once
// Test helpers: the location of the real KITTI data in ../shared/data and scratch folders.
#include <filesystem>
#include <string>
#include <system_error>

namespace slam_mms::testing {

/// The shared data folder: $SLAM_MMS_SHARED_DATA if set, else <source>/../shared/data.
std::filesystem::path SharedDataDir();

/// The real KITTI raw drive folder (.../kitti_raw/2011_09_26/2011_09_26_drive_0013_sync).
std::filesystem::path KittiRawDriveDir();

/// True when the real KITTI drive is present.
bool HasKittiRaw();

/// A fresh empty folder under the system temp dir, unique per test; removed by the caller if
/// wanted.
std::filesystem::path MakeTempDir(const std::string& tag);

/// MakeTempDir(tag), removed with everything in it when this goes out of scope (the simulated
/// drives are tens of MB).
struct ScopedTempDir {
  std::filesystem::path path;
  explicit ScopedTempDir(const std::string& tag) : path(MakeTempDir(tag)) {}
  ~ScopedTempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  ScopedTempDir(const ScopedTempDir&) = delete;
  ScopedTempDir& operator=(const ScopedTempDir&) = delete;
  operator const std::filesystem::path&() const {
    return path;
  }  // NOLINT(google-explicit-constructor)
};

}  // namespace slam_mms::testing

/// Skips the current test with a clear message where ../shared/data is absent.
#define SLAM_MMS_REQUIRE_KITTI_RAW()                                                             \
  do {                                                                                           \
    if (!::slam_mms::testing::HasKittiRaw()) {                                                   \
      GTEST_SKIP() << "real KITTI data not found at " << ::slam_mms::testing::KittiRawDriveDir() \
                   << " (set SLAM_MMS_SHARED_DATA to the shared/data folder to run this)";       \
    }                                                                                            \
  } while (0)
