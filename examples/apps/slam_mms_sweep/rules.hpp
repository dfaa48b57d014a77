#pragma once
// The robustness sweep's rules (issue 15) and its tables. Each rule gives "pass", "FAIL" or "n/a"
// (does not apply to the run) with a reason naming the numbers:
//   sane             the run's process exited normally within its time limit, every method
//                    completed with status ok, processed every scan, and wrote no NaN/inf pose
//                    or map point ("no crash, no hang, no NaN in any output");
//   lidar_tracks     lidar_only: t_rel <= 1.0 % where not flagged degenerate; flagged
//                    (degenerate_fraction >= 0.1 of the registered scans): largest drift from
//                    the start (max_drift_from_start_m) <= 3 % of the distance travelled; a
//                    window too short for a 10 m segment: largest drift <= 1 % of the distance
//                    + 0.1 m;
//   full_vs_pos_rtk  RTK fixed all the way (>= 99 % fixed, no outage): full ATE <=
//                    max(1.1 x gnss_ins, gnss_ins + 0.02 m) and rotation RMSE <= gnss_ins +
//                    0.05 deg;
//   standing_still   a window standing still (class "standing"): full rotation RMSE <= gnss_ins
//                    + 0.05 deg (standing must not rotate the estimate);
//   full_map_sharper full MME < gnss_ins MME;
//   full_bounded     full ATE <= 2 x the input records' own ATE (sim.records_ate_m: the OXTS
//                    positions against the truth over the scans) + 0.1 m; n/a without it.
// The real-frame rule (real_lidar_drift): lidar_only t_rel over 10 m <= 3.28 % and r_rel over
// 25 m <= 0.89 deg/100 m (the public LiDAR-only peer, KISS-ICP, on the same frames).
//
// Thread safety: free functions.

#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "slam_mms/core/status.hpp"

namespace slam_mms::sweep {

struct RuleOutcome {
  std::string rule;
  std::string verdict;  ///< "pass", "FAIL" or "n/a".
  std::string reason;   ///< The numbers behind the verdict.
};

/// The result of one run as the parent saw it: result.json (may be null) plus how the process
/// ended ("" = exit 0; else e.g. "exit 1", "signal 11", "timeout after 900 s").
struct RunRecord {
  nlohmann::json spec;
  nlohmann::json result;
  std::string process_error;
  double wall_s = 0.0;
};

std::vector<RuleOutcome> EvaluateRules(const RunRecord& run);
/// The real-frame rule on --real-one's result (null result: FAIL naming process_error).
RuleOutcome EvaluateRealRule(const RunRecord& real);

/// The rule names, in table order.
const std::vector<std::string>& RuleNames();

/// sweep.csv (one row per run, every metric), sweep.md (the table of docs/, the rule counts and
/// every failure named by run, seed and rule) and sweep.json (every record and outcome).
/// `command` is the sweep's command line (written into sweep.md).
Status WriteSweepTables(const std::vector<RunRecord>& runs, const RunRecord* real,
                        const std::string& command, const std::filesystem::path& out_dir,
                        int* num_failures);

}  // namespace slam_mms::sweep
