#pragma once
// PNG plots of slam_mms_run (trajectories, position error, map height) from the runs and their
// evaluations (outputs.hpp).

#include <filesystem>
#include <vector>

#include "slam_mms/eval/ground_truth.hpp"
#include "slam_mms/eval/outage_error.hpp"
#include "slam_mms_run/outputs.hpp"
#include "slam_mms_run/run_mode.hpp"

namespace slam_mms::app {

/// trajectories.png, position_error.png, map_<name>_height.png (full, gnss_ins). Logs failures.
void WritePlots(const std::vector<ModeRun>& runs, const std::vector<MethodEvaluation>& evals,
                const eval::GroundTruth* gt, const std::vector<eval::OutageWindow>& outages,
                Timestamp reference, const std::filesystem::path& out_dir);

}  // namespace slam_mms::app
