#pragma once
// Checks a Ceres cost function's analytic Jacobians against central differences, block by block,
// in the tangent space of each block's manifold (what the solver uses: J_ambient * PlusJacobian).

#include <ceres/cost_function.h>
#include <ceres/manifold.h>

#include <Eigen/Core>
#include <vector>

namespace slam_mms::testing {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct JacobianPair {
  RowMatrix analytic;  // residuals x tangent
  RowMatrix numeric;
};

inline Eigen::VectorXd EvaluateResidual(const ceres::CostFunction& f,
                                        const std::vector<std::vector<double>>& params) {
  std::vector<const double*> ptrs;
  for (const auto& p : params) ptrs.push_back(p.data());
  Eigen::VectorXd r(f.num_residuals());
  f.Evaluate(ptrs.data(), r.data(), nullptr);
  return r;
}

/// manifold may be null (Euclidean block). Step h in the tangent space.
inline JacobianPair CompareJacobian(const ceres::CostFunction& f,
                                    const std::vector<std::vector<double>>& params, int block,
                                    const ceres::Manifold* manifold, double h = 1e-6) {
  const int m = f.num_residuals();
  const int n_amb = f.parameter_block_sizes()[block];
  const int n_tan = manifold ? manifold->TangentSize() : n_amb;
  std::vector<const double*> ptrs;
  for (const auto& p : params) ptrs.push_back(p.data());
  std::vector<RowMatrix> J(params.size());
  std::vector<double*> jptrs(params.size(), nullptr);
  for (size_t b = 0; b < params.size(); ++b) {
    J[b].resize(m, f.parameter_block_sizes()[b]);
    jptrs[b] = J[b].data();
  }
  Eigen::VectorXd r(m);
  f.Evaluate(ptrs.data(), r.data(), jptrs.data());
  JacobianPair out;
  if (manifold) {
    RowMatrix plus_j(n_amb, n_tan);
    manifold->PlusJacobian(params[block].data(), plus_j.data());
    out.analytic = J[block] * plus_j;
  } else {
    out.analytic = J[block];
  }
  out.numeric.resize(m, n_tan);
  for (int k = 0; k < n_tan; ++k) {
    std::vector<std::vector<double>> p_plus = params, p_minus = params;
    Eigen::VectorXd delta = Eigen::VectorXd::Zero(n_tan);
    delta[k] = h;
    if (manifold) {
      manifold->Plus(params[block].data(), delta.data(), p_plus[block].data());
      delta[k] = -h;
      manifold->Plus(params[block].data(), delta.data(), p_minus[block].data());
    } else {
      p_plus[block][k] += h;
      p_minus[block][k] -= h;
    }
    out.numeric.col(k) = (EvaluateResidual(f, p_plus) - EvaluateResidual(f, p_minus)) / (2.0 * h);
  }
  return out;
}

}  // namespace slam_mms::testing
