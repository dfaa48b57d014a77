#include "slam_mms/backend/robust_loss.hpp"

#include <ceres/loss_function.h>

#include <cmath>
#include <string>

#include "slam_mms/backend/solve_summary.hpp"

namespace slam_mms {

Status RobustLoss::Validate() const {
  if (!(scale > 0.0) || !std::isfinite(scale)) {
    return InvalidArgumentError("RobustLoss::scale = " + std::to_string(scale) +
                                "; must be finite and > 0");
  }
  return OkStatus();
}

ceres::LossFunction* RobustLoss::NewLossFunction() const {
  switch (type) {
    case RobustLossType::kHuber: return new ceres::HuberLoss(scale);
    case RobustLossType::kCauchy: return new ceres::CauchyLoss(scale);
    case RobustLossType::kNone: break;
  }
  return nullptr;
}

double RobustLoss::Weight(double squared_norm) const {
  const double b = scale * scale;
  switch (type) {
    case RobustLossType::kHuber: return squared_norm <= b ? 1.0 : scale / std::sqrt(squared_norm);
    case RobustLossType::kCauchy: return 1.0 / (1.0 + squared_norm / b);
    case RobustLossType::kNone: break;
  }
  return 1.0;
}

const char* RobustLossTypeName(RobustLossType type) {
  switch (type) {
    case RobustLossType::kNone: return "none";
    case RobustLossType::kHuber: return "huber";
    case RobustLossType::kCauchy: return "cauchy";
  }
  return "unknown";
}

const char* SolveTerminationName(SolveTermination t) {
  switch (t) {
    case SolveTermination::kConverged: return "converged";
    case SolveTermination::kNoConvergence: return "no_convergence";
    case SolveTermination::kFailure: return "failure";
    case SolveTermination::kNothingToSolve: return "nothing_to_solve";
  }
  return "unknown";
}

}  // namespace slam_mms
