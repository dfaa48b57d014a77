#include "backend/ceres_solve.hpp"

#include <ceres/covariance.h>
#include <ceres/solver.h>

#include <cmath>
#include <utility>
#include <vector>

#include "backend/backend_math.hpp"
#include "backend/pose_block.hpp"

namespace slam_mms::backend_internal {

SolveSummary SolveProblem(ceres::Problem* problem, const CeresSolveOptions& options) {
  SolveSummary summary;
  std::vector<double*> blocks;
  problem->GetParameterBlocks(&blocks);
  for (double* p : blocks) summary.num_free_states += problem->IsParameterBlockConstant(p) ? 0 : 1;
  summary.num_residual_blocks = problem->NumResidualBlocks();
  if (summary.num_free_states == 0 || summary.num_residual_blocks == 0) {
    summary.termination = SolveTermination::kNothingToSolve;
    summary.message = "no free parameter block or no factor";
    return summary;
  }
  std::vector<std::vector<double>> backup;
  backup.reserve(blocks.size());
  for (double* p : blocks) backup.emplace_back(p, p + problem->ParameterBlockSize(p));

  ceres::Solver::Options so;
  so.minimizer_type = ceres::TRUST_REGION;
  so.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  so.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  so.sparse_linear_algebra_library_type = ceres::SUITE_SPARSE;
  so.num_threads = options.num_threads;
  so.max_num_iterations = options.max_iterations;
  so.max_solver_time_in_seconds = options.max_solve_time_s;
  so.function_tolerance = options.function_tolerance;
  so.logging_type = ceres::SILENT;
  so.minimizer_progress_to_stdout = false;
  std::string error;
  if (!so.IsValid(&error)) {
    summary.termination = SolveTermination::kFailure;
    summary.message = "invalid solver options: " + error;
    return summary;
  }
  ceres::Solver::Summary cs;
  ceres::Solve(so, problem, &cs);
  summary.iterations =
      static_cast<int>(cs.iterations.size()) > 0 ? static_cast<int>(cs.iterations.size()) - 1 : 0;
  summary.initial_cost = cs.initial_cost;
  summary.final_cost = cs.final_cost;
  summary.solve_time_s = cs.total_time_in_seconds;
  summary.message = cs.message;
  switch (cs.termination_type) {
    case ceres::CONVERGENCE: summary.termination = SolveTermination::kConverged; break;
    case ceres::NO_CONVERGENCE: summary.termination = SolveTermination::kNoConvergence; break;
    default: summary.termination = SolveTermination::kFailure; break;
  }
  bool finite = std::isfinite(cs.final_cost);
  for (double* p : blocks) {
    for (int i = 0; i < problem->ParameterBlockSize(p); ++i) finite &= std::isfinite(p[i]);
  }
  if (!finite) {
    summary.termination = SolveTermination::kFailure;
    summary.message += " (non-finite result)";
  }
  if (summary.termination == SolveTermination::kFailure) {
    for (size_t i = 0; i < blocks.size(); ++i)
      std::copy(backup[i].begin(), backup[i].end(), blocks[i]);
  }
  return summary;
}

StatusOr<Matrix6d> PoseBlockCovariance(ceres::Problem* problem, const double* pose_block,
                                       int num_threads) {
  if (!problem->HasParameterBlock(pose_block)) {
    return NotFoundError("pose covariance: the block is not in the problem");
  }
  if (problem->IsParameterBlockConstant(pose_block)) {
    return FailedPreconditionError("pose covariance: the pose is held constant");
  }
  ceres::Covariance::Options co;
  co.algorithm_type = ceres::SPARSE_QR;
  co.num_threads = num_threads;
  ceres::Covariance covariance(co);
  const std::vector<std::pair<const double*, const double*>> pairs = {{pose_block, pose_block}};
  if (!covariance.Compute(pairs, problem)) {
    return FailedPreconditionError(
        "pose covariance: the factors do not constrain the pose (rank-deficient Jacobian)");
  }
  Eigen::Matrix<double, 6, 6, Eigen::RowMajor> c;
  if (!covariance.GetCovarianceBlockInTangentSpace(pose_block, pose_block, c.data())) {
    return InternalError("pose covariance: Ceres could not return the block");
  }
  if (!c.allFinite()) return InternalError("pose covariance: not finite");
  const Eigen::Isometry3d T = PoseFromBlock(pose_block);
  return CeresTangentCovarianceToLibrary(Matrix6d(c), T.linear());
}

}  // namespace slam_mms::backend_internal
