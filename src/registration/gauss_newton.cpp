#include "registration/gauss_newton.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace slam_mms::registration_internal {

Eigen::Vector3d NormalEquations::LengthScales() const {
  if (inliers == 0) return Eigen::Vector3d::Ones();
  const Eigen::Vector3d m = moment2 / static_cast<double>(inliers);
  const double sum = m.sum();
  return Eigen::Vector3d(std::sqrt(std::max(1e-6, sum - m.x())),
                         std::sqrt(std::max(1e-6, sum - m.y())),
                         std::sqrt(std::max(1e-6, sum - m.z())));
}

StepResult SolveAndAnalyse(const NormalEquations& eq, double degeneracy_threshold,
                           double solve_floor) {
  StepResult out;
  const Eigen::Vector3d L = eq.LengthScales();
  Vector6d s_inv;
  s_inv << L.cwiseInverse(), 1.0, 1.0, 1.0;
  // H' = S^-1 H S^-1, g' = S^-1 g.
  const Matrix6d Hs = s_inv.asDiagonal() * eq.SymmetricH() * s_inv.asDiagonal();
  const Vector6d gs = s_inv.cwiseProduct(eq.g);
  Eigen::SelfAdjointEigenSolver<Matrix6d> es(Hs);
  if (es.info() != Eigen::Success) return out;
  const Vector6d lambda = es.eigenvalues();
  const Matrix6d& E = es.eigenvectors();
  const double lambda_max = lambda[5];
  if (!(lambda_max > 0.0) || !std::isfinite(lambda_max)) return out;
  out.solvable = true;

  DegeneracyAnalysis& d = out.degeneracy;
  d.length_scales_m = L;
  d.eigenvalues = lambda;
  d.eigenvectors = E;
  d.degenerate = false;
  Vector6d inv_lambda;  // pseudo-inverse spectrum for the step
  Vector6d cov_lambda;  // finite inverse spectrum for the covariance
  for (int i = 0; i < 6; ++i) {
    const double rel = lambda[i] / lambda_max;
    d.degenerate_direction[static_cast<size_t>(i)] = rel < degeneracy_threshold;
    d.degenerate = d.degenerate || rel < degeneracy_threshold;
    inv_lambda[i] = rel < solve_floor ? 0.0 : 1.0 / lambda[i];
    cov_lambda[i] = 1.0 / std::max(lambda[i], lambda_max * 1e-12);
  }
  const Matrix6d Hs_inv = E * cov_lambda.asDiagonal() * E.transpose();
  // Per-axis information with the others free, 1 / (H'^-1)_kk, relative to lambda_max. Relative
  // eigenvalues are floored at threshold^2 here, so that an exactly null direction that is
  // numerically mixed (by 1e-3 or so) into another axis does not mark that axis too.
  const double floor_rel = degeneracy_threshold * degeneracy_threshold;
  for (int k = 0; k < 6; ++k) {
    double inv = 0.0;
    for (int i = 0; i < 6; ++i) {
      inv += E(k, i) * E(k, i) / std::max(lambda[i] / lambda_max, floor_rel);
    }
    d.axis_information[k] = std::clamp(1.0 / inv, 0.0, 1.0);
    d.degenerate_axis[static_cast<size_t>(k)] = d.axis_information[k] < degeneracy_threshold;
  }
  // delta' = -H'^+ g', delta = S^-1 delta'.
  const Vector6d delta_s = -(E * inv_lambda.asDiagonal() * (E.transpose() * gs));
  out.delta = s_inv.cwiseProduct(delta_s);
  // Covariance: sigma^2 H^-1 = sigma^2 S^-1 H'^-1 S^-1.
  const double dof = static_cast<double>(eq.inliers > 6 ? eq.inliers - 6 : 1);
  const double sigma2 = eq.weighted_r2 / dof;
  out.covariance = sigma2 * (s_inv.asDiagonal() * Hs_inv * s_inv.asDiagonal());
  return out;
}

}  // namespace slam_mms::registration_internal
