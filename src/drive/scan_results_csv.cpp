#include "slam_mms/drive/scan_results_csv.hpp"

#include <fstream>

namespace slam_mms {

Status WriteScanResultsCsv(const std::vector<LocalizationResult>& results,
                           const std::filesystem::path& path) {
  std::ofstream f(path);
  if (!f) return UnavailableError("cannot write " + path.string());
  f << "scan_index,t_utc_ns,submap_id,motion_factor,registered,registration_used,downweighted,"
       "termination,inlier_ratio,rms_residual_m,icp_iterations,degenerate,consistency_d2,"
       "num_model_surfels,num_surfels,num_moving_objects,num_moving_pixels";
  for (const char* name : StageTimings::Names()) f << "," << name << "_ms";
  f << ",total_ms\n";
  f.precision(9);
  for (const LocalizationResult& r : results) {
    f << r.scan_index << "," << r.stamp.nanoseconds() << "," << r.submap_id << ","
      << MotionFactorTypeName(r.motion_factor) << "," << r.registered << "," << r.registration_used
      << "," << r.registration_downweighted << "," << IcpTerminationName(r.termination) << ","
      << r.inlier_ratio << "," << r.rms_residual_m << "," << r.icp_iterations << "," << r.degenerate
      << "," << r.consistency_mahalanobis_sq << "," << r.num_model_surfels << "," << r.num_surfels
      << "," << r.num_moving_objects << "," << r.num_moving_pixels;
    for (double v : r.timings.Values()) f << "," << v;
    f << "," << r.timings.total_ms << "\n";
  }
  if (!f) return DataLossError("write failed: " + path.string());
  return OkStatus();
}

}  // namespace slam_mms
