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
#include "slam_mms/registration/registration_options.hpp"
#include "slam_mms/registration/registration_result.hpp"

namespace slam_mms {

class PointIcp {
 public:
  /// The SDK's options (PointIcpOptions) plus the thread count its owner sets.
  struct Options : PointIcpOptions {
    /// Total threads used by SetTarget and Align (including the caller), in [1, 256].
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
