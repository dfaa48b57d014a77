// Localizer (level 1) submaps, on the synthetic drive of localizer_drive.hpp: the submap life
// cycle (cut every WT, records, finish), moving submaps (SetSubmapPose), the submap clouds
// (NotFound, spilling to disk and back), the thread count, and a failed first scan.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "pipeline/localizer_drive.hpp"
#include "slam_mms/pipeline/localizer.hpp"
#include "testing/test_data.hpp"

namespace slam_mms::testing {
namespace {

// ---- submaps ------------------------------------------------------------------------------------

TEST(LocalizerTest, SubmapsStartEveryWtAndTheirRecordsAreConsistent) {
  constexpr int kScans = 14;  // submaps of scans 0-3, 4-7, 8-11 and 12-13 (current)
  auto loc = MakeLocalizer(SmallOptions(MappingMode::kLidarOnly));
  ASSERT_NE(loc, nullptr);
  const std::vector<LocalizationResult> results = RunLidarOnly(loc.get(), 0, kScans);
  ASSERT_EQ(results.size(), static_cast<size_t>(kScans));
  for (int k = 0; k < kScans; ++k) {
    const LocalizationResult& r = results[static_cast<size_t>(k)];
    EXPECT_EQ(r.new_submap, k % kScansPerSubmap == 0) << k;
    EXPECT_EQ(r.submap_id, k / kScansPerSubmap) << k;
    EXPECT_EQ(r.stamp, ScanStart(k));
  }
  const std::vector<SubmapRecord>& subs = loc->submaps();
  ASSERT_EQ(subs.size(), 4u);
  for (size_t i = 0; i < subs.size(); ++i) {
    const SubmapRecord& rec = subs[i];
    const int first = static_cast<int>(i) * kScansPerSubmap;
    const int last = std::min(first + kScansPerSubmap, kScans) - 1;
    EXPECT_EQ(rec.id, static_cast<int32_t>(i));
    EXPECT_EQ(rec.finished, i + 1 < subs.size()) << i;
    EXPECT_EQ(rec.start, ScanStart(first)) << i;
    EXPECT_EQ(rec.end, ScanStart(last)) << i;
    ASSERT_EQ(rec.scan_indices.size(), static_cast<size_t>(last - first + 1)) << i;
    ASSERT_EQ(rec.scan_stamps.size(), rec.scan_indices.size());
    ASSERT_EQ(rec.T_submap_scan.size(), rec.scan_indices.size());
    ASSERT_EQ(rec.cov_submap_scan.size(), rec.scan_indices.size());
    // The reference frame is the body pose of the first scan.
    EXPECT_TRUE(rec.T_submap_scan.front().isApprox(Eigen::Isometry3d::Identity(), 1e-12));
    for (size_t j = 0; j < rec.scan_indices.size(); ++j) {
      const int k = first + static_cast<int>(j);
      EXPECT_EQ(rec.scan_indices[j], k);
      EXPECT_EQ(rec.scan_stamps[j], ScanStart(k));
      // T_world_submap * T_submap_scan is the pose the scan was reported at.
      const Eigen::Isometry3d T = rec.T_world_submap * rec.T_submap_scan[j];
      EXPECT_LT(TransErrM(results[static_cast<size_t>(k)].T_world_body, T), 1e-9) << k;
      EXPECT_LT(RotErrDeg(results[static_cast<size_t>(k)].T_world_body, T), 1e-7) << k;
      EXPECT_TRUE(rec.cov_submap_scan[j].allFinite());
    }
    // The reckon chain: the previous reference to this one.
    if (i > 0) {
      const Eigen::Isometry3d chained = subs[i - 1].T_world_submap * rec.T_prev_this;
      EXPECT_LT(TransErrM(rec.T_world_submap, chained), 1e-9) << i;
      EXPECT_LT(RotErrDeg(rec.T_world_submap, chained), 1e-7) << i;
      EXPECT_TRUE(rec.cov_prev_this.allFinite());
    }
    // A finished submap has its map cloud (in memory without spill_dir), the current one not yet.
    if (rec.finished) {
      EXPECT_GT(rec.cloud_size, 1000u) << i;
      EXPECT_EQ(rec.cloud.size(), rec.cloud_size) << i;
      EXPECT_GT(rec.registration_cloud.size(), 100u) << i;
      EXPECT_LT(rec.registration_cloud.size(), rec.cloud.size()) << i;  // coarser voxels
      EXPECT_TRUE(rec.cloud_file.empty());
    } else {
      EXPECT_EQ(rec.cloud_size, 0u);
    }
  }

  // FinishCurrentSubmap closes the current one (idempotent); its map cloud holds its scans.
  loc->FinishCurrentSubmap();
  loc->FinishCurrentSubmap();
  ASSERT_EQ(loc->submaps().size(), 4u);
  const SubmapRecord& last = loc->submaps().back();
  EXPECT_TRUE(last.finished);
  EXPECT_GT(last.cloud_size, 1000u);
  EXPECT_EQ(last.end, ScanStart(kScans - 1));
  MapPointStamps stamps;
  auto cloud = loc->SubmapCloud(last.id, SubmapSource::CloudKind::kMap, &stamps);
  ASSERT_TRUE(cloud.ok()) << cloud.status().ToString();
  EXPECT_EQ(cloud->size(), last.cloud_size);
  ASSERT_EQ(stamps.size(), cloud->size());
  const std::set<int64_t> seen(stamps.scan_index.begin(), stamps.scan_index.end());
  for (int64_t k : last.scan_indices) EXPECT_EQ(seen.count(k), 1u) << k;
  for (int64_t t : stamps.time_ns) {
    EXPECT_GE(t, last.start.nanoseconds());
    EXPECT_LE(t, last.end.nanoseconds());
  }
}

TEST(LocalizerTest, SetSubmapPoseMovesTheSubmapItsScansAndItsSurfels) {
  auto loc = MakeLocalizer(SmallOptions(MappingMode::kLidarOnly));
  ASSERT_NE(loc, nullptr);
  ASSERT_EQ(RunLidarOnly(loc.get(), 0, 10).size(), 10u);  // submaps 0, 1, 2 (current)
  ASSERT_EQ(loc->submaps().size(), 3u);
  const std::vector<SubmapRecord> before = loc->submaps();
  const std::vector<Surfel> surfels_before = loc->surfel_map().surfels();
  size_t moved = 0, others = 0;
  for (uint32_t i = 0; i < surfels_before.size(); ++i) {
    if (!loc->surfel_map().IsAlive(i)) continue;
    (surfels_before[i].submap_id == 1 ? moved : others) += 1;
  }
  ASSERT_GT(moved, 1000u);  // submap 1 is still live (the previous one)
  ASSERT_GT(others, 1000u);

  Eigen::Isometry3d delta = Eigen::Isometry3d::Identity();
  delta.translate(Eigen::Vector3d(1.0, -2.0, 0.5));
  delta.rotate(Eigen::AngleAxisd(0.1, Eigen::Vector3d(0.2, 0.3, 1.0).normalized()));
  const Eigen::Isometry3d target = delta * before[1].T_world_submap;
  ASSERT_TRUE(loc->SetSubmapPose(1, target).ok());

  const std::vector<SubmapRecord>& after = loc->submaps();
  EXPECT_TRUE(after[1].T_world_submap.isApprox(target, 1e-12));
  for (size_t j = 0; j < after[1].T_submap_scan.size(); ++j) {
    // The scans ride along: their world poses move by delta.
    const Eigen::Isometry3d world_before = before[1].T_world_submap * before[1].T_submap_scan[j];
    const Eigen::Isometry3d world_after = after[1].T_world_submap * after[1].T_submap_scan[j];
    EXPECT_TRUE(world_after.isApprox(delta * world_before, 1e-9)) << j;
  }
  for (size_t i : {size_t{0}, size_t{2}}) {
    EXPECT_EQ(after[i].T_world_submap.matrix(), before[i].T_world_submap.matrix()) << i;
  }
  const std::vector<Surfel>& surfels_after = loc->surfel_map().surfels();
  ASSERT_EQ(surfels_after.size(), surfels_before.size());
  const Eigen::Isometry3f delta_f = delta.cast<float>();
  for (uint32_t i = 0; i < surfels_after.size(); ++i) {
    if (!loc->surfel_map().IsAlive(i)) continue;
    const Surfel& a = surfels_after[i];
    const Surfel& b = surfels_before[i];
    ASSERT_EQ(a.submap_id, b.submap_id);
    if (b.submap_id == 1) {
      ASSERT_LT((a.position - delta_f * b.position).norm(), 1e-4f) << i;
      ASSERT_LT((a.normal - delta_f.linear() * b.normal).norm(), 1e-5f) << i;
    } else {
      ASSERT_EQ(a.position, b.position) << i;
      ASSERT_EQ(a.normal, b.normal) << i;
    }
  }

  // Unknown id and non-finite poses: errors, nothing moves.
  const Status unknown = loc->SetSubmapPose(7, target);
  EXPECT_EQ(unknown.code(), StatusCode::kNotFound);
  EXPECT_NE(unknown.message().find("7"), std::string::npos) << unknown.ToString();
  Eigen::Isometry3d nan_pose = target;
  nan_pose.translation().z() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(loc->SetSubmapPose(0, nan_pose).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(loc->submaps()[0].T_world_submap.matrix(), before[0].T_world_submap.matrix());
  EXPECT_EQ(loc->surfel_map().surfels()[0].position, surfels_after[0].position);

  // Moving every submap by delta (a level-2 correction of the whole map): level 1 goes on in the
  // moved frame, the next scans are placed at delta * truth.
  ASSERT_TRUE(loc->SetSubmapPose(0, delta * before[0].T_world_submap).ok());
  ASSERT_TRUE(loc->SetSubmapPose(2, delta * before[2].T_world_submap).ok());
  const std::vector<LocalizationResult> more = RunLidarOnly(loc.get(), 10, 14);
  ASSERT_EQ(more.size(), 4u);
  for (const LocalizationResult& r : more) {
    const Eigen::Isometry3d expected = delta * TrueScanPose(static_cast<int>(r.scan_index));
    EXPECT_TRUE(r.registration_used) << r.scan_index;
    EXPECT_LT(TransErrM(expected, r.T_world_body), kTolTransM) << r.scan_index;
    EXPECT_LT(RotErrDeg(expected, r.T_world_body), kTolRotDeg) << r.scan_index;
  }
}

// ---- submap clouds ------------------------------------------------------------------------------

TEST(LocalizerTest, SubmapCloudOfAnUnknownIdIsNotFound) {
  auto loc = MakeLocalizer(SmallOptions(MappingMode::kLidarOnly));
  ASSERT_NE(loc, nullptr);
  EXPECT_EQ(loc->SubmapCloud(0, SubmapSource::CloudKind::kMap).status().code(),
            StatusCode::kNotFound);
  ASSERT_EQ(RunLidarOnly(loc.get(), 0, 5).size(), 5u);  // submaps 0 and 1
  for (int32_t id : {-1, 2, 1000}) {
    for (auto kind : {SubmapSource::CloudKind::kMap, SubmapSource::CloudKind::kRegistration}) {
      auto c = loc->SubmapCloud(id, kind);
      EXPECT_EQ(c.status().code(), StatusCode::kNotFound) << id;
      EXPECT_NE(c.status().message().find(std::to_string(id)), std::string::npos)
          << c.status().ToString();
    }
  }
  auto c0 = loc->SubmapCloud(0, SubmapSource::CloudKind::kMap);
  ASSERT_TRUE(c0.ok()) << c0.status().ToString();
  EXPECT_TRUE(SameCloud(*c0, loc->submaps()[0].cloud));
  // Through the SubmapSource interface too.
  const SubmapSource& source = *loc;
  EXPECT_EQ(source.SubmapCloud(5, SubmapSource::CloudKind::kRegistration).status().code(),
            StatusCode::kNotFound);
}

/// Runs scans 0-9 (submaps 0, 1, 2) and finishes the last submap.
std::unique_ptr<Localizer> RunTenScans(const Localizer::Options& o) {
  auto loc = MakeLocalizer(o);
  if (loc == nullptr) return nullptr;
  if (RunLidarOnly(loc.get(), 0, 10).size() != 10u) return nullptr;
  loc->FinishCurrentSubmap();
  return loc;
}

TEST(LocalizerTest, SpilledCloudsComeBackEqualAndTheSpillFolderIsRemoved) {
  const auto in_memory = RunTenScans(SmallOptions(MappingMode::kLidarOnly));
  ASSERT_NE(in_memory, nullptr);
  const testing::ScopedTempDir spill_dir("slam_mms_localizer_spill");
  Localizer::Options o = SmallOptions(MappingMode::kLidarOnly);
  o.spill_dir = spill_dir.path;
  auto spilled = RunTenScans(o);
  ASSERT_NE(spilled, nullptr);

  const std::filesystem::path folder = spilled->spill_folder();
  ASSERT_FALSE(folder.empty());
  EXPECT_EQ(folder.parent_path(), spill_dir.path);
  EXPECT_TRUE(std::filesystem::is_directory(folder));
  // Spilling changes no result.
  const auto& subs_mem = in_memory->submaps();
  const auto& subs = spilled->submaps();
  ASSERT_EQ(subs.size(), 3u);
  ASSERT_EQ(subs_mem.size(), subs.size());
  for (size_t i = 0; i < subs.size(); ++i) {
    EXPECT_EQ(subs[i].T_world_submap.matrix(), subs_mem[i].T_world_submap.matrix()) << i;
    ASSERT_EQ(subs[i].T_submap_scan.size(), subs_mem[i].T_submap_scan.size());
    for (size_t j = 0; j < subs[i].T_submap_scan.size(); ++j) {
      EXPECT_EQ(subs[i].T_submap_scan[j].matrix(), subs_mem[i].T_submap_scan[j].matrix());
    }
  }
  // Every finished submap's map cloud is on disk; the registration clouds once two behind the
  // current one (submap 0 here).
  size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(folder)) files += e.is_regular_file();
  EXPECT_EQ(files, 3u + 1u);
  for (size_t i = 0; i < subs.size(); ++i) {
    const SubmapRecord& rec = subs[i];
    EXPECT_TRUE(rec.cloud.empty()) << i;
    EXPECT_EQ(rec.cloud_file.parent_path(), folder) << i;
    EXPECT_TRUE(std::filesystem::is_regular_file(rec.cloud_file)) << i;
    EXPECT_EQ(rec.cloud_size, subs_mem[i].cloud.size()) << i;
    EXPECT_EQ(rec.registration_cloud_file.empty(), i != 0) << i;
    for (auto kind : {SubmapSource::CloudKind::kMap, SubmapSource::CloudKind::kRegistration}) {
      MapPointStamps stamps, stamps_mem;
      auto a = spilled->SubmapCloud(rec.id, kind, &stamps);
      auto b = in_memory->SubmapCloud(rec.id, kind, &stamps_mem);
      ASSERT_TRUE(a.ok()) << a.status().ToString();
      ASSERT_TRUE(b.ok()) << b.status().ToString();
      EXPECT_GT(a->size(), 100u);
      EXPECT_TRUE(SameCloud(*a, *b)) << "submap " << i << " kind " << static_cast<int>(kind);
      EXPECT_EQ(stamps.time_ns, stamps_mem.time_ns);
      EXPECT_EQ(stamps.scan_index, stamps_mem.scan_index);
      EXPECT_EQ(stamps.size(), kind == SubmapSource::CloudKind::kMap ? a->size() : 0u);
    }
  }
  // Releasing a submap's clouds removes its files.
  const std::filesystem::path map0 = subs[0].cloud_file, reg0 = subs[0].registration_cloud_file;
  spilled->ReleaseSubmapClouds(0, /*keep_registration_cloud=*/false);
  EXPECT_FALSE(std::filesystem::exists(map0));
  EXPECT_FALSE(std::filesystem::exists(reg0));
  EXPECT_EQ(spilled->submaps()[0].cloud_size, 0u);
  auto released = spilled->SubmapCloud(0, SubmapSource::CloudKind::kMap);
  ASSERT_TRUE(released.ok()) << released.status().ToString();
  EXPECT_TRUE(released->empty());

  // The Localizer takes its private folder with it; the parent stays.
  spilled.reset();
  EXPECT_FALSE(std::filesystem::exists(folder));
  EXPECT_TRUE(std::filesystem::is_directory(spill_dir.path));
  EXPECT_TRUE(std::filesystem::is_empty(spill_dir.path));
}

// Options::num_threads > 1 accumulates the submap clouds on a background thread: the same clouds
// and poses as inline.
// num_threads is the one thread count of every level-1 stage: a different count may change the
// floating-point summation order of the parallel reductions (ICP normal equations, window solve),
// never the result beyond rounding. (That the background cloud accumulation gives the same clouds
// bit for bit is SubmapCloudBuilder's own test.)
TEST(LocalizerTest, ThreadCountChangesNothingBeyondRounding) {
  Localizer::Options one = SmallOptions(MappingMode::kLidarOnly);
  one.num_threads = 1;
  const auto a = RunTenScans(one);
  const auto b = RunTenScans(SmallOptions(MappingMode::kLidarOnly));  // num_threads = 2
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  ASSERT_EQ(a->submaps().size(), b->submaps().size());
  double max_dt = 0.0, max_dr = 0.0;
  for (size_t i = 0; i < a->submaps().size(); ++i) {
    const SubmapRecord& ra = a->submaps()[i];
    const SubmapRecord& rb = b->submaps()[i];
    ASSERT_EQ(ra.scan_indices, rb.scan_indices) << i;
    for (size_t j = 0; j < ra.T_submap_scan.size(); ++j) {
      const Eigen::Isometry3d Ta = ra.T_world_submap * ra.T_submap_scan[j];
      const Eigen::Isometry3d Tb = rb.T_world_submap * rb.T_submap_scan[j];
      max_dt = std::max(max_dt, (Ta.translation() - Tb.translation()).norm());
      max_dr = std::max(max_dr, RotErrDeg(Ta, Tb));
    }
    EXPECT_GT(ra.cloud.size(), 1000u);
    EXPECT_NEAR(static_cast<double>(ra.cloud.size()), static_cast<double>(rb.cloud.size()),
                0.01 * static_cast<double>(rb.cloud.size()))
        << i;
  }
  RecordProperty("max_translation_diff_m", std::to_string(max_dt));
  RecordProperty("max_rotation_diff_deg", std::to_string(max_dr));
  EXPECT_LT(max_dt, 1e-4);
  EXPECT_LT(max_dr, 1e-4);
}

// A first scan that fails (here a time offset outside the scan, found by the de-skew) must not
// start submap 0: it used to leave that scan as the reference of submap 0 although it was never
// processed, and the next scan was filed as its second scan (at the initial pose, one scan's
// motion off), with dt measured from time 0.
TEST(LocalizerTest, AFailedFirstScanStartsNoSubmap) {
  auto loc = MakeLocalizer(SmallOptions(MappingMode::kLidarOnly));
  ASSERT_NE(loc, nullptr);
  Scan bad = DriveScan(0, /*skewed=*/true);
  bad.cloud.time_offsets_s()[10] = 0.5f;  // the sweep lasts 0.1 s
  auto r0 = loc->ProcessScan(bad, ConstantVelocity());
  ASSERT_EQ(r0.status().code(), StatusCode::kInvalidArgument) << r0.status().ToString();
  EXPECT_TRUE(loc->submaps().empty());
  auto r1 = loc->ProcessScan(DriveScan(1, /*skewed=*/true), ConstantVelocity());
  ASSERT_TRUE(r1.ok()) << r1.status().ToString();
  EXPECT_TRUE(r1->new_submap);
  EXPECT_EQ(loc->submaps().front().scan_indices.front(), 1);
}

}  // namespace
}  // namespace slam_mms::testing
