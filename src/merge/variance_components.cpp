#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "merge/merge_graph.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms::merge_internal {
namespace {

// Variance component estimation (step 6). A group: a drive's factors of one kind, or (drive -1)
// the cross-drive overlaps.
struct VarianceGroup {
  int64_t drive = -1;
  SubmapFactorKind kind = SubmapFactorKind::kRegistration;
  bool operator<(const VarianceGroup& o) const {
    return std::tie(drive, kind) < std::tie(o.drive, o.kind);
  }
};

// Factors whose errors are correlated in time (GNSS biases, the POS's attitude): their residuals
// after the solve show only the part that varies between them (the estimate follows the rest),
// so their variance is never estimated below the stated one.
bool TimeCorrelated(SubmapFactorKind kind) {
  return kind == SubmapFactorKind::kGnss || kind == SubmapFactorKind::kPosePrior ||
         kind == SubmapFactorKind::kAttitudeChain || kind == SubmapFactorKind::kGnssBias ||
         kind == SubmapFactorKind::kGnssBiasLink;
}

}  // namespace

Status EstimateVarianceComponents(const std::vector<DriveAdjustment::Drive>& drives,
                                  const std::vector<DriveAdjustment::Overlap>& overlaps,
                                  const DriveAdjustment::Options& o, SubmapGraph* graph,
                                  std::vector<FactorOrigin> origins, DriveAdjustment::Result* out) {
  // Each drive factor's group.
  std::vector<std::vector<VarianceGroup>> group_of(drives.size());
  for (size_t d = 0; d < drives.size(); ++d) {
    for (const SubmapGraphFactor& f : drives[d].result.factors) {
      group_of[d].push_back({static_cast<int64_t>(d), f.kind});
    }
  }
  const VarianceGroup overlap_group;  // drive -1, registration
  std::map<VarianceGroup, double> factor_of;
  std::map<VarianceGroup, DriveAdjustment::VarianceComponent> groups;
  FactorScales scales;
  std::map<VarianceGroup, double> applied;  // the factors of the graph solved last
  for (int round = 1; round <= o.variance_component_rounds; ++round) {
    StatusOr<std::vector<SubmapGraph::FactorFit>> fitted = graph->FitFactors();
    if (!fitted.ok() && fitted.status().code() == StatusCode::kFailedPrecondition) {
      // A direction no factor observes (drives without GNSS: where they are as a whole): no
      // redundancy is defined. The adjustment stands as solved, with the factors applied so far.
      out->variance_components_skipped = fitted.status().message();
      SLAM_MMS_LOG(kWarning) << "DriveAdjustment: variance components not estimated: "
                             << fitted.status().message();
      break;
    }
    SLAM_MMS_RETURN_IF_ERROR(fitted.status());
    const std::vector<SubmapGraph::FactorFit>& fits = *fitted;
    if (fits.size() != origins.size()) {
      return InternalError("DriveAdjustment: variance components: factor bookkeeping differs");
    }
    std::map<VarianceGroup, std::pair<double, double>> sums;  // chi2, redundancy
    for (auto& [key, g] : groups) g.factors = 0;
    for (size_t i = 0; i < fits.size(); ++i) {
      const FactorOrigin& from = origins[i];
      if (from.drive >= 0 && from.index < 0) continue;  // a datum bias prior: not a measurement
      const VarianceGroup key =
          from.drive < 0
              ? overlap_group
              : group_of[static_cast<size_t>(from.drive)][static_cast<size_t>(from.index)];
      sums[key].first += fits[i].chi2;
      sums[key].second += fits[i].redundancy;
      const auto [group, created] = groups.try_emplace(key);
      if (created) {
        group->second.drive =
            key.drive >= 0 ? drives[static_cast<size_t>(key.drive)].name : std::string();
        group->second.kind = key.kind;
      }
      ++group->second.factors;
    }
    bool settled = true;
    for (const auto& [key, sum] : sums) {
      DriveAdjustment::VarianceComponent& g = groups[key];
      g.redundancy = sum.second;
      g.estimated = sum.second >= o.variance_component_min_redundancy;
      if (!g.estimated) continue;
      double& factor = factor_of.emplace(key, 1.0).first->second;
      const double next =
          std::clamp(factor * sum.first / sum.second,
                     TimeCorrelated(key.kind) ? 1.0 : o.variance_factor_min, o.variance_factor_max);
      if (std::abs(std::log(next / factor)) > std::log(1.05)) settled = false;
      factor = next;
    }
    out->variance_component_rounds = round;
    if (settled) break;
    scales.drive.assign(drives.size(), {});
    for (size_t d = 0; d < drives.size(); ++d) {
      for (const VarianceGroup& key : group_of[d]) {
        const auto it = factor_of.find(key);
        scales.drive[d].push_back(it == factor_of.end() ? 1.0 : it->second);
      }
    }
    const auto ov = factor_of.find(overlap_group);
    scales.overlap = ov == factor_of.end() ? 1.0 : ov->second;
    applied = factor_of;
    origins.clear();
    SLAM_MMS_ASSIGN_OR_RETURN(SubmapGraph g, BuildGraph(drives, overlaps, o, &scales, &origins));
    SLAM_MMS_ASSIGN_OR_RETURN(out->summary, g.Solve(SolveTrigger::kFinish));
    *graph = std::move(g);
  }
  out->variance_components.clear();
  for (auto& [key, g] : groups) {
    const auto it = applied.find(key);
    g.variance_factor = it == applied.end() ? 1.0 : it->second;
    out->variance_components.push_back(g);
    SLAM_MMS_LOG(kInfo) << "DriveAdjustment: variance factor "
                        << (g.drive.empty() ? std::string("overlaps") : g.drive) << " "
                        << SubmapFactorKindName(g.kind) << ": " << g.variance_factor << " ("
                        << g.factors << " factors, redundancy " << g.redundancy << ")";
  }
  return OkStatus();
}

}  // namespace slam_mms::merge_internal
