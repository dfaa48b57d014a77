#pragma once
// PointIcp: point-to-plane ICP against a KD-tree (nanoflann) of target points, the point-based
// fallback of the paper (§5.2.1) for map-to-map registration and for scans where projective
// association fails. Target normals come from a PCA of the k nearest neighbours (or are given).
//
//   E = sum_i rho( n_j . (T_target_source p_i - q_j) )^2,  j = nearest target point of T p_i,
//
// rho = Huber; Gauss-Newton on SE(3) with right perturbation (rotation first); nearest neighbours
// are re-searched at every iteration. Work is split over Options::num_threads persistent threads.
//
// Ownership: SetTarget copies the target points; Align borrows the source view for the call only.
// Move-only (owns a KD-tree and a thread pool).
// Thread safety: not thread-safe; use one PointIcp per thread (Align uses its own worker threads).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/registration/registration_result.hpp"

namespace slam_mms {

class PointIcp {
 public:
  struct Options {
    /// Associations farther than this (Euclidean, to the nearest target point) are rejected [m].
    double max_correspondence_distance = 2.0;
    /// Neighbours used for the PCA normal of each target point (>= 3).
    int num_normal_neighbors = 10;
    /// A target normal is valid if its surface variation lambda_min / (l0 + l1 + l2) is below this
    /// (0: perfect plane, 1/3: isotropic).
    double max_surface_variation = 0.1;
    /// Huber threshold on the point-to-plane residual [m]; <= 0 disables the robust loss.
    double huber_delta = 0.1;
    int max_iterations = 30;
    /// Fewer inliers than this in an iteration stops with kTooFewCorrespondences.
    int min_correspondences = 30;
    /// Convergence: |omega| of the last update [rad] and |v| [m] both below these.
    double rotation_eps = 1e-4;
    double translation_eps = 1e-4;
    /// Relative eigenvalue (scaled Hessian) below which a direction is reported degenerate.
    double degeneracy_threshold = 1e-2;
    /// Degenerate directions keep the initial guess (solution remapping) instead of drifting with
    /// the noise; the covariance still reports their large variance.
    bool freeze_degenerate_directions = true;
    /// Source points are reduced to one per voxel of this size before matching [m]; 0 keeps all.
    double source_voxel_size = 0.0;
    /// Total threads used by SetTarget and Align (including the caller).
    int num_threads = 2;

    [[nodiscard]] Status Validate() const;
  };

  /// Default options.
  PointIcp();
  /// Fails with InvalidArgument if options are invalid.
  static StatusOr<PointIcp> Create(const Options& options);
  ~PointIcp();
  PointIcp(PointIcp&&) noexcept;
  PointIcp& operator=(PointIcp&&) noexcept;
  PointIcp(const PointIcp&) = delete;
  PointIcp& operator=(const PointIcp&) = delete;

  const Options& options() const;

  /// Copies the target's finite points, builds the KD-tree and estimates normals (PCA of
  /// num_normal_neighbors). Fails if fewer than num_normal_neighbors finite points.
  Status SetTarget(const PointCloudView& target);
  /// Target with given unit normals (e.g. surfel centres and normals): no PCA.
  Status SetTarget(const std::vector<Eigen::Vector3f>& points,
                   const std::vector<Eigen::Vector3f>& normals);

  size_t target_size() const;
  /// Target points and normals as used (normals of invalid planes are zero).
  const std::vector<Eigen::Vector3f>& target_points() const;
  const std::vector<Eigen::Vector3f>& target_normals() const;

  /// Registers `source` (points in the source frame) to the target starting from
  /// T_target_source_init. Fails (FailedPrecondition) without a target, InvalidArgument for an
  /// empty source; estimator outcomes are fields of the result.
  StatusOr<RegistrationResult> Align(const PointCloudView& source,
                                     const Eigen::Isometry3d& T_target_source_init);

 private:
  struct Impl;
  explicit PointIcp(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace slam_mms
