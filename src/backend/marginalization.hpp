#pragma once
// Marginalization by the Schur complement (private to the backend module).
//
// Given the residual blocks that touch the parameter blocks to remove, evaluate them at the current
// estimate (with the robust loss applied, as Ceres's solver sees them), form the Gauss-Newton
// system H = J^T J, b = J^T r over [removed | kept] tangent coordinates, and eliminate the removed
// part:
//
//   H* = H_kk - H_km H_mm^+ H_mk,     b* = b_k - H_km H_mm^+ b_m.
//
// The result is a MarginalPriorFactor on the kept blocks, r(x) = S (x [-] x_lin) + e0 with
// S^T S = H* and S^T e0 = b*, so that |r|^2 = dx^T H* dx + 2 b*^T dx + const: the same quadratic as
// the eliminated factors, to first order. [-] is the Minus of the blocks' Ceres manifolds
// (PoseManifold for poses: translation difference, half-angle left rotation difference; plain
// difference for vectors). Its Jacobian is evaluated exactly at x, so the prior's Jacobian in the
// Ceres tangent is S at x = x_lin.

#include <ceres/cost_function.h>
#include <ceres/problem.h>

#include <Eigen/Core>
#include <memory>
#include <set>
#include <vector>

#include "slam_mms/core/status.hpp"

namespace slam_mms::backend_internal {

struct LinearizedBlock {
  double* param = nullptr;  ///< The block in the problem (identity only; values are read by Ceres).
  bool is_pose = false;  ///< 7 ambient / 6 tangent (PoseManifold); else a vector, tangent = size.
  int ambient_size = 0;
  int tangent_size = 0;
  std::vector<double> x_lin;  ///< Value at linearisation.
};

class MarginalPriorFactor final : public ceres::CostFunction {
 public:
  MarginalPriorFactor(std::vector<LinearizedBlock> blocks, Eigen::MatrixXd S, Eigen::VectorXd e0);

  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

  const std::vector<LinearizedBlock>& blocks() const { return blocks_; }
  std::vector<double*> parameter_pointers() const;

 private:
  std::vector<LinearizedBlock> blocks_;
  Eigen::MatrixXd S_;
  Eigen::VectorXd e0_;
};

/// Builds the prior that replaces `residual_blocks` after `removed` parameter blocks leave.
/// Returns nullptr (OK) when the residuals touch no kept, non-constant block.
StatusOr<std::unique_ptr<MarginalPriorFactor>> MarginalizeBlocks(
    const ceres::Problem& problem, const std::vector<ceres::ResidualBlockId>& residual_blocks,
    const std::set<double*>& removed, double eigen_threshold);

}  // namespace slam_mms::backend_internal
