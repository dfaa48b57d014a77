#include "slam_mms_run/plot_outputs.hpp"

#include <algorithm>
#include <string>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/eval/plots.hpp"

namespace slam_mms::app {

void WritePlots(const std::vector<ModeRun>& runs, const std::vector<MethodEvaluation>& evals,
                const eval::GroundTruth* gt, const std::vector<eval::OutageWindow>& outages,
                Timestamp reference, const std::filesystem::path& out_dir) {
  auto warn = [](const char* what, const Status& s) {
    if (!s.ok()) {
      SLAM_MMS_LOG(kWarning) << what << ": " << s.ToString();
    }
  };
  std::vector<eval::NamedTrajectory> methods;
  for (const ModeRun& r : runs) {
    if (!r.trajectory.empty()) methods.push_back({r.name, r.trajectory});
  }
  if (gt != nullptr && !methods.empty()) {
    // The ground truth over the span of the estimates only (the simulator's covers the lead-in).
    Trajectory gt_span;
    Timestamp t_min = methods.front().trajectory.start(), t_max = methods.front().trajectory.end();
    for (const auto& m : methods) {
      t_min = std::min(t_min, m.trajectory.start());
      t_max = std::max(t_max, m.trajectory.end());
    }
    for (const StampedPose& p : gt->T_world_body.poses()) {
      if (p.stamp >= t_min && p.stamp <= t_max) (void)gt_span.Add(p);
    }
    if (gt_span.size() < 2) gt_span = gt->T_world_body;
    eval::PlotOptions po;
    po.title = "Trajectories from above (ground truth: " + gt->kind + ")";
    warn("trajectories.png",
         eval::PlotTrajectoriesTopView({"ground truth (" + gt->kind + ")", gt_span}, methods,
                                       outages, reference, out_dir / "trajectories.png", po));
    std::vector<eval::ErrorSeries> series;
    for (const MethodEvaluation& e : evals) {
      if (e.ate) series.push_back(eval::MakeErrorSeries(e.name, e.ate->errors, reference));
    }
    if (!series.empty()) {
      eval::PlotOptions pe;
      pe.title = "Position error vs " + gt->kind + " ground truth";
      warn("position_error.png",
           eval::PlotPositionErrors(series, outages, out_dir / "position_error.png", pe));
    }
  }
  for (const ModeRun& r : runs) {
    if (r.mode == MappingMode::kLidarOnly || r.map.empty()) continue;
    std::vector<Eigen::Vector3d> overlay;
    for (const StampedPose& p : r.trajectory.poses())
      overlay.push_back(p.T_world_body.translation());
    eval::PlotOptions pm;
    pm.title = "Map of " + r.name + " from above, coloured by height";
    const std::string file = "map_" + r.name + "_height.png";
    warn(file.c_str(), eval::PlotMapHeight(r.map, overlay, out_dir / file, pm));
  }
}

}  // namespace slam_mms::app
