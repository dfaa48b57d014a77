#pragma once
// The options of the two registrations, as the SDK exposes them (Localizer::Options::icp,
// MappingSystem::Options::level2.icp). The registration classes themselves are internal (src/);
// their threads come from the owner's one num_threads (Localizer / MappingSystem).
//
// Thread safety: plain values.

#include "slam_mms/core/status.hpp"

namespace slam_mms {

/// Scan-to-model projective ICP of level 1 (paper §5.1.2, eq 15; SuMa's Frame2Model).
struct ProjectiveIcpOptions {
  /// Euclidean gate between the moved scan vertex and its model vertex [m] (SuMa
  /// icp-max-distance).
  double max_distance = 2.0;
  /// Normal gate [deg] (SuMa icp-max-angle).
  double max_angle_deg = 30.0;
  /// Huber threshold on the point-to-plane residual [m] (SuMa factor 0.5); <= 0: no robust loss.
  double huber_delta = 0.5;
  int max_iterations = 20;
  /// Fewer inliers than this in an iteration stops with kTooFewCorrespondences.
  int min_correspondences = 100;
  /// Convergence: |omega| of the last update [rad] and |v| [m] both below these.
  double rotation_eps = 1e-4;
  double translation_eps = 1e-4;
  /// Relative eigenvalue (scaled Hessian, see DegeneracyAnalysis) below which a direction is
  /// reported degenerate.
  double degeneracy_threshold = 1e-2;
  /// Degenerate directions keep the initial guess (solution remapping) instead of drifting.
  bool freeze_degenerate_directions = true;
  /// Use every k-th valid scan pixel (1: all).
  int pixel_stride = 1;

  /// InvalidArgument naming "ProjectiveIcp::Options::<field>".
  [[nodiscard]] Status Validate() const;
};

/// Point-to-plane ICP against a k-d tree of target points: level 2's map-to-map registration and
/// loop verification (paper §5.2.1).
struct PointIcpOptions {
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

  /// InvalidArgument naming "PointIcp::Options::<field>".
  [[nodiscard]] Status Validate() const;
};

}  // namespace slam_mms
