#pragma once
// How the residual blocks of a solved Ceres problem fit its estimate: per block, its squared
// whitened residual (the loss function not applied), its dimension and its redundancy number
// r = tr(I - J_b (J^T J)^-1 J_b^T) (J the whitened Jacobian over the free parameter blocks, J_b a
// block's rows). The redundancies of all blocks sum to the number of residuals minus the number
// of free parameters (where J has full column rank); E[chi2_b] = r_b when the block's covariance
// is right, so sum(chi2) / sum(r) over a group of factors is the group's variance factor
// (variance component estimation, Foerstner 1979). Private to the backend.
//
// Written by hand: Ceres gives the Jacobian (Problem::Evaluate) but not the hat matrix's
// diagonal; ceres::Covariance gives blocks of (J^T J)^-1 but not per-row products with J.
//
// Thread safety: reads the problem; not safe beside a solve of the same problem.

#include <ceres/problem.h>

#include <vector>

#include "slam_mms/backend/submap_graph.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms::internal {

/// `blocks`: the residual blocks to report, in that order (every block of the problem enters the
/// estimate's Jacobian). `parameters`: every parameter block of the problem in a fixed order (the
/// constant ones are left out); Ceres's own listing is ordered by address, which would make the
/// last digits depend on where the heap put the blocks. FailedPrecondition where the normal
/// matrix is singular on the free parameters (an unobservable direction: no redundancy is
/// defined).
StatusOr<std::vector<SubmapGraph::FactorFit>> FitResidualBlocks(
    ceres::Problem* problem, const std::vector<ceres::ResidualBlockId>& blocks,
    const std::vector<double*>& parameters, int num_threads);

}  // namespace slam_mms::internal
