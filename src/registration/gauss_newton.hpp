#pragma once
// Shared Gauss-Newton machinery of ProjectiveIcp and PointIcp: normal-equation accumulators, the
// eigen-decomposition based step (with degenerate directions left at the prior), the degeneracy
// analysis and the covariance.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstddef>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/registration/registration_result.hpp"

namespace slam_mms::registration_internal {

/// H = sum w J J^T (upper triangle while accumulating), g = sum w r J.
struct NormalEquations {
  Matrix6d H = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  double weighted_r2 = 0.0;                           ///< sum w r^2
  double r2 = 0.0;                                    ///< sum r^2
  Eigen::Vector3d moment2 = Eigen::Vector3d::Zero();  ///< sum of p_source.^2 (rotation scales)
  size_t inliers = 0;
  size_t candidates = 0;  ///< valid source points considered

  void SetZero() { *this = NormalEquations(); }
  void Add(const Vector6d& J, double r, double w, const Eigen::Vector3d& p_source) {
    H.selfadjointView<Eigen::Upper>().rankUpdate(J, w);
    g.noalias() += (w * r) * J;
    weighted_r2 += w * r * r;
    r2 += r * r;
    moment2 += p_source.cwiseAbs2();
    ++inliers;
  }
  NormalEquations& operator+=(const NormalEquations& o) {
    H += o.H;
    g += o.g;
    weighted_r2 += o.weighted_r2;
    r2 += o.r2;
    moment2 += o.moment2;
    inliers += o.inliers;
    candidates += o.candidates;
    return *this;
  }
  /// Full symmetric H from the accumulated upper triangle.
  Matrix6d SymmetricH() const {
    Matrix6d S = H.selfadjointView<Eigen::Upper>();
    return S;
  }
  /// Per rotation axis k: the RMS distance of the inlier source points from that axis through the
  /// origin, sqrt(mean(|p|^2 - p_k^2)), so that omega_k * L_k is the RMS displacement it causes.
  Eigen::Vector3d LengthScales() const;
};

/// Step and analysis of one linear system.
struct StepResult {
  Vector6d delta = Vector6d::Zero();  ///< [omega; v], to apply as T <- T * Exp(delta)
  DegeneracyAnalysis degeneracy;
  Matrix6d covariance = Matrix6d::Identity();
  bool solvable = false;  ///< false when H has no positive eigenvalue
};

/// Solves H delta = -g with the pseudo-inverse of the scaled H': directions whose relative
/// eigenvalue is below `solve_floor` are left unchanged (solution remapping, Zhang et al. 2016: a
/// degenerate direction keeps its initial guess instead of drifting with the noise). Analyses
/// degeneracy with `degeneracy_threshold` and forms the covariance sigma^2 H^-1.
StepResult SolveAndAnalyse(const NormalEquations& eq, double degeneracy_threshold,
                           double solve_floor);

/// Settings of the shared loop.
struct GaussNewtonSettings {
  int max_iterations = 30;
  size_t min_correspondences = 30;
  double rotation_eps_rad = 1e-4;
  double translation_eps_m = 1e-4;
  double degeneracy_threshold = 1e-2;
  /// Keep degenerate directions at the initial guess (else only numerically singular ones).
  bool freeze_degenerate_directions = true;
};

/// The Gauss-Newton loop. `build(T, &eq)` fills the normal equations at T (eq is zeroed first).
template <typename Build>
RegistrationResult RunGaussNewton(const GaussNewtonSettings& s, const Eigen::Isometry3d& T_init,
                                  Build&& build) {
  RegistrationResult result;
  Eigen::Isometry3d T = T_init;
  NormalEquations eq;
  StepResult step;
  result.termination = IcpTermination::kMaxIterations;
  for (int it = 0; it < s.max_iterations; ++it) {
    eq.SetZero();
    build(T, &eq);
    result.iterations = it + 1;
    if (eq.inliers < s.min_correspondences || eq.inliers < 6) {
      result.termination = IcpTermination::kTooFewCorrespondences;
      break;
    }
    step = SolveAndAnalyse(eq, s.degeneracy_threshold,
                           s.freeze_degenerate_directions ? s.degeneracy_threshold : 1e-9);
    if (!step.solvable) {
      result.termination = IcpTermination::kDegenerate;
      break;
    }
    T = T * se3::Exp(step.delta);
    if (step.delta.head<3>().norm() < s.rotation_eps_rad &&
        step.delta.tail<3>().norm() < s.translation_eps_m) {
      result.termination = IcpTermination::kConverged;
      break;
    }
  }
  result.T_target_source = Orthonormalized(T);
  result.num_inliers = eq.inliers;
  result.inlier_ratio = eq.candidates > 0
                            ? static_cast<double>(eq.inliers) / static_cast<double>(eq.candidates)
                            : 0.0;
  result.rms_residual_m = eq.inliers > 0 ? std::sqrt(eq.r2 / static_cast<double>(eq.inliers)) : 0.0;
  if (step.solvable) {
    result.covariance = step.covariance;
    result.degeneracy = step.degeneracy;
  }
  return result;
}

}  // namespace slam_mms::registration_internal
