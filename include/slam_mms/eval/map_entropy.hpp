#pragma once
// Mean map entropy (paper eqs 26-27, Razlaw et al. 2015) and mean plane variance of a point map.
//
//   h(p_k) = 1/2 ln |2 pi e Sigma(p_k)|     (eq 26)   H(P) = 1/|P| sum_k h(p_k)   (eq 27)
//
// Sigma(p_k) is the covariance (divided by N, the maximum-likelihood estimate) of the N map points
// within `radius_m` of p_k, p_k itself included (nanoflann radius search, squared distance < r^2).
// As the paper does, the map is first voxel-downsampled (voxel centroids, default 0.1 m) and every
// remaining point is evaluated. Points with fewer than `min_neighbors` neighbours are skipped and
// counted; so are points whose covariance has det <= 0 (all neighbours coplanar to machine
// precision). Lower entropy = sharper map. Compare numbers only for equal options.
//
// Mean plane variance: the mean over the same valid points of the SMALLEST EIGENVALUE of Sigma(p_k)
// [m^2] (the map-metrics definition, not the RANSAC-plane one of the original tool).
//
// Thread safety: free function; reads its input only; runs `num_threads` worker threads itself.

#include <cstddef>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms::eval {

struct MapEntropyOptions {
  double radius_m = 0.5;      ///< Neighbourhood radius r [m] (paper: 0.5 m).
  double voxel_size_m = 0.1;  ///< Downsampling voxel [m] before evaluation; 0 disables it.
  int min_neighbors = 5;      ///< Fewer neighbours (query point included): skipped and counted.
  int num_threads = 2;        ///< Worker threads; 0 = std::thread::hardware_concurrency().

  [[nodiscard]] Status Validate() const;
};

struct MapEntropyResult {
  /// Mean of h over the valid points [nats]; NaN when no point is valid (report it as null).
  double mean_map_entropy = 0.0;
  /// Mean smallest covariance eigenvalue over the valid points [m^2]; NaN when none is valid.
  double mean_plane_variance_m2 = 0.0;
  size_t num_input_points = 0;       ///< Points given (finite ones).
  size_t num_evaluated_points = 0;   ///< Points after voxel downsampling (each one a query).
  size_t num_valid_points = 0;       ///< Queries that entered the means.
  size_t num_sparse_points = 0;      ///< Queries skipped: fewer than min_neighbors neighbours.
  size_t num_degenerate_points = 0;  ///< Queries skipped: det(Sigma) <= 0.
  double mean_neighbors = 0.0;       ///< Mean neighbour count of the valid points.
  MapEntropyOptions options;         ///< The options used (report r, voxel and minimum with it).
};

StatusOr<MapEntropyResult> ComputeMapEntropy(
    const PointCloudView& map, const MapEntropyOptions& options = MapEntropyOptions());
StatusOr<MapEntropyResult> ComputeMapEntropy(
    const PointCloud& map, const MapEntropyOptions& options = MapEntropyOptions());

}  // namespace slam_mms::eval
