#pragma once
// The one place where the backend calls ceres::Solve and computes covariances (private).

#include <ceres/problem.h>

#include "slam_mms/backend/solve_summary.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms::backend_internal {

struct CeresSolveOptions {
  int max_iterations = 100;
  double max_solve_time_s = 1.0;
  int num_threads = 2;
  double function_tolerance = 1e-8;
};

/// Levenberg-Marquardt, SPARSE_NORMAL_CHOLESKY on SuiteSparse. Restores the parameters when Ceres
/// reports a failure or leaves a non-finite value.
SolveSummary SolveProblem(ceres::Problem* problem, const CeresSolveOptions& options);

/// Covariance of one pose block, rotation first, right perturbation: its block of (J^T J)^-1 over
/// every free block, with the robust losses applied. Deterministic (independent of memory
/// addresses and thread count). FailedPrecondition when the block is constant or the problem
/// does not constrain it (a rank-deficient Jacobian).
StatusOr<Matrix6d> PoseBlockCovariance(ceres::Problem* problem, const double* pose_block,
                                       int num_threads);

}  // namespace slam_mms::backend_internal
