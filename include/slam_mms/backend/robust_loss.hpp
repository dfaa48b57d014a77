#pragma once
// RobustLoss: which Ceres loss function robustifies a factor, chosen per factor. The scale is in
// units of the WHITENED residual (i.e. in standard deviations): a factor whose Mahalanobis norm
// exceeds `scale` is down-weighted.
//
// Thread safety: value type.

#include "slam_mms/core/status.hpp"

namespace ceres {
class LossFunction;
}

namespace slam_mms {

enum class RobustLossType {
  kNone,    ///< Plain least squares.
  kHuber,   ///< Quadratic up to `scale`, linear beyond (convex; bounded influence).
  kCauchy,  ///< log(1 + s/scale^2): redescending influence, for loops that may be wrong.
};

struct RobustLoss {
  RobustLossType type = RobustLossType::kNone;
  double scale = 1.0;  ///< Whitened residual norm where down-weighting starts [sigma], > 0.

  static RobustLoss None() { return {}; }
  static RobustLoss Huber(double scale) { return {RobustLossType::kHuber, scale}; }
  static RobustLoss Cauchy(double scale) { return {RobustLossType::kCauchy, scale}; }

  [[nodiscard]] Status Validate() const;

  /// A new Ceres loss function (nullptr for kNone); the caller (or the Problem) owns it.
  ceres::LossFunction* NewLossFunction() const;

  /// rho'(s) for the squared whitened norm s: the weight an IRLS step gives the factor (1 for
  /// kNone).
  double Weight(double squared_norm) const;
};

const char* RobustLossTypeName(RobustLossType type);

}  // namespace slam_mms
