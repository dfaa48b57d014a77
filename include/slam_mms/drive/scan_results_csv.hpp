#pragma once
// The per-scan level-1 results of a run as CSV (slam_mms_run's <method>_scans.csv, also written by
// `python -m slam_mms run`): one row per LocalizationResult with the registration outcome,
// degeneracy, motion factor and the stage times.
//
// Columns: scan_index, t_utc_ns (the scan start, int64 UTC ns: the outputs' one time format),
// submap_id, motion_factor, registered, registration_used, downweighted, termination, inlier_ratio,
// rms_residual_m, icp_iterations, degenerate, consistency_d2, num_model_surfels, num_surfels, one
// <stage>_ms per StageTimings::Names(), total_ms. Numbers with 9 significant digits; booleans 0/1.
//
// Thread safety: a free function; one call per output file.

#include <filesystem>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/localization_result.hpp"

namespace slam_mms {

/// Writes `results` to `path` (overwritten). kUnavailable where the file cannot be opened,
/// kDataLoss where a write fails.
[[nodiscard]] Status WriteScanResultsCsv(const std::vector<LocalizationResult>& results,
                                         const std::filesystem::path& path);

}  // namespace slam_mms
