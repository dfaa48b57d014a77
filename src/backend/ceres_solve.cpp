#include "backend/ceres_solve.hpp"

#include <ceres/solver.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <unordered_set>
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
  // Not ceres::Covariance: it orders the parameter blocks by their memory addresses, so its sparse
  // QR pivoted differently from run to run and the covariance's last bits, fed back as weights,
  // made `full` non-deterministic (2.7e-5 m between two runs of one drive). Here the columns are
  // the free blocks in the order the residual blocks (insertion order) first use them, and the
  // marginal is the pose's block of (J^T J)^-1 from a Cholesky factorization of the Jacobi-scaled
  // normal matrix: the same result on every run, for any thread count.
  std::vector<ceres::ResidualBlockId> residual_blocks;
  problem->GetResidualBlocks(&residual_blocks);
  ceres::Problem::EvaluateOptions eo;
  eo.residual_blocks = residual_blocks;
  eo.num_threads = num_threads;
  std::unordered_set<const double*> seen;
  int pose_column = -1;
  int columns = 0;
  std::vector<double*> in_block;
  for (ceres::ResidualBlockId r : residual_blocks) {
    problem->GetParameterBlocksForResidualBlock(r, &in_block);
    for (double* p : in_block) {
      if (problem->IsParameterBlockConstant(p) || !seen.insert(p).second) continue;
      if (p == pose_block) pose_column = columns;
      eo.parameter_blocks.push_back(p);
      columns += problem->ParameterBlockTangentSize(p);
    }
  }
  if (pose_column < 0) {
    return FailedPreconditionError("pose covariance: no factor constrains the pose");
  }
  ceres::CRSMatrix J;
  if (!problem->Evaluate(eo, nullptr, nullptr, nullptr, &J) || J.num_cols != columns) {
    return InternalError("pose covariance: the Jacobian could not be evaluated");
  }
  // H = J^T J, row by row in a fixed order.
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(columns, columns);
  for (int row = 0; row < J.num_rows; ++row) {
    for (int a = J.rows[row]; a < J.rows[row + 1]; ++a) {
      const double va = J.values[a];
      for (int b = J.rows[row]; b < J.rows[row + 1]; ++b)
        H(J.cols[a], J.cols[b]) += va * J.values[b];
    }
  }
  if (!H.allFinite()) return InternalError("pose covariance: the Jacobian is not finite");
  Eigen::VectorXd scale(columns);
  for (int i = 0; i < columns; ++i) {
    if (!(H(i, i) > 0.0)) {
      return FailedPreconditionError(
          "pose covariance: the factors do not constrain the problem (a zero Jacobian column)");
    }
    scale(i) = 1.0 / std::sqrt(H(i, i));
  }
  const Eigen::MatrixXd Hs = scale.asDiagonal() * H * scale.asDiagonal();
  const Eigen::LLT<Eigen::MatrixXd> llt(Hs);
  // Rank: the scaled normal matrix's reciprocal condition (a nearly free direction, as the QR's
  // rank test found it; kMinReciprocalCondition bounds cond(J) at 1e7 after scaling).
  constexpr double kMinReciprocalCondition = 1e-14;
  if (llt.info() != Eigen::Success || !(llt.rcond() > kMinReciprocalCondition)) {
    return FailedPreconditionError(
        "pose covariance: the factors do not constrain the pose (rank-deficient Jacobian)");
  }
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(columns, 6);
  E.block<6, 6>(pose_column, 0).setIdentity();
  const Eigen::MatrixXd X = llt.solve(E);  // columns of Hs^-1 at the pose
  Matrix6d c;
  for (int i = 0; i < 6; ++i) {
    for (int j = 0; j < 6; ++j) {
      c(i, j) = scale(pose_column + i) * X(pose_column + i, j) * scale(pose_column + j);
    }
  }
  c = 0.5 * (c + c.transpose()).eval();
  if (!c.allFinite()) return InternalError("pose covariance: not finite");
  const Eigen::Isometry3d T = PoseFromBlock(pose_block);
  return CeresTangentCovarianceToLibrary(c, T.linear());
}

}  // namespace slam_mms::backend_internal
