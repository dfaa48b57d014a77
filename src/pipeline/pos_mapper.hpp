#pragma once
// PosMapper: MappingSystem's POS-only mapping (gnss_ins mode, the traditional MMS; issue #19,
// part 2): each scan is de-skewed with the POS motion over it, placed at the POS pose of its start
// and accumulated on the final map's voxel grid; the POS poses are the trajectory. No map
// feedback.
//
// Ownership: owns the map, the trajectory and its de-skewer. Thread safety: not thread-safe.

#include <Eigen/Geometry>

#include "pipeline/scan_deskewer.hpp"
#include "pipeline/voxel_accumulator.hpp"
#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"
#include "slam_mms/pipeline/localization_result.hpp"
#include "slam_mms/pipeline/map_point_stamps.hpp"

namespace slam_mms::internal {

class PosMapper {
 public:
  PosMapper() = default;
  /// `deskewer` de-skews the scans; points farther than map_max_range_m from the sensor are not
  /// kept; the map is voxelised at map_voxel_m (first observation per voxel tracked).
  PosMapper(ScanDeskewer deskewer, const Eigen::Isometry3d& T_body_lidar, double map_voxel_m,
            double map_max_range_m);

  /// Places `scan` with the POS states at its start (s0) and end (s1); the result is s0's pose
  /// (motion factor kPos). InvalidArgument from the de-skewer (a bad motion or time offset) or
  /// from the trajectory (a stamp not after the previous scan's); nothing is added then.
  StatusOr<LocalizationResult> Map(const Scan& scan, const InsState& s0, const InsState& s1);

  const Trajectory& trajectory() const { return trajectory_; }
  /// The voxel map (world), and per point the first observation's time and scan (may be null).
  PointCloud Cloud(MapPointStamps* stamps) const;

 private:
  ScanDeskewer deskewer_;
  Eigen::Isometry3d T_body_lidar_ = Eigen::Isometry3d::Identity();
  double map_max_range_m_ = 60.0;
  VoxelAccumulator map_;
  Trajectory trajectory_;
  PointCloud deskewed_;  // scratch, reused
};

}  // namespace slam_mms::internal
