// DownsampledUnionMap: strip by strip from the drive-result folders, the same points as
// VoxelDownsample of the whole concatenation, bit for bit; errors name the file or the option.
#include "slam_mms/merge/union_map.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <random>
#include <tuple>
#include <vector>

#include "slam_mms/core/voxel_downsample.hpp"
#include "slam_mms/merge/drive_result_io.hpp"
#include "testing/test_data.hpp"

namespace slam_mms {
namespace {

namespace fs = std::filesystem;

// Two drives of six submaps each along a 120 m street (x), clouds of 3000 points in 16 x 5 x 1.6 m
// around each submap origin (on a lattice), the drives 3.3 m apart: voxels shared by points of one
// cloud, of consecutive submaps and of the two drives.
std::vector<UnionMapSubmap> WriteDrives(const fs::path& root, std::vector<PointCloud>* clouds) {
  std::vector<UnionMapSubmap> out;
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> lattice(-80, 80);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int d = 0; d < 2; ++d) {
    DriveResult r;
    r.origin = {48.0, 11.0, 500.0};
    for (int k = 0; k < 6; ++k) {
      DriveSubmap s;
      s.id = k;
      s.start = Timestamp::FromNanoseconds(1700000000000000000 + k * 1000000000LL);
      s.end = s.start.PlusSeconds(0.5);
      s.T_world_submap.translation() << 20.0 * k + 3.3 * d, 1.7 * d, 0.2;
      s.T_world_submap.linear() =
          Eigen::AngleAxisd(0.05 * k - 0.1 * d, Eigen::Vector3d::UnitZ()).toRotationMatrix();
      SubmapScanPose p;
      p.submap = s.id;
      p.scan_id = k;
      p.stamp = s.start;
      s.scans.push_back(p);
      s.cov_submap_scan.push_back(Matrix6d::Identity());
      for (int i = 0; i < 3000; ++i) {
        s.map_cloud.Add(
            Eigen::Vector3f(0.1f * lattice(rng), 0.05f * lattice(rng), 0.01f * lattice(rng)),
            u(rng));
      }
      s.registration_cloud.Add(Eigen::Vector3f::Zero());
      clouds->push_back(s.map_cloud);
      out.push_back({root / ("drive" + std::to_string(d)), s.id, s.T_world_submap});
      r.submaps.push_back(std::move(s));
    }
    EXPECT_TRUE(WriteDriveResult(r, root / ("drive" + std::to_string(d))).ok());
  }
  return out;
}

using Row = std::array<float, 5>;  // x, y, z, intensity, time offset

std::vector<Row> Sorted(const PointCloud& c) {
  std::vector<Row> rows;
  for (size_t i = 0; i < c.size(); ++i) {
    const auto& p = c.points()[i];
    rows.push_back({p.x(), p.y(), p.z(), c.intensities()[i], c.time_offsets_s()[i]});
  }
  std::sort(rows.begin(), rows.end());
  return rows;
}

TEST(UnionMapTest, StripsGiveTheWholeConcatenationsVoxelsBitForBit) {
  const testing::ScopedTempDir dir("union_map");
  std::vector<PointCloud> clouds;
  const std::vector<UnionMapSubmap> submaps = WriteDrives(dir.path, &clouds);
  // The reference: every cloud placed (PlaceInWorld), concatenated in order, downsampled at once.
  PointCloud all;
  for (size_t k = 0; k < submaps.size(); ++k) {
    const Eigen::Matrix3f R = submaps[k].T_world_submap.linear().cast<float>();
    const Eigen::Vector3f t = submaps[k].T_world_submap.translation().cast<float>();
    for (size_t i = 0; i < clouds[k].size(); ++i) {
      all.Add(PlaceInWorld(R, t, clouds[k].points()[i]), clouds[k].intensities()[i]);
    }
  }
  for (const double voxel : {0.1, 0.5}) {
    auto whole = VoxelDownsample(all, voxel);
    ASSERT_TRUE(whole.ok());
    if (voxel > 0.3) ASSERT_LT(whole->size(), all.size() / 2);  // voxels of several points
    const std::vector<Row> expected = Sorted(*whole);
    for (const double strip : {0.05, 1.0, 7.3, 50.0, 1000.0}) {
      UnionMapOptions o;
      o.voxel_m = voxel;
      o.strip_m = strip;
      auto u = DownsampledUnionMap(submaps, o);
      ASSERT_TRUE(u.ok()) << u.status().ToString();
      EXPECT_TRUE(Sorted(*u) == expected) << "voxel " << voxel << ", strip " << strip << ": "
                                          << u->size() << " points against " << whole->size();
    }
  }
}

TEST(UnionMapTest, ErrorsNameTheFileOrTheOption) {
  const testing::ScopedTempDir dir("union_map_bad");
  std::vector<PointCloud> clouds;
  std::vector<UnionMapSubmap> submaps = WriteDrives(dir.path, &clouds);
  UnionMapOptions bad;
  bad.strip_m = 0.0;
  auto r = DownsampledUnionMap(submaps, bad);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("strip_m"), std::string::npos) << r.status().ToString();
  submaps[3].id = 42;  // no such cloud
  r = DownsampledUnionMap(submaps, UnionMapOptions());
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("000042_map.pcd"), std::string::npos)
      << r.status().ToString();
  EXPECT_TRUE(DownsampledUnionMap({}, UnionMapOptions()).ok());  // nothing: an empty map
  submaps[3].id = 3;
  submaps[4].T_world_submap.translation().x() = 1e12;  // beyond the voxel grid
  r = DownsampledUnionMap(submaps, UnionMapOptions());
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.status().message().find("too far"), std::string::npos) << r.status().ToString();
  EXPECT_NE(r.status().message().find("submap 4 of"), std::string::npos) << r.status().ToString();
}

}  // namespace
}  // namespace slam_mms
