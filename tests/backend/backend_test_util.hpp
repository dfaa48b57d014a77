#pragma once
// Shared helpers of the backend tests: random poses, numeric Jacobians.
#include <ceres/cost_function.h>
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "slam_mms/core/lie.hpp"

namespace slam_mms::testing_backend {

inline Eigen::Isometry3d RandomPose(std::mt19937& rng, double rot_scale, double trans_scale) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector6d xi;
  for (int i = 0; i < 3; ++i) xi[i] = rot_scale * n(rng);
  for (int i = 3; i < 6; ++i) xi[i] = trans_scale * n(rng);
  return se3::Exp(xi);
}

inline Matrix6d DiagonalCovariance(double sigma_rot, double sigma_trans) {
  Matrix6d c = Matrix6d::Zero();
  c.diagonal() << Eigen::Vector3d::Constant(sigma_rot * sigma_rot),
      Eigen::Vector3d::Constant(sigma_trans * sigma_trans);
  return c;
}

/// Noise sample xi ~ N(0, diag) applied on the right: T * Exp(xi).
inline Eigen::Isometry3d Perturb(const Eigen::Isometry3d& T, std::mt19937& rng, double sigma_rot,
                                 double sigma_trans) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector6d xi;
  for (int i = 0; i < 3; ++i) xi[i] = sigma_rot * n(rng);
  for (int i = 3; i < 6; ++i) xi[i] = sigma_trans * n(rng);
  return T * se3::Exp(xi);
}

/// Central differences of f with respect to every ambient coordinate of every block.
inline void CheckAmbientJacobians(const ceres::CostFunction& f,
                                  std::vector<std::vector<double>> blocks, double tol) {
  const int m = f.num_residuals();
  const auto& sizes = f.parameter_block_sizes();
  std::vector<const double*> params;
  for (auto& b : blocks) params.push_back(b.data());
  std::vector<std::vector<double>> jac(blocks.size());
  std::vector<double*> jac_ptrs;
  for (size_t k = 0; k < blocks.size(); ++k) {
    jac[k].resize(static_cast<size_t>(m * sizes[k]));
    jac_ptrs.push_back(jac[k].data());
  }
  std::vector<double> r0(static_cast<size_t>(m));
  ASSERT_TRUE(f.Evaluate(params.data(), r0.data(), jac_ptrs.data()));
  const double h = 1e-6;
  for (size_t k = 0; k < blocks.size(); ++k) {
    for (int j = 0; j < sizes[k]; ++j) {
      std::vector<double> rp(static_cast<size_t>(m)), rm(static_cast<size_t>(m));
      const double x0 = blocks[k][static_cast<size_t>(j)];
      blocks[k][static_cast<size_t>(j)] = x0 + h;
      ASSERT_TRUE(f.Evaluate(params.data(), rp.data(), nullptr));
      blocks[k][static_cast<size_t>(j)] = x0 - h;
      ASSERT_TRUE(f.Evaluate(params.data(), rm.data(), nullptr));
      blocks[k][static_cast<size_t>(j)] = x0;
      for (int i = 0; i < m; ++i) {
        const double numeric = (rp[static_cast<size_t>(i)] - rm[static_cast<size_t>(i)]) / (2 * h);
        const double analytic = jac[k][static_cast<size_t>(i * sizes[k] + j)];
        EXPECT_NEAR(analytic, numeric, tol * (1.0 + std::abs(numeric)))
            << "block " << k << " residual " << i << " coordinate " << j;
      }
    }
  }
}

}  // namespace slam_mms::testing_backend
