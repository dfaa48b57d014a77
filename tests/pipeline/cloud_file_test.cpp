// Spill files of submap clouds (src/pipeline/cloud_file): round trip and every corruption named.
#include "pipeline/cloud_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace slam_mms::internal {
namespace {

namespace fs = std::filesystem;

class CloudFileTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("slam_mms_cloud_file_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  static PointCloud MakeCloud(size_t n) {
    PointCloud c;
    for (size_t i = 0; i < n; ++i) {
      const float f = static_cast<float>(i);
      c.Add(Eigen::Vector3f(0.1f * f, -2.0f * f, 1e3f + f), 0.001f * f);
    }
    return c;
  }
  fs::path dir_;
};

TEST_F(CloudFileTest, RoundTripIsExact) {
  for (size_t n : {size_t{0}, size_t{1}, size_t{4095}, size_t{4096}, size_t{10001}}) {
    const PointCloud c = MakeCloud(n);
    const fs::path p = dir_ / "c.bin";
    ASSERT_TRUE(WriteCloudFile(p, c).ok());
    EXPECT_EQ(fs::file_size(p), 16u + 16u * n);
    auto r = ReadCloudFile(p);
    ASSERT_TRUE(r.ok()) << r.status().ToString();
    ASSERT_EQ(r->size(), n);
    for (size_t i = 0; i < n; ++i) {
      EXPECT_EQ(r->points()[i], c.points()[i]);
      EXPECT_EQ(r->intensities()[i], c.intensities()[i]);
    }
  }
}

TEST_F(CloudFileTest, StampsRoundTripAndTruncatedStampsAreDataLoss) {
  const PointCloud c = MakeCloud(5000);
  MapPointStamps stamps;
  for (size_t i = 0; i < c.size(); ++i) {
    stamps.time_ns.push_back(1317042651000000000 + static_cast<int64_t>(i) * 12345);
    stamps.scan_index.push_back(static_cast<int64_t>(i / 100));
  }
  const fs::path p = dir_ / "s.bin";
  ASSERT_TRUE(WriteCloudFile(p, c, &stamps).ok());
  EXPECT_EQ(fs::file_size(p), 16u + 32u * c.size());
  MapPointStamps back;
  auto r = ReadCloudFile(p, &back);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  EXPECT_EQ(r->points(), c.points());
  EXPECT_EQ(back.time_ns, stamps.time_ns);
  EXPECT_EQ(back.scan_index, stamps.scan_index);
  // A version-1 file (no stamps) clears them.
  ASSERT_TRUE(WriteCloudFile(dir_ / "v1.bin", c).ok());
  ASSERT_TRUE(ReadCloudFile(dir_ / "v1.bin", &back).ok());
  EXPECT_TRUE(back.empty());
  fs::resize_file(p, fs::file_size(p) - 8);
  EXPECT_EQ(ReadCloudFile(p, &back).status().code(), StatusCode::kDataLoss);
  // The spill folder moves the stamps with the cloud and gives them back.
  auto folder = SpillFolder::Create(dir_);
  ASSERT_TRUE(folder.ok());
  PointCloud moved = c;
  MapPointStamps moved_stamps = stamps;
  fs::path file;
  ASSERT_TRUE(folder->Spill("m.bin", &moved, &file, &moved_stamps).ok());
  EXPECT_TRUE(moved.empty());
  EXPECT_TRUE(moved_stamps.empty());
  MapPointStamps out;
  auto again = CloudFromMemoryOrFile(moved, file, &moved_stamps, &out);
  ASSERT_TRUE(again.ok());
  EXPECT_EQ(out.time_ns, stamps.time_ns);
}

TEST_F(CloudFileTest, MissingTruncatedAndCorruptFilesAreNamed) {
  const fs::path missing = dir_ / "missing.bin";
  auto r = ReadCloudFile(missing);
  EXPECT_EQ(r.status().code(), StatusCode::kNotFound);
  EXPECT_NE(r.status().message().find("missing.bin"), std::string::npos);

  const fs::path p = dir_ / "c.bin";
  ASSERT_TRUE(WriteCloudFile(p, MakeCloud(100)).ok());
  fs::resize_file(p, 16 + 16 * 99 + 7);  // a point cut short
  r = ReadCloudFile(p);
  EXPECT_EQ(r.status().code(), StatusCode::kDataLoss);
  EXPECT_NE(r.status().message().find("header says 100 points"), std::string::npos)
      << r.status().message();
  EXPECT_NE(r.status().message().find("c.bin"), std::string::npos);

  fs::resize_file(p, 10);  // header cut short
  r = ReadCloudFile(p);
  EXPECT_EQ(r.status().code(), StatusCode::kDataLoss);
  EXPECT_NE(r.status().message().find("truncated header"), std::string::npos);

  {
    std::ofstream f(p, std::ios::binary | std::ios::trunc);
    f << "NOTACLOUD_______________";
  }
  r = ReadCloudFile(p);
  EXPECT_EQ(r.status().code(), StatusCode::kDataLoss);
  EXPECT_NE(r.status().message().find("bad magic"), std::string::npos);

  // A count that would overflow the size arithmetic.
  {
    std::ofstream f(p, std::ios::binary | std::ios::trunc);
    const uint64_t n = ~uint64_t{0} / 8;
    f.write("SMMSCLD1", 8);
    f.write(reinterpret_cast<const char*>(&n), 8);
  }
  r = ReadCloudFile(p);
  EXPECT_EQ(r.status().code(), StatusCode::kDataLoss);
}

TEST_F(CloudFileTest, UnwritablePathIsAnErrorNamingIt) {
  const fs::path p = dir_ / "no_such_folder" / "c.bin";
  const Status st = WriteCloudFile(p, MakeCloud(3));
  EXPECT_EQ(st.code(), StatusCode::kUnavailable);
  EXPECT_NE(st.message().find("no_such_folder"), std::string::npos);
}

TEST_F(CloudFileTest, SpillFolderHoldsTheFilesAndIsRemovedWithItsOwner) {
  fs::path folder;
  {
    auto created = SpillFolder::Create(dir_);
    ASSERT_TRUE(created.ok()) << created.status().ToString();
    SpillFolder spill = std::move(created).value();  // moved from: must not remove it
    ASSERT_TRUE(spill.enabled());
    folder = spill.path();
    EXPECT_TRUE(fs::is_directory(folder));
    EXPECT_EQ(folder.parent_path(), dir_);

    PointCloud cloud = MakeCloud(50);
    const PointCloud original = cloud;
    fs::path file;
    ASSERT_TRUE(spill.Spill("a.bin", &cloud, &file).ok());
    EXPECT_EQ(file, folder / "a.bin");
    EXPECT_TRUE(cloud.empty());
    auto back = CloudFromMemoryOrFile(cloud, file);
    ASSERT_TRUE(back.ok()) << back.status().ToString();
    EXPECT_EQ(back->points(), original.points());

    // Already spilled: nothing happens.
    PointCloud other = MakeCloud(5);
    ASSERT_TRUE(spill.Spill("b.bin", &other, &file).ok());
    EXPECT_EQ(file, folder / "a.bin");
    EXPECT_EQ(other.size(), 5u);
  }
  EXPECT_FALSE(fs::exists(folder));

  // Disabled: the cloud stays in memory.
  SpillFolder disabled;
  PointCloud cloud = MakeCloud(4);
  fs::path file;
  ASSERT_TRUE(disabled.Spill("c.bin", &cloud, &file).ok());
  EXPECT_TRUE(file.empty());
  EXPECT_EQ(cloud.size(), 4u);
  auto same = CloudFromMemoryOrFile(cloud, file);
  ASSERT_TRUE(same.ok());
  EXPECT_EQ(same->size(), 4u);
}

TEST_F(CloudFileTest, SpillFolderThatCannotBeCreatedIsNamed) {
  auto created = SpillFolder::Create("/proc/slam_mms_no_such_place");
  EXPECT_EQ(created.status().code(), StatusCode::kUnavailable);
  EXPECT_NE(created.status().message().find("/proc/slam_mms_no_such_place"), std::string::npos);
}

}  // namespace
}  // namespace slam_mms::internal
