#pragma once
// SolveSummary: the outcome of one back-end solve, a value in the spirit of ceres::Solver::Summary.
// A solve that ran but failed (numerical failure, bad linear solve) is reported here, not as a
// Status: Status is for bad input.
//
// Thread safety: value type.

#include <string>

namespace slam_mms {

enum class SolveTermination {
  kConverged,       ///< A Ceres tolerance was reached.
  kNoConvergence,   ///< Iteration or time limit reached; the estimate improved but may not be
                    ///< optimal.
  kFailure,         ///< The solver failed; the estimate is the one before the solve.
  kNothingToSolve,  ///< No free state or no factor.
};

const char* SolveTerminationName(SolveTermination t);

struct SolveSummary {
  SolveTermination termination = SolveTermination::kNothingToSolve;
  int iterations = 0;         ///< Levenberg-Marquardt iterations (successful + unsuccessful).
  double initial_cost = 0.0;  ///< 0.5 * sum of squared (robustified) whitened residuals.
  double final_cost = 0.0;
  double solve_time_s = 0.0;    ///< Wall time inside ceres::Solve.
  int num_free_states = 0;      ///< Parameter blocks the solve could move.
  int num_residual_blocks = 0;  ///< Factors that entered the solve.
  std::string message;          ///< Ceres's message or ours.

  /// True when the estimate may be used (converged, or stopped at a limit after improving it).
  bool usable() const {
    return termination == SolveTermination::kConverged ||
           termination == SolveTermination::kNoConvergence;
  }
};

}  // namespace slam_mms
