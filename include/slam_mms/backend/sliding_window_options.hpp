#pragma once
// The options of level 1's sliding-window graph, as the SDK exposes them
// (Localizer::Options::window). The graph itself is internal (src/backend); its Ceres threads come
// from the Localizer's one num_threads.
//
// Thread safety: plain values.

#include "slam_mms/core/status.hpp"

namespace slam_mms {

/// What happens to a state that leaves the window: kMarginalize folds its factors into a Gaussian
/// prior on its neighbours (Schur complement); kFix holds it constant (the window becomes
/// over-confident). See docs/backend.md.
enum class WindowExitMode { kMarginalize, kFix };
/// A registration that fails the consistency gate: rejected, or down-weighted (its covariance
/// inflated by d2 / gate).
enum class WindowInconsistencyAction { kReject, kDownWeight };

struct SlidingWindowOptions {
  int window_size = 10;  ///< Non-kept states kept after Solve(), > 0.
  WindowExitMode exit_mode = WindowExitMode::kMarginalize;
  int max_iterations = 100;          ///< Levenberg-Marquardt iterations (paper: <= 100), > 0.
  double max_solve_time_s = 1.0;     ///< Wall-time cap of one solve [s], > 0.
  double function_tolerance = 1e-8;  ///< Ceres relative cost change to stop, > 0.
  /// Chi-square gate on d2 (6 DoF); 22.46 is the 99.9 % quantile. > 0.
  double consistency_gate_chi2 = 22.46;
  WindowInconsistencyAction inconsistency_action = WindowInconsistencyAction::kReject;
  /// Eigenvalues of the marginal information below this fraction of the largest are dropped
  /// (directions the removed factors did not observe), >= 0.
  double marginalization_eigen_threshold = 1e-12;

  /// InvalidArgument naming "SlidingWindowGraph::Options::<field>".
  [[nodiscard]] Status Validate() const;
};

}  // namespace slam_mms
