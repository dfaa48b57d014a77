#pragma once
// Voxel-grid downsampling: every occupied cube of side `voxel_size_m` (aligned to the world origin:
// voxel index floor(p / voxel_size_m), the exact floor of the quotient, so a point on a voxel face
// belongs to the voxel above it) becomes one point at the centroid of its points, with their
// mean intensity and mean per-point time offset. The paper downsamples maps at 0.1 m before the
// mean map entropy (§6).
//
// Output order: voxels sorted by (ix, iy, iz), so the result does not depend on the input order.
// Non-finite points are dropped.
//
// Thread safety: free functions; the input is only read; safe to call concurrently.

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms {

/// Fails where voxel_size_m is not finite and > 0, or where a voxel index would exceed
/// +-(2^30 - 1) (a point beyond 1.07e8 m from the origin at 0.1 m).
StatusOr<PointCloud> VoxelDownsample(const PointCloudView& cloud, double voxel_size_m);
StatusOr<PointCloud> VoxelDownsample(const PointCloud& cloud, double voxel_size_m);

}  // namespace slam_mms
