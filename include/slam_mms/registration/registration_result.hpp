#pragma once
// RegistrationResult: what ProjectiveIcp and PointIcp return (small_gicp-style Result value).
//
// Conventions (ARCHITECTURE.md): the estimate is T_target_source (maps source points into the
// target frame); the covariance is that of the right perturbation T = T_hat * Exp(delta), delta =
// [omega; v] (rotation first) and comes from the inverse Gauss-Newton Hessian scaled by the
// residual variance.
//
// Thread safety: value type.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstddef>

#include "slam_mms/core/lie.hpp"

namespace slam_mms {

/// Why an ICP run stopped.
enum class IcpTermination {
  kConverged = 0,          ///< The last update was below the rotation and translation tolerances.
  kMaxIterations,          ///< Options::max_iterations reached without meeting the tolerances.
  kTooFewCorrespondences,  ///< Fewer inliers than Options::min_correspondences in some iteration.
  kDegenerate,             ///< The normal equations had no usable direction (all of H ~ 0).
};

/// "CONVERGED", "MAX_ITERATIONS", ...
const char* IcpTerminationName(IcpTermination termination);

/// Eigen-analysis of the 6x6 Gauss-Newton Hessian H = sum w J^T J at the final estimate.
/// The rotation block is made commensurable with translation by per-axis length scales L_k (the RMS
/// distance of the inlier source points from rotation axis k): the analysed matrix is
/// H' = S^-1 H S^-1 with S = diag(Lx, Ly, Lz, 1, 1, 1), i.e. a rotation omega_k counts as the RMS
/// displacement L_k * omega_k [m] it causes. Eigenvalues are in 1/m^2 units (for unit weights:
/// constraints per metre^2 of motion), so a tunnel's roll is not mistaken for a weak direction just
/// because the points are far ahead.
struct DegeneracyAnalysis {
  Eigen::Vector3d length_scales_m = Eigen::Vector3d::Ones();  ///< Lx, Ly, Lz.
  /// Eigenvalues of H', ascending.
  Vector6d eigenvalues = Vector6d::Zero();
  /// Column i is the unit eigenvector of eigenvalues[i], in the scaled tangent [L .* omega; v].
  Matrix6d eigenvectors = Matrix6d::Identity();
  /// eigenvalues[i] / max eigenvalue < Options::degeneracy_threshold.
  std::array<bool, 6> degenerate_direction{};
  /// Per tangent axis [omega_x, omega_y, omega_z, v_x, v_y, v_z] of the source/sensor frame: the
  /// information left on that axis once the other five are free, 1 / (H'^-1)_kk, divided by the
  /// largest eigenvalue (in [0, 1]; 0 = not observable at all). For this measure relative
  /// eigenvalues are floored at degeneracy_threshold^2, so an exactly unobservable direction that
  /// is numerically mixed into another axis does not mark that axis as well.
  Vector6d axis_information = Vector6d::Zero();
  /// axis_information[k] < Options::degeneracy_threshold.
  std::array<bool, 6> degenerate_axis{};
  /// Any degenerate direction.
  bool degenerate = false;
};

/// Inliers, RMS, covariance and degeneracy are those of the last linearisation, i.e. at the
/// estimate before the final update (which is below the tolerances when converged).
struct RegistrationResult {
  Eigen::Isometry3d T_target_source = Eigen::Isometry3d::Identity();
  /// Covariance of the right perturbation of T_target_source, [rotation, translation]:
  /// sigma^2 * H^-1 with sigma^2 = sum(w r^2) / (inliers - 6). Degenerate directions get a large
  /// (but finite) variance.
  Matrix6d covariance = Matrix6d::Identity();
  size_t num_inliers = 0;       ///< Associations used in the final linear system.
  double inlier_ratio = 0.0;    ///< num_inliers / number of valid source points.
  double rms_residual_m = 0.0;  ///< sqrt(mean r^2) over the inliers (point-to-plane) [m].
  int iterations = 0;           ///< Gauss-Newton iterations run.
  IcpTermination termination = IcpTermination::kMaxIterations;
  DegeneracyAnalysis degeneracy;

  bool converged() const { return termination == IcpTermination::kConverged; }
  /// Converged or stopped at max iterations with a solvable system: the estimate is meaningful.
  bool IsUsable() const {
    return termination == IcpTermination::kConverged ||
           termination == IcpTermination::kMaxIterations;
  }
};

}  // namespace slam_mms
