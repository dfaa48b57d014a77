#include "pipeline/submap_manager.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <optional>
#include <sstream>
#include <string>
#include <utility>

#include "core/option_error.hpp"
#include "pipeline/noise_model.hpp"
#include "pipeline/pose_covariance.hpp"
#include "slam_mms/backend/submap_graph.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {

namespace noise = internal::noise;
namespace {

const SubmapRecord* FindSubmap(const SubmapSource& loc, int32_t id) {
  for (const SubmapRecord& rec : loc.submaps()) {
    if (rec.id == id) return &rec;
  }
  return nullptr;
}

/// T_submap_body at `t` by interpolating the submap's scan poses (clamped extrapolation).
Eigen::Isometry3d BodyPoseAt(const SubmapRecord& rec, Timestamp t) {
  const auto& stamps = rec.scan_stamps;
  if (stamps.size() == 1 || t <= stamps.front()) return rec.T_submap_scan.front();
  if (t >= stamps.back()) return rec.T_submap_scan.back();
  const auto it = std::upper_bound(stamps.begin(), stamps.end(), t);
  const size_t j = static_cast<size_t>(it - stamps.begin());
  const double alpha = t.SecondsSince(stamps[j - 1]) / stamps[j].SecondsSince(stamps[j - 1]);
  return InterpolatePose(rec.T_submap_scan[j - 1], rec.T_submap_scan[j], alpha);
}

constexpr double kRadToDeg = 180.0 / M_PI;

/// How many measurements share one error when the error is correlated over `window_s` and the
/// previous one was taken at `*last` (Options::gnss_correlation_s, pos_attitude_correlation_s):
/// window / (time since it), at least 1; 1 for the first one or where window_s is 0. Sets
/// `*last` to `now`. A measurement's covariance is multiplied by it.
double CorrelatedCount(double window_s, std::optional<Timestamp>* last, Timestamp now) {
  double count = 1.0;
  if (window_s > 0.0 && last->has_value()) {
    count = window_s / std::clamp(now.SecondsSince(**last), 1e-3, window_s);
  }
  *last = now;
  return count;
}

/// "a / b / c deg": the rotation sigmas of a pose covariance (rotation first), for the logs.
std::string RotationSigmasDeg(const Matrix6d& cov) {
  std::ostringstream out;
  out << std::sqrt(cov(0, 0)) * kRadToDeg << " / " << std::sqrt(cov(1, 1)) * kRadToDeg << " / "
      << std::sqrt(cov(2, 2)) * kRadToDeg << " deg";
  return out.str();
}

}  // namespace

Status Level2Options::Validate() const {
  auto bad = [](const char* f, double v, const char* rule) {
    return internal::OptionError("SubmapManager::Options", f, v, rule);
  };
  if (!(loop_distance_m > 0.0)) return bad("loop_distance_m", loop_distance_m, "must be > 0");
  if (loop_min_submap_gap < 1)
    return bad("loop_min_submap_gap", loop_min_submap_gap, "must be >= 1");
  if (!(loop_min_inlier_ratio >= 0.0 && loop_min_inlier_ratio <= 1.0)) {
    return bad("loop_min_inlier_ratio", loop_min_inlier_ratio, "must be in [0, 1]");
  }
  if (!(loop_max_rms_m > 0.0)) return bad("loop_max_rms_m", loop_max_rms_m, "must be > 0");
  if (!(loop_gate_chi2 > 0.0)) return bad("loop_gate_chi2", loop_gate_chi2, "must be > 0");
  if (!(long_outage_s >= 0.0)) return bad("long_outage_s", long_outage_s, "must be >= 0");
  if (!(reckon_sigma_rot_rad > 0.0)) {
    return bad("reckon_sigma_rot_rad", reckon_sigma_rot_rad, "must be > 0");
  }
  if (!(reckon_sigma_trans_m > 0.0)) {
    return bad("reckon_sigma_trans_m", reckon_sigma_trans_m, "must be > 0");
  }
  if (!(reckon_sigma_rot_rad_per_m >= 0.0)) {
    return bad("reckon_sigma_rot_rad_per_m", reckon_sigma_rot_rad_per_m, "must be >= 0");
  }
  if (!(reckon_sigma_trans_per_m >= 0.0)) {
    return bad("reckon_sigma_trans_per_m", reckon_sigma_trans_per_m, "must be >= 0");
  }
  if (!(gnss_sigma_scale > 0.0)) return bad("gnss_sigma_scale", gnss_sigma_scale, "must be > 0");
  if (!(gnss_correlation_s >= 0.0)) {
    return bad("gnss_correlation_s", gnss_correlation_s, "must be >= 0");
  }
  if (!(pos_attitude_correlation_s >= 0.0)) {
    return bad("pos_attitude_correlation_s", pos_attitude_correlation_s, "must be >= 0");
  }
  if (!(attitude_prior_sigma_rad >= 0.0)) {
    return bad("attitude_prior_sigma_rad", attitude_prior_sigma_rad, "must be >= 0");
  }
  for (auto [name, em] :
       {std::pair<const char*, const GnssErrorModel*>{"gnss_bias_rtk_fixed", &gnss_bias_rtk_fixed},
        {"gnss_bias_rtk_float", &gnss_bias_rtk_float},
        {"gnss_bias_code", &gnss_bias_code}}) {
    const std::string f = name;
    if (!(em->correlated_fraction >= 0.0 && em->correlated_fraction < 1.0)) {
      return bad((f + ".correlated_fraction").c_str(), em->correlated_fraction,
                 "must be in [0, 1)");
    }
    if (!(em->correlation_time_s > 0.0) || !std::isfinite(em->correlation_time_s)) {
      return bad((f + ".correlation_time_s").c_str(), em->correlation_time_s, "must be > 0");
    }
  }
  if (!(gnss_bias_node_interval_s > 0.0) || !std::isfinite(gnss_bias_node_interval_s)) {
    return bad("gnss_bias_node_interval_s", gnss_bias_node_interval_s, "must be > 0");
  }
  if (max_iterations < 1) return bad("max_iterations", max_iterations, "must be >= 1");
  return icp.Validate();
}

struct SubmapManager::Impl {
  Options opt;
  std::unique_ptr<SubmapGraph> graph;
  std::unique_ptr<PointIcp> icp;
  Stats stats;
  struct PendingGnss {
    GnssMeasurement m;
    Eigen::Vector3d t_body_antenna;
  };
  std::deque<PendingGnss> pending_gnss;
  std::optional<Timestamp> last_gnss_stamp;  // of the last fix attached
  /// Options::gnss_bias_states: the newest GNSS bias node (its graph key, solution class, the
  /// stamp of its first fix and of the last fix on it) and the next free key.
  struct GnssBiasNode {
    int key = -1;
    int solution_class = -1;
    Timestamp start, last_fix;
  };
  std::optional<GnssBiasNode> gnss_bias_node;
  int next_gnss_bias_key = 0;
  /// The start of the submap that got the last POS attitude prior.
  std::optional<Timestamp> last_attitude_prior_stamp;
  /// The last submap that got the POS attitude, and that attitude
  /// (Options::pos_attitude_cross_covariance).
  struct LastPosAttitude {
    int32_t id = -1;
    Eigen::Matrix3d R_world_submap = Eigen::Matrix3d::Identity();
  };
  std::optional<LastPosAttitude> last_pos_attitude;
  int32_t last_id = -1;

  /// Registers source (frame b) against target (frame a) from T_a_b_init; empty when it fails.
  std::optional<RegistrationResult> Register(const PointCloud& target, const PointCloud& source,
                                             const Eigen::Isometry3d& T_a_b_init) {
    if (target.size() < noise::kMinRegistrationPoints ||
        source.size() < noise::kMinRegistrationPoints) {
      return std::nullopt;
    }
    if (!icp->SetTarget(target.View()).ok()) return std::nullopt;
    auto r = icp->Align(source.View(), T_a_b_init);
    if (!r.ok() || !r->IsUsable()) return std::nullopt;
    return std::move(r).value();
  }

  /// The loop gate (Level2Options::loop_gate_chi2): the squared Mahalanobis distance of the
  /// loop's correction c of the current estimate of T_cand_this, d2 = c^T (S_loop + S_chain)^-1 c,
  /// with S_chain the covariance of the sequential chain (reckon, map-to-map) between the two
  /// submaps: how far the graph's relative pose may have drifted. Empty where the chain has a gap.
  std::optional<double> LoopMahalanobisSq(int32_t cand, int32_t current,
                                          const RegistrationResult& reg, const Vector6d& correction,
                                          const Matrix6d& loop_covariance) const {
    auto chain = graph->CheckLoop(cand, current, reg.T_target_source, loop_covariance);
    if (!chain.ok() || !chain->chain_available) return std::nullopt;
    const Matrix6d S = loop_covariance + chain->chain_covariance;
    return correction.dot(S.ldlt().solve(correction));
  }

  Matrix6d RegistrationCovariance(const RegistrationResult& r) const {
    Matrix6d cov = noise::kMapToMapCovarianceScale * r.covariance;
    cov.diagonal() += internal::DiagonalPoseCovariance(noise::kMapToMapSigmaFloorRotRad,
                                                       noise::kMapToMapSigmaFloorTransM)
                          .diagonal();
    return 0.5 * (cov + cov.transpose());
  }

  /// Options::gnss_bias_states: the bias node a fix of `type` at `stamp` with covariance `*cov`
  /// measures (a new run's first node with the stationary prior, a node following the previous
  /// one, or the current one), -1 for a white class; `*cov` becomes the fix's white part.
  StatusOr<int> GnssBiasNodeFor(Timestamp stamp, GnssFixType type, Eigen::Matrix3d* cov) {
    const int cls = GnssSolutionClass(type);
    const GnssErrorModel& em = cls == 0   ? opt.gnss_bias_rtk_fixed
                               : cls == 1 ? opt.gnss_bias_rtk_float
                                          : opt.gnss_bias_code;
    if (!(em.correlated_fraction > 0.0)) {
      gnss_bias_node.reset();
      return -1;
    }
    const Eigen::Matrix3d stationary = em.correlated_fraction * *cov;
    GnssBiasNode& node = gnss_bias_node.emplace(gnss_bias_node.value_or(GnssBiasNode{}));
    if (node.key < 0 || node.solution_class != cls ||
        stamp.SecondsSince(node.last_fix) > noise::kGnssBiasRunGapS) {
      node.key = next_gnss_bias_key++;
      SLAM_MMS_RETURN_IF_ERROR(graph->AddGnssBias(node.key, stationary));
      node.solution_class = cls;
      node.start = stamp;
    } else if (stamp.SecondsSince(node.start) >= opt.gnss_bias_node_interval_s) {
      const double phi = std::exp(-stamp.SecondsSince(node.start) / em.correlation_time_s);
      const int key = next_gnss_bias_key++;
      SLAM_MMS_RETURN_IF_ERROR(
          graph->AddGnssBiasLink(node.key, key, phi, (1.0 - phi * phi) * stationary));
      node.key = key;
      node.start = stamp;
    }
    node.last_fix = stamp;
    *cov -= stationary;
    return node.key;
  }

  Status AttachGnss(const SubmapRecord& rec, Timestamp next_start) {
    while (!pending_gnss.empty() && pending_gnss.front().m.stamp < next_start) {
      const PendingGnss g = pending_gnss.front();
      pending_gnss.pop_front();
      if (g.m.stamp.SecondsSince(rec.start) < -noise::kGnssBeforeSubmapS) continue;
      Eigen::Matrix3d cov = opt.gnss_sigma_scale * opt.gnss_sigma_scale * g.m.cov_world_antenna;
      int bias = -1;
      if (opt.gnss_bias_states) {
        SLAM_MMS_ASSIGN_OR_RETURN(bias, GnssBiasNodeFor(g.m.stamp, g.m.type, &cov));
      } else {
        cov *= CorrelatedCount(opt.gnss_correlation_s, &last_gnss_stamp, g.m.stamp);
      }
      SLAM_MMS_RETURN_IF_ERROR(graph->AddGnssPrior(
          rec.id, g.m.p_world_antenna, cov, BodyPoseAt(rec, g.m.stamp), g.t_body_antenna, bias));
      ++stats.gnss_factors;
    }
    return OkStatus();
  }

  /// After a solve: the graph's estimates of level 1's submaps (the unfinished current one moved
  /// rigidly with the last finished one).
  StatusOr<std::vector<SubmapPoseUpdate>> Solution(const SubmapSource& loc) const {
    const auto& submaps = loc.submaps();
    std::vector<SubmapPoseUpdate> updates;
    const SubmapRecord* last_in_graph = FindSubmap(loc, last_id);
    for (const SubmapRecord& rec : submaps) {
      if (graph->HasSubmap(rec.id)) {
        SLAM_MMS_ASSIGN_OR_RETURN(Eigen::Isometry3d T, graph->SubmapPose(rec.id));
        updates.push_back({rec.id, T});
      } else if (last_in_graph != nullptr) {
        SLAM_MMS_ASSIGN_OR_RETURN(Eigen::Isometry3d T_last_new, graph->SubmapPose(last_id));
        const Eigen::Isometry3d T_last_rec =
            last_in_graph->T_world_submap.inverse() * rec.T_world_submap;
        updates.push_back({rec.id, T_last_new * T_last_rec});
      }
    }
    return updates;
  }

  StatusOr<std::vector<SubmapPoseUpdate>> Solve(const SubmapSource& loc, SolveTrigger trigger) {
    const auto t0 = std::chrono::steady_clock::now();
    SLAM_MMS_ASSIGN_OR_RETURN(SolveSummary summary, graph->Solve(trigger));
    stats.last_solve_ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ++stats.solves;
    SLAM_MMS_LOG(kInfo) << "level 2: solve (" << SolveTriggerName(trigger) << ") over "
                        << graph->num_submaps()
                        << " submaps: " << SolveTerminationName(summary.termination) << ", "
                        << summary.iterations << " iterations, " << stats.last_solve_ms << " ms";
    if (!summary.usable()) return std::vector<SubmapPoseUpdate>();
    return Solution(loc);
  }
};

SubmapManager::SubmapManager() : impl_(std::make_unique<Impl>()) {}
SubmapManager::~SubmapManager() = default;

StatusOr<std::unique_ptr<SubmapManager>> SubmapManager::Create(const Options& options,
                                                               int num_threads) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (num_threads < 1) {
    return internal::OptionError("SubmapManager::Create", "num_threads", num_threads,
                                 "must be >= 1");
  }
  std::unique_ptr<SubmapManager> mgr(new SubmapManager());
  Impl& m = *mgr->impl_;
  m.opt = options;
  SubmapGraph::Options gopt;
  gopt.max_iterations = options.max_iterations;
  gopt.num_threads = num_threads;
  gopt.loop_candidate_distance_m = options.loop_distance_m;
  gopt.loop_min_submap_gap = options.loop_min_submap_gap;
  SLAM_MMS_ASSIGN_OR_RETURN(SubmapGraph graph, SubmapGraph::Create(gopt));
  m.graph = std::make_unique<SubmapGraph>(std::move(graph));
  PointIcp::Options iopt;
  static_cast<PointIcpOptions&>(iopt) = options.icp;
  iopt.num_threads = num_threads;
  SLAM_MMS_ASSIGN_OR_RETURN(PointIcp icp, PointIcp::Create(iopt));
  m.icp = std::make_unique<PointIcp>(std::move(icp));
  return mgr;
}

void SubmapManager::AddGnssMeasurement(const GnssMeasurement& measurement,
                                       const Eigen::Vector3d& t_body_antenna) {
  if (!impl_->opt.use_gnss) return;
  impl_->pending_gnss.push_back({measurement, t_body_antenna});
}

StatusOr<std::vector<SubmapPoseUpdate>> SubmapManager::OnSubmapFinished(
    const SubmapSource& submaps, int32_t submap_id, bool gnss_returned_after_outage,
    const std::optional<PosAttitude>& pos_attitude) {
  Impl& m = *impl_;
  const SubmapRecord* rec = FindSubmap(submaps, submap_id);
  if (rec == nullptr) {
    return NotFoundError("SubmapManager: level 1 has no submap " + std::to_string(submap_id));
  }
  // Nodes: the submap and its scan poses (level 1 is done with them).
  SLAM_MMS_RETURN_IF_ERROR(m.graph->AddSubmap(submap_id, rec->T_world_submap));
  for (size_t j = 0; j < rec->scan_indices.size(); ++j) {
    SLAM_MMS_RETURN_IF_ERROR(m.graph->AddScan(submap_id, rec->scan_indices[j], rec->scan_stamps[j],
                                              rec->T_submap_scan[j]));
  }
  if (m.opt.use_gnss && m.opt.attitude_prior_sigma_rad > 0.0) {
    // Without the POS: roll and pitch from level 1 (observed from gravity by the IMU), loosely;
    // yaw free. GNSS positions cannot observe a rotation about the direction of travel.
    const double s_rp = m.opt.attitude_prior_sigma_rad;
    Matrix6d cov = Matrix6d::Zero();
    cov.diagonal() << s_rp * s_rp, s_rp * s_rp, noise::kFreeYawVariance,
        noise::kFreePositionVariance, noise::kFreePositionVariance, noise::kFreePositionVariance;
    Eigen::Isometry3d T_prior = rec->T_world_submap;
    bool chained_pos_attitude = false;
    if (pos_attitude && pos_attitude->cov_rotation.allFinite() &&
        pos_attitude->R_world_submap.allFinite()) {
      // The POS's attitude with its own covariance, yaw included (plus (1e-5 rad)^2: never
      // exact). Its yaw matters where the positions cannot hold it: the GNSS positions of a
      // vehicle standing still hold no yaw, so a free yaw followed the GNSS noise (it turned
      // whole standing drives of the sweep by 2-13 deg while level 1 held 0.2 deg).
      T_prior.linear() = pos_attitude->R_world_submap;
      const Eigen::Matrix3d c =
          0.5 * (pos_attitude->cov_rotation + pos_attitude->cov_rotation.transpose());
      // Options::pos_attitude_correlation_s: the priors within the window count as one.
      const double correlated = CorrelatedCount(m.opt.pos_attitude_correlation_s,
                                                &m.last_attitude_prior_stamp, rec->start);
      cov.topLeftCorner<3, 3>() = correlated * c + 1e-10 * Eigen::Matrix3d::Identity();
      const std::optional<Impl::LastPosAttitude> last = m.last_pos_attitude;
      m.last_pos_attitude = Impl::LastPosAttitude{submap_id, pos_attitude->R_world_submap};
      const auto& link = pos_attitude->link;
      if (m.opt.pos_attitude_cross_covariance && link && last &&
          link->previous_submap == last->id && m.graph->HasSubmap(last->id)) {
        // Options::pos_attitude_cross_covariance: the POS's own conditional given the last one.
        const Eigen::Vector3d sd = link->chain.covariance.diagonal().cwiseSqrt() * kRadToDeg;
        SLAM_MMS_LOG(kDebug) << "level 2: submap " << submap_id << " POS attitude chained to "
                             << last->id << ", innovation " << sd.x() << " / " << sd.y() << " / "
                             << sd.z() << " deg (world axes), transition diagonal "
                             << link->chain.transition.diagonal().transpose();
        SLAM_MMS_RETURN_IF_ERROR(m.graph->AddAttitudeChainFactor(
            last->id, submap_id, last->R_world_submap, pos_attitude->R_world_submap, link->chain));
        chained_pos_attitude = true;
      } else {
        SLAM_MMS_LOG(kDebug) << "level 2: submap " << submap_id << " attitude prior from the POS, "
                             << RotationSigmasDeg(cov);
      }
    }
    if (!chained_pos_attitude) {
      SLAM_MMS_RETURN_IF_ERROR(m.graph->AddPosePrior(submap_id, T_prior, cov));
    }
  }
  const SubmapRecord* prev = m.last_id >= 0 ? FindSubmap(submaps, m.last_id) : nullptr;
  if (prev != nullptr) {
    // F_Reckon (eq 21): the serial chain from level 1.
    const double d = rec->T_prev_this.translation().norm();
    SLAM_MMS_RETURN_IF_ERROR(m.graph->AddReckonFactor(
        m.last_id, submap_id, rec->T_prev_this,
        m.opt.reckon_from_level1
            ? rec->cov_prev_this
            : internal::DiagonalPoseCovariance(
                  std::hypot(m.opt.reckon_sigma_rot_rad, m.opt.reckon_sigma_rot_rad_per_m * d),
                  std::hypot(m.opt.reckon_sigma_trans_m, m.opt.reckon_sigma_trans_per_m * d))));
    // F_Reg (§5.2.1): map-to-map registration with the previous submap (point-based ICP).
    if (m.opt.use_map_to_map) {
      auto prev_cloud = submaps.SubmapCloud(prev->id, SubmapSource::CloudKind::kRegistration);
      if (!prev_cloud.ok()) {
        SLAM_MMS_LOG(kWarning) << "level 2: map-to-map registration " << prev->id << " -> "
                               << submap_id << " skipped: " << prev_cloud.status().ToString();
      }
      auto reg = prev_cloud.ok()
                     ? m.Register(*prev_cloud, rec->registration_cloud, rec->T_prev_this)
                     : std::nullopt;
      if (reg && reg->inlier_ratio >= noise::kMapToMapMinInlierRatio) {
        const Vector6d correction = se3::Log(rec->T_prev_this.inverse() * reg->T_target_source);
        const bool accepted = correction.head<3>().norm() < noise::kMapToMapMaxCorrectionRotRad &&
                              correction.tail<3>().norm() < noise::kMapToMapMaxCorrectionTransM;
        const Matrix6d cov = m.RegistrationCovariance(*reg);
        SLAM_MMS_LOG(kDebug) << "level 2: map-to-map " << prev->id << " -> " << submap_id
                             << ": inliers " << reg->inlier_ratio << ", correction "
                             << correction.head<3>().norm() * kRadToDeg << " deg "
                             << correction.tail<3>().norm() << " m, sigma "
                             << RotationSigmasDeg(cov) << " -> "
                             << (accepted ? "accepted" : "rejected");
        if (accepted) {
          SLAM_MMS_RETURN_IF_ERROR(
              m.graph->AddRegistrationFactor(m.last_id, submap_id, reg->T_target_source, cov));
          ++m.stats.map_to_map_accepted;
        }
      }
    }
  }
  // F_GNSS (eq 24): the fixes the POS used while this submap was mapped.
  const auto& all = submaps.submaps();
  Timestamp next_start = rec->end.PlusSeconds(noise::kGnssAfterLastScanS);
  for (size_t i = 0; i + 1 < all.size(); ++i) {
    if (all[i].id == submap_id) next_start = all[i + 1].start;
  }
  if (m.opt.use_gnss) SLAM_MMS_RETURN_IF_ERROR(m.AttachGnss(*rec, next_start));
  m.last_id = submap_id;

  // F_Loop (eqs 22-23): candidates within D_thr, not recent; verified by registration.
  bool loop = false;
  if (m.opt.use_loops) {
    const Eigen::Vector3d center = rec->T_world_submap * rec->T_submap_scan.back().translation();
    for (const LoopCandidate& c : m.graph->LoopCandidates(center, submap_id)) {
      const SubmapRecord* cand = FindSubmap(submaps, static_cast<int32_t>(c.submap));
      if (cand == nullptr) continue;
      ++m.stats.loops_tested;
      const Eigen::Isometry3d T_init = cand->T_world_submap.inverse() * rec->T_world_submap;
      auto cand_cloud = submaps.SubmapCloud(cand->id, SubmapSource::CloudKind::kRegistration);
      if (!cand_cloud.ok()) {
        SLAM_MMS_LOG(kWarning) << "level 2: loop candidate " << cand->id
                               << " skipped: " << cand_cloud.status().ToString();
        continue;
      }
      auto reg = m.Register(*cand_cloud, rec->registration_cloud, T_init);
      if (!reg) continue;
      const Vector6d correction = se3::Log(T_init.inverse() * reg->T_target_source);
      const Matrix6d loop_covariance = m.RegistrationCovariance(*reg);
      const std::optional<double> d2 =
          m.LoopMahalanobisSq(cand->id, submap_id, *reg, correction, loop_covariance);
      const bool verified = reg->inlier_ratio >= m.opt.loop_min_inlier_ratio &&
                            reg->rms_residual_m <= m.opt.loop_max_rms_m &&
                            (!d2 || *d2 < m.opt.loop_gate_chi2);
      SLAM_MMS_LOG(kDebug) << "level 2: loop " << cand->id << " <-> " << submap_id << ": inliers "
                           << reg->inlier_ratio << ", rms " << reg->rms_residual_m
                           << ", correction " << correction.tail<3>().norm() << " m "
                           << correction.head<3>().norm() << " rad, d2 "
                           << (d2 ? std::to_string(*d2) : std::string("- (no chain)")) << " -> "
                           << (verified ? "accepted" : "rejected");
      if (!verified) continue;
      SLAM_MMS_RETURN_IF_ERROR(
          m.graph->AddLoopFactor(cand->id, submap_id, reg->T_target_source, loop_covariance)
              .status());
      ++m.stats.loops_accepted;
      loop = true;
      break;  // the most compatible (nearest verified) candidate
    }
  }
  if (loop) return m.Solve(submaps, SolveTrigger::kLoopClosed);
  if (gnss_returned_after_outage) return m.Solve(submaps, SolveTrigger::kGnssReturned);
  return std::vector<SubmapPoseUpdate>();
}

StatusOr<std::vector<SubmapPoseUpdate>> SubmapManager::Finish(const SubmapSource& submaps) {
  Impl& m = *impl_;
  if (m.graph->num_submaps() == 0) return std::vector<SubmapPoseUpdate>();
  return m.Solve(submaps, SolveTrigger::kFinish);
}

const SubmapManager::Stats& SubmapManager::stats() const { return impl_->stats; }

const SubmapGraph& SubmapManager::graph() const { return *impl_->graph; }

}  // namespace slam_mms
