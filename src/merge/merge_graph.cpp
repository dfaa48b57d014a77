#include "merge/merge_graph.hpp"

#include <string>
#include <vector>

namespace slam_mms::merge_internal {
namespace {

// A drive's own GNSS bias key in the merged graph (the keys below kBiasKeyStride are the
// drives' datum biases, Options::gnss_bias_sigma_m).
constexpr int kBiasKeyStride = 1 << 20;
StatusOr<int> GraphBiasKey(size_t drive, int key) {
  if (key < 0 || key >= kBiasKeyStride || drive + 1 >= size_t{1} << 10) {
    return InvalidArgumentError("GNSS bias key " + std::to_string(key) + " of drive " +
                                std::to_string(drive) + " out of range");
  }
  return static_cast<int>(drive + 1) * kBiasKeyStride + key;
}

constexpr SubmapId kDriveIdStride = SubmapId{1} << 32;

}  // namespace

SubmapId GraphId(size_t drive, SubmapId id) {
  return static_cast<SubmapId>(drive) * kDriveIdStride + id;
}

StatusOr<SubmapGraph> BuildGraph(const std::vector<DriveAdjustment::Drive>& drives,
                                 const std::vector<DriveAdjustment::Overlap>& overlaps,
                                 const DriveAdjustment::Options& o, const FactorScales* scales,
                                 std::vector<FactorOrigin>* origins) {
  SLAM_MMS_ASSIGN_OR_RETURN(SubmapGraph graph, SubmapGraph::Create(o.graph));
  for (size_t d = 0; d < drives.size(); ++d) {
    const DriveResult& r = drives[d].result;
    const std::string ctx = "drive '" + drives[d].name + "'";
    const bool bias = o.gnss_bias_sigma_m > 0.0;
    if (bias) {
      const double v = o.gnss_bias_sigma_m * o.gnss_bias_sigma_m;
      SLAM_MMS_RETURN_IF_ERROR(
          graph.AddGnssBias(static_cast<int>(d), v * Eigen::Matrix3d::Identity()));
      if (origins != nullptr) origins->push_back({static_cast<int64_t>(d), -1});
    }
    for (const DriveSubmap& s : r.submaps) {
      SLAM_MMS_RETURN_IF_ERROR(
          graph.AddSubmap(GraphId(d, s.id), s.T_world_submap).WithContext(ctx));
      std::vector<SubmapScanPose> scans = s.scans;
      SLAM_MMS_RETURN_IF_ERROR(graph.SetScans(GraphId(d, s.id), scans).WithContext(ctx));
    }
    for (size_t i = 0; i < r.factors.size(); ++i) {
      const SubmapId a = GraphId(d, r.factors[i].a), b = GraphId(d, r.factors[i].b);
      SubmapGraphFactor f = r.factors[i];
      if (scales != nullptr) f.covariance *= scales->Of(d, i);
      const size_t num_factors = graph.Factors().size();
      Status st;
      switch (f.kind) {
        case SubmapFactorKind::kRegistration:
          st = graph.AddRegistrationFactor(a, b, f.T, f.covariance, f.loss);
          break;
        case SubmapFactorKind::kReckon: st = graph.AddReckonFactor(a, b, f.T, f.covariance); break;
        case SubmapFactorKind::kLoop:
          st = graph.AddLoopFactor(a, b, f.T, f.covariance).status();
          break;
        case SubmapFactorKind::kPosePrior:
          if (o.use_pose_priors) st = graph.AddPosePrior(a, f.T, f.covariance);
          break;
        case SubmapFactorKind::kAttitudeChain:
          if (o.use_pose_priors) {
            AttitudeChain chain;
            chain.transition = f.transition;
            chain.covariance = f.covariance.topLeftCorner<3, 3>();
            st = graph.AddAttitudeChainFactor(a, b, f.T_a.linear(), f.T.linear(), chain);
          }
          break;
        case SubmapFactorKind::kGnss: {
          // The drive's own bias node (level 2's Gauss-Markov nodes), else the datum bias if any.
          StatusOr<int> key = f.gnss_bias >= 0 ? GraphBiasKey(d, f.gnss_bias)
                                               : StatusOr<int>(bias ? static_cast<int>(d) : -1);
          st = key.ok()
                   ? graph.AddGnssPrior(a, f.p_world_antenna, f.covariance.topLeftCorner<3, 3>(),
                                        f.T_submap_body, f.t_body_antenna, *key)
                   : key.status();
          break;
        }
        case SubmapFactorKind::kGnssBias: {  // a run's first node (no datum bias: Run)
          StatusOr<int> key = GraphBiasKey(d, f.gnss_bias);
          st =
              key.ok() ? graph.AddGnssBias(*key, f.covariance.topLeftCorner<3, 3>()) : key.status();
          break;
        }
        case SubmapFactorKind::kGnssBiasLink: {
          StatusOr<int> key = GraphBiasKey(d, f.gnss_bias);
          StatusOr<int> from = GraphBiasKey(d, f.gnss_bias_from);
          st = !key.ok()    ? key.status()
               : !from.ok() ? from.status()
                            : graph.AddGnssBiasLink(*from, *key, f.transition(0, 0),
                                                    f.covariance.topLeftCorner<3, 3>());
          break;
        }
      }
      if (!st.ok()) {
        return InvalidArgumentError(ctx + ": " + SubmapFactorKindName(f.kind) + " factor " +
                                    std::to_string(f.a) + "->" + std::to_string(f.b) + ": " +
                                    st.message());
      }
      if (origins != nullptr && graph.Factors().size() > num_factors) {
        origins->push_back({static_cast<int64_t>(d), static_cast<int64_t>(i)});
      }
    }
  }
  for (const DriveAdjustment::Overlap& ov : overlaps) {
    if (!ov.accepted) continue;
    SLAM_MMS_RETURN_IF_ERROR(graph.AddRegistrationFactor(
        GraphId(ov.drive_a, ov.submap_a), GraphId(ov.drive_b, ov.submap_b), ov.T_a_b,
        (scales != nullptr ? scales->overlap : 1.0) * ov.covariance, o.overlap_loss));
    if (origins != nullptr) origins->push_back({-1, -1});
  }
  return graph;
}

}  // namespace slam_mms::merge_internal
