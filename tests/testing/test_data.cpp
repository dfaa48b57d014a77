#include "testing/test_data.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <random>

namespace slam_mms::testing {

std::filesystem::path SharedDataDir() {
  if (const char* env = std::getenv("SLAM_MMS_SHARED_DATA"); env != nullptr && *env != '\0') {
    return env;
  }
  return SLAM_MMS_DEFAULT_SHARED_DATA;
}

std::filesystem::path KittiRawDriveDir() {
  return SharedDataDir() / "kitti_raw" / "2011_09_26" / "2011_09_26_drive_0013_sync";
}

bool HasKittiRaw() {
  std::error_code ec;
  return std::filesystem::is_directory(KittiRawDriveDir() / "velodyne_points", ec);
}

std::filesystem::path MakeTempDir(const std::string& tag) {
  static std::atomic<int> counter{0};
  std::random_device rd;
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::string name = tag;
  if (info != nullptr) name += std::string("_") + info->test_suite_name() + "_" + info->name();
  for (char& c : name) {
    if (c == '/') c = '_';
  }
  const auto dir =
      std::filesystem::temp_directory_path() /
      ("slam_mms_test_" + name + "_" + std::to_string(rd()) + "_" + std::to_string(counter++));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace slam_mms::testing
