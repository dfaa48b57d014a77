#pragma once
// ScanRenderer: PNG pictures for checking simulated data by eye (and the docs): a scan's top view,
// its range image, a perspective view, and the procedural scene seen from above along a trajectory.
// Rendering uses OpenCV (a private dependency of the sim module).
//
// Thread safety: stateless; functions may be called concurrently on distinct files.

#include <filesystem>
#include <string>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/sim/city_world.hpp"
#include "slam_mms/sim/reference_trajectory.hpp"

namespace slam_mms::sim {

class ScanRenderer {
 public:
  /// A labelled scan (points in the lidar frame).
  struct LabeledScan {
    std::string label;
    const PointCloud* cloud = nullptr;
  };

  /// Side by side per scan: a top view (80 m square around the sensor, coloured by height) over a
  /// range image (64 rows by elevation +2..-24.8 deg, 2083 columns by azimuth, coloured by range)
  /// and a perspective view from behind and above the car.
  [[nodiscard]] static Status WriteScanComparison(const std::vector<LabeledScan>& scans,
                                                  const std::filesystem::path& png);

  /// The scene from above (classes coloured, buildings shaded by height) over the trajectory span
  /// [t_begin_s, t_end_s] with the path drawn; `meters_per_pixel` > 0.
  [[nodiscard]] static Status WriteSceneMap(const CityWorld& world,
                                            const ReferenceTrajectory& trajectory, double t_begin_s,
                                            double t_end_s, double meters_per_pixel,
                                            const std::filesystem::path& png);
};

}  // namespace slam_mms::sim
