#pragma once
// The merged graph of DriveAdjustment (src/merge/drive_adjustment.cpp) and its step 6, variance
// component estimation (src/merge/variance_components.cpp). Private to the merge module.

#include <cstdint>
#include <vector>

#include "slam_mms/backend/submap_graph.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/merge/drive_adjustment.hpp"

namespace slam_mms::merge_internal {

// A drive's submap id in the merged graph: drive d's ids are offset by d * 2^32.
SubmapId GraphId(size_t drive, SubmapId id);

// Per drive, per factor of its result (same order): the variance factor of its covariance; and
// the overlaps'. Empty: every factor as stated.
struct FactorScales {
  std::vector<std::vector<double>> drive;
  double overlap = 1.0;
  double Of(size_t d, size_t i) const { return d < drive.size() ? drive[d][i] : 1.0; }
};
// Where a factor of the merged graph comes from: a drive's factor (drive, index into its result's
// factors) or (drive -1) an overlap; a datum bias (index -1) of a drive.
struct FactorOrigin {
  int64_t drive = -1;
  int64_t index = -1;
};

// The graph of every drive plus the accepted overlaps; each factor's covariance scaled by
// `scales` (null: as stated); `origins` (may be null): per factor of the graph, where it is from.
StatusOr<SubmapGraph> BuildGraph(const std::vector<DriveAdjustment::Drive>& drives,
                                 const std::vector<DriveAdjustment::Overlap>& overlaps,
                                 const DriveAdjustment::Options& o,
                                 const FactorScales* scales = nullptr,
                                 std::vector<FactorOrigin>* origins = nullptr);

// Step 6: rounds of scaling each group (a drive's factors of one kind; the overlaps) by
// sum chi2 / sum redundancy and solving again, until every factor of a round is within 5 % of the
// last; `graph` (solved, built with `origins`) is replaced by the last solve, and the factors
// reported (out->variance_components) are those it was solved with.
Status EstimateVarianceComponents(const std::vector<DriveAdjustment::Drive>& drives,
                                  const std::vector<DriveAdjustment::Overlap>& overlaps,
                                  const DriveAdjustment::Options& o, SubmapGraph* graph,
                                  std::vector<FactorOrigin> origins, DriveAdjustment::Result* out);

}  // namespace slam_mms::merge_internal
