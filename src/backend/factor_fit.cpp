#include "backend/factor_fit.hpp"

#include <ceres/cost_function.h>
#include <ceres/crs_matrix.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <string>
#include <unordered_map>

namespace slam_mms::internal {

StatusOr<std::vector<SubmapGraph::FactorFit>> FitResidualBlocks(
    ceres::Problem* problem, const std::vector<ceres::ResidualBlockId>& blocks,
    const std::vector<double*>& parameters, int num_threads) {
  // Every residual block (they all shape the estimate), the reported ones first, in their order.
  std::vector<ceres::ResidualBlockId> all;
  problem->GetResidualBlocks(&all);
  std::unordered_map<ceres::ResidualBlockId, size_t> position;
  for (size_t i = 0; i < blocks.size(); ++i) position.emplace(blocks[i], i);
  std::vector<ceres::ResidualBlockId> order = blocks;
  for (ceres::ResidualBlockId id : all) {
    if (position.count(id) == 0) order.push_back(id);
  }
  if (static_cast<int>(parameters.size()) != problem->NumParameterBlocks()) {
    return InternalError("FitResidualBlocks: " + std::to_string(parameters.size()) +
                         " parameter blocks given, the problem has " +
                         std::to_string(problem->NumParameterBlocks()));
  }
  std::vector<double*> free;
  for (double* p : parameters) {
    if (!problem->IsParameterBlockConstant(p)) free.push_back(p);
  }
  ceres::Problem::EvaluateOptions eo;
  eo.residual_blocks = order;
  eo.parameter_blocks = free;
  eo.apply_loss_function = false;
  eo.num_threads = num_threads;
  double cost = 0.0;
  std::vector<double> residuals;
  ceres::CRSMatrix jacobian;
  if (!problem->Evaluate(eo, &cost, &residuals, nullptr, &jacobian)) {
    return InternalError("FitResidualBlocks: the problem could not be evaluated");
  }
  // The normal matrix N = J^T J (dense: a level-2 graph has at most a few thousand parameters).
  const int n = jacobian.num_cols;
  Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(n, n);
  for (int r = 0; r < jacobian.num_rows; ++r) {
    for (int a = jacobian.rows[r]; a < jacobian.rows[r + 1]; ++a) {
      for (int b = jacobian.rows[r]; b < jacobian.rows[r + 1]; ++b) {
        normal(jacobian.cols[a], jacobian.cols[b]) += jacobian.values[a] * jacobian.values[b];
      }
    }
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(normal);
  const double max_pivot = n > 0 ? ldlt.vectorD().cwiseAbs().maxCoeff() : 0.0;
  if (ldlt.info() != Eigen::Success ||
      (n > 0 && !(ldlt.vectorD().minCoeff() > 1e-12 * max_pivot))) {
    return FailedPreconditionError(
        "FitResidualBlocks: the normal matrix is singular (" + std::to_string(n) +
        " free parameters): a direction is not observed, so no redundancy is defined");
  }
  const Eigen::MatrixXd inverse = ldlt.solve(Eigen::MatrixXd::Identity(n, n));
  std::vector<SubmapGraph::FactorFit> out(blocks.size());
  int row = 0;
  for (size_t i = 0; i < blocks.size(); ++i) {
    const int dim = problem->GetCostFunctionForResidualBlock(blocks[i])->num_residuals();
    SubmapGraph::FactorFit& f = out[i];
    f.dim = dim;
    f.redundancy = dim;
    for (int r = row; r < row + dim; ++r) {
      f.chi2 += residuals[static_cast<size_t>(r)] * residuals[static_cast<size_t>(r)];
      double h = 0.0;  // j_r N^-1 j_r^T
      for (int a = jacobian.rows[r]; a < jacobian.rows[r + 1]; ++a) {
        for (int b = jacobian.rows[r]; b < jacobian.rows[r + 1]; ++b) {
          h +=
              jacobian.values[a] * inverse(jacobian.cols[a], jacobian.cols[b]) * jacobian.values[b];
        }
      }
      f.redundancy -= h;
    }
    row += dim;
  }
  return out;
}

}  // namespace slam_mms::internal
