#pragma once
// SurfelProjectionBlock: SurfelMap::Integrate's projection of its active surfels into the scan's
// range image, a block at a time: the surfels are gathered, then moved to the sensor frame and
// projected by one branch-free loop that the compiler vectorises (surfel_projection_block.cpp is
// built with -fno-math-errno -fno-trapping-math; no value changes). The floats are those of the
// per-surfel Eigen code it replaced (R x + t as (a + (b + c)) + t, norm and dot as x + (y + z)).
// Private to the surfel module.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>

#include "slam_mms/surfel/surfel.hpp"

namespace slam_mms::internal {

struct SurfelProjectionBlock {
  static constexpr int kSize = 64;
  // Sensor-frame centre and normal; in_range: within [min_r, max_r] and facing the sensor; v, u:
  // continuous row and column (the caller floors them), meaningful where in_range.
  alignas(64) float px[kSize], py[kSize], pz[kSize];
  alignas(64) float nx[kSize], ny[kSize], nz[kSize];
  alignas(64) float v[kSize], u[kSize];
  alignas(64) int32_t in_range[kSize];

  /// Projects surfels[ids[0 .. n)] (n <= kSize); `remaining` (>= n): how many ids follow from
  /// ids[0] (for the prefetch of the next block's surfels).
  void Project(const Surfel* surfels, const uint32_t* ids, int n, size_t remaining,
               const Eigen::Matrix3f& R_sensor_world, const Eigen::Vector3f& t_sensor_world,
               float min_r, float max_r, float fov_up, float rows_per_rad, float cols);
};

}  // namespace slam_mms::internal
