#include "pipeline/submap_store.hpp"

#include <string>
#include <system_error>
#include <utility>

#include "slam_mms/core/logging.hpp"

namespace slam_mms::internal {

StatusOr<SubmapStore> SubmapStore::Create(const std::filesystem::path& spill_dir) {
  SubmapStore store;
  if (!spill_dir.empty()) {
    auto spill = SpillFolder::Create(spill_dir);
    if (!spill.ok()) return spill.status();
    store.spill_ = std::move(spill).value();
  }
  return store;
}

StatusOr<PointCloud> SubmapStore::SubmapCloud(int32_t id, CloudKind kind) const {
  return SubmapCloud(id, kind, nullptr);
}

StatusOr<PointCloud> SubmapStore::SubmapCloud(int32_t id, CloudKind kind,
                                              MapPointStamps* stamps) const {
  if (stamps != nullptr) stamps->clear();
  for (const SubmapRecord& rec : submaps_) {
    if (rec.id != id) continue;
    const bool map = kind == CloudKind::kMap;
    auto cloud = CloudFromMemoryOrFile(map ? rec.cloud : rec.registration_cloud,
                                       map ? rec.cloud_file : rec.registration_cloud_file,
                                       map ? &rec.cloud_stamps : nullptr, stamps);
    if (!cloud.ok()) {
      return cloud.status().WithContext("Localizer: spilled cloud of submap " + std::to_string(id));
    }
    return cloud;
  }
  return NotFoundError("Localizer::SubmapCloud: no submap " + std::to_string(id));
}

SubmapRecord& SubmapStore::Start(const Eigen::Isometry3d& T_world_submap, Timestamp stamp,
                                 int64_t scan_index, const Eigen::Isometry3d& T_prev_this,
                                 const Matrix6d& cov_prev_this) {
  SubmapRecord rec;
  rec.id = submaps_.empty() ? 0 : submaps_.back().id + 1;
  rec.T_world_submap = T_world_submap;
  rec.start = stamp;
  rec.end = stamp;
  rec.T_prev_this = T_prev_this;
  rec.cov_prev_this = cov_prev_this;
  rec.scan_indices.push_back(scan_index);
  rec.scan_stamps.push_back(stamp);
  rec.T_submap_scan.push_back(Eigen::Isometry3d::Identity());
  rec.cov_submap_scan.push_back(Matrix6d::Identity() * 1e-8);
  submaps_.push_back(std::move(rec));
  return submaps_.back();
}

void SubmapStore::FinishCurrent(PointCloud map_cloud, MapPointStamps stamps,
                                PointCloud registration_cloud) {
  if (submaps_.empty() || submaps_.back().finished) return;
  SubmapRecord& rec = submaps_.back();
  rec.cloud = std::move(map_cloud);
  rec.cloud_stamps = std::move(stamps);
  rec.registration_cloud = std::move(registration_cloud);
  rec.cloud_size = rec.cloud.size();
  rec.finished = true;
  Spill(rec, CloudKind::kMap);
  if (submaps_.size() >= 3) Spill(submaps_[submaps_.size() - 3], CloudKind::kRegistration);
}

Status SubmapStore::SetPose(int32_t id, const Eigen::Isometry3d& T_world_submap) {
  SubmapRecord* rec = Find(id);
  if (rec == nullptr) {
    return NotFoundError("Localizer::SetSubmapPose: no submap " + std::to_string(id));
  }
  rec->T_world_submap = T_world_submap;
  return OkStatus();
}

void SubmapStore::ReleaseClouds(int32_t id, bool keep_registration_cloud) {
  SubmapRecord* rec = Find(id);
  if (rec == nullptr) return;
  std::error_code ec;
  rec->cloud = PointCloud();
  rec->cloud_stamps = MapPointStamps();
  rec->cloud_size = 0;
  if (!rec->cloud_file.empty()) std::filesystem::remove(rec->cloud_file, ec);
  rec->cloud_file.clear();
  if (keep_registration_cloud) return;
  rec->registration_cloud = PointCloud();
  if (!rec->registration_cloud_file.empty()) {
    std::filesystem::remove(rec->registration_cloud_file, ec);
  }
  rec->registration_cloud_file.clear();
}

void SubmapStore::Spill(SubmapRecord& rec, CloudKind kind) {
  const bool map = kind == CloudKind::kMap;
  const Status st = spill_.Spill(
      "submap_" + std::to_string(rec.id) + (map ? "_map.bin" : "_registration.bin"),
      map ? &rec.cloud : &rec.registration_cloud,
      map ? &rec.cloud_file : &rec.registration_cloud_file, map ? &rec.cloud_stamps : nullptr);
  if (!st.ok()) {
    SLAM_MMS_LOG(kWarning) << "Localizer: submap " << rec.id
                           << " cloud kept in memory, spilling failed: " << st.ToString();
  }
}

SubmapRecord* SubmapStore::Find(int32_t id) {
  for (SubmapRecord& rec : submaps_) {
    if (rec.id == id) return &rec;
  }
  return nullptr;
}

}  // namespace slam_mms::internal
