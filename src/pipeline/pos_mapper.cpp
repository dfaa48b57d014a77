#include "pipeline/pos_mapper.hpp"

#include <utility>

namespace slam_mms::internal {

PosMapper::PosMapper(ScanDeskewer deskewer, const Eigen::Isometry3d& T_body_lidar,
                     double map_voxel_m, double map_max_range_m)
    : deskewer_(std::move(deskewer)),
      T_body_lidar_(T_body_lidar),
      map_max_range_m_(map_max_range_m),
      map_(map_voxel_m, /*track_first_observation=*/true) {}

StatusOr<LocalizationResult> PosMapper::Map(const Scan& scan, const InsState& s0,
                                            const InsState& s1) {
  const Eigen::Isometry3d T_bstart_bend = s0.T_world_body.inverse() * s1.T_world_body;
  SLAM_MMS_RETURN_IF_ERROR(deskewer_.Deskew(scan, T_bstart_bend, T_body_lidar_, &deskewed_));
  const ScanStamp stamp{scan.stamp_start.nanoseconds(), &scan.cloud.time_offsets_s(), scan.index};
  StampedPose pose;
  pose.stamp = scan.stamp_start;
  pose.T_world_body = s0.T_world_body;
  pose.cov_T_world_body = s0.cov_T_world_body;
  // The trajectory checks the stamp order; nothing is added to the map before it has.
  SLAM_MMS_RETURN_IF_ERROR(
      trajectory_.Add(pose).WithContext("PosMapper: scan '" + scan.source + "'"));
  map_.Add(deskewed_, s0.T_world_body * T_body_lidar_, map_max_range_m_, &stamp);
  LocalizationResult res;
  res.scan_index = scan.index;
  res.stamp = scan.stamp_start;
  res.T_world_body = s0.T_world_body;
  res.cov_T_world_body = s0.cov_T_world_body;
  res.motion_factor = MotionFactorType::kPos;
  return res;
}

PointCloud PosMapper::Cloud(MapPointStamps* stamps) const {
  return stamps != nullptr ? map_.Cloud(&stamps->time_ns, &stamps->scan_index) : map_.Cloud();
}

}  // namespace slam_mms::internal
