#pragma once
// DownsampledUnionMap: the union of many submaps' map clouds, read from their drive-result folders
// (merge/drive_result_io.hpp) and placed at given poses, voxel-downsampled, without holding every
// cloud at once: the map of an adjustment over many drives (slam_mms_merge), or the same drives at
// their input or true poses for a comparison.
//
// The result has exactly the points VoxelDownsample gives for the concatenation of the placed
// clouds (in the order given), bit for bit, in another order: strip by strip. The space is cut
// into strips of whole voxels (about strip_m wide, across the longer horizontal extent), and each
// strip is gathered from the clouds that reach into it and downsampled on its own; a voxel lies
// in one strip, and its points keep their order, so its centroid is the one of the whole. Memory:
// the output plus one strip's points, against every cloud twice over (the concatenation and its
// sort keys). Each cloud is read once to find its strips and once per strip it reaches into.
//
// Thread safety: free function; reads the files only.

#include <Eigen/Geometry>
#include <filesystem>
#include <vector>

#include "slam_mms/backend/submap_graph_factor.hpp"
#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms {

/// One submap's map cloud: its drive-result folder, its id there, and where to place it.
struct UnionMapSubmap {
  std::filesystem::path drive_result_dir;
  SubmapId id = 0;
  Eigen::Isometry3d T_world_submap = Eigen::Isometry3d::Identity();
};

struct UnionMapOptions {
  double voxel_m = 0.1;   ///< The downsampling voxel [m], > 0.
  double strip_m = 50.0;  ///< Strip width [m] (rounded to whole voxels, at least one), > 0.

  [[nodiscard]] Status Validate() const;
};

/// A point of a submap's cloud in the world: T_world_submap applied in single precision (the
/// rotation and translation cast to float first), as DownsampledUnionMap places them.
inline Eigen::Vector3f PlaceInWorld(const Eigen::Matrix3f& R_world_submap,
                                    const Eigen::Vector3f& t_world_submap,
                                    const Eigen::Vector3f& p_submap) {
  return R_world_submap * p_submap + t_world_submap;
}

/// The union of the submaps' map clouds at their poses, voxel-downsampled (see the file comment).
/// Errors: the options' (InvalidArgument naming the field), a cloud that cannot be read (naming
/// its file), a point too far out for the voxel grid (VoxelDownsample's error).
[[nodiscard]] StatusOr<PointCloud> DownsampledUnionMap(const std::vector<UnionMapSubmap>& submaps,
                                                       const UnionMapOptions& options);

}  // namespace slam_mms
