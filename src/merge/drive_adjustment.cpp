#include "slam_mms/merge/drive_adjustment.hpp"

#include <GeographicLib/Geocentric.hpp>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>

#include "core/option_error.hpp"
#include "merge/merge_graph.hpp"
#include "registration/point_icp.hpp"
#include "slam_mms/core/geodesy.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {
namespace {

using merge_internal::BuildGraph;
using merge_internal::EstimateVarianceComponents;
using merge_internal::FactorOrigin;
using merge_internal::GraphId;

constexpr size_t kMinRegistrationPoints = 100;

// T_world0_worldi: the exact rigid transform between two local ENU frames (through ECEF).
Eigen::Isometry3d EnuToEnu(const GeodeticPoint& from, const GeodeticPoint& to) {
  const GeographicLib::Geocentric& earth = GeographicLib::Geocentric::WGS84();
  Eigen::Vector3d ecef_from, ecef_to;
  earth.Forward(from.latitude_deg, from.longitude_deg, from.height_m, ecef_from.x(), ecef_from.y(),
                ecef_from.z());
  earth.Forward(to.latitude_deg, to.longitude_deg, to.height_m, ecef_to.x(), ecef_to.y(),
                ecef_to.z());
  const Eigen::Matrix3d R_ecef_from = R_ecef_enu(from.latitude_deg, from.longitude_deg);
  const Eigen::Matrix3d R_ecef_to = R_ecef_enu(to.latitude_deg, to.longitude_deg);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R_ecef_to.transpose() * R_ecef_from;
  T.translation() = R_ecef_to.transpose() * (ecef_from - ecef_to);
  return T;
}

// Moves a drive into the world whose frame is T_new_old applied from the left.
void MoveDrive(const Eigen::Isometry3d& T_new_old, DriveResult* d) {
  for (DriveSubmap& s : d->submaps) {
    s.T_world_submap = T_new_old * s.T_world_submap;
    for (SubmapScanPose& p : s.scans) p.T_world_scan = s.T_world_submap * p.T_submap_scan;
  }
  const Eigen::Matrix3d R = T_new_old.linear();
  for (SubmapGraphFactor& f : d->factors) {
    if (f.kind == SubmapFactorKind::kPosePrior) {
      f.T = T_new_old * f.T;  // right-perturbation covariance: unchanged
    } else if (f.kind == SubmapFactorKind::kAttitudeChain) {
      // The chain is in world axes: eps' = R eps, so A' = R A R^T, Q' = R Q R^T.
      f.T = T_new_old * f.T;
      f.T_a = T_new_old * f.T_a;
      f.transition = R * f.transition * R.transpose();
      const Eigen::Matrix3d q = f.covariance.topLeftCorner<3, 3>();
      f.covariance.topLeftCorner<3, 3>() = R * q * R.transpose();
    } else if (f.kind == SubmapFactorKind::kGnss) {
      f.p_world_antenna = T_new_old * f.p_world_antenna;
      const Eigen::Matrix3d c = f.covariance.topLeftCorner<3, 3>();
      f.covariance.topLeftCorner<3, 3>() = R * c * R.transpose();
    } else if (f.kind == SubmapFactorKind::kGnssBias || f.kind == SubmapFactorKind::kGnssBiasLink) {
      // A world offset: b' = R b (the transition is a multiple of I).
      const Eigen::Matrix3d c = f.covariance.topLeftCorner<3, 3>();
      f.covariance.topLeftCorner<3, 3>() = R * c * R.transpose();
    }
  }
}

// The submap `id` of `subs` (id order; the id is known to be there).
std::vector<DriveSubmap>::const_iterator FindSubmap(const std::vector<DriveSubmap>& subs,
                                                    SubmapId id) {
  return std::lower_bound(subs.begin(), subs.end(), id,
                          [](const DriveSubmap& s, SubmapId v) { return s.id < v; });
}

// T_a_b of an overlap's two submaps under the graph's current estimate.
StatusOr<Eigen::Isometry3d> GraphRelativePose(const SubmapGraph& graph,
                                              const DriveAdjustment::Overlap& ov) {
  SLAM_MMS_ASSIGN_OR_RETURN(Eigen::Isometry3d T_world_a,
                            graph.SubmapPose(GraphId(ov.drive_a, ov.submap_a)));
  SLAM_MMS_ASSIGN_OR_RETURN(Eigen::Isometry3d T_world_b,
                            graph.SubmapPose(GraphId(ov.drive_b, ov.submap_b)));
  return T_world_a.inverse() * T_world_b;
}

Eigen::Vector3d MiddlePosition(const DriveSubmap& s) {
  return s.scans.empty() ? s.T_world_submap.translation()
                         : s.scans[s.scans.size() / 2].T_world_scan.translation();
}

struct CellKey {
  int64_t x, y;
  bool operator==(const CellKey& o) const { return x == o.x && y == o.y; }
};
struct CellHash {
  size_t operator()(const CellKey& k) const {
    return std::hash<int64_t>()(k.x * 73856093LL ^ k.y * 19349663LL);
  }
};

Matrix6d RegistrationCovariance(const RegistrationResult& r, const DriveAdjustment::Options& o) {
  Matrix6d cov = o.registration_covariance_scale * r.covariance;
  const double fr = o.registration_sigma_floor_rad * o.registration_sigma_floor_rad;
  const double ft = o.registration_sigma_floor_m * o.registration_sigma_floor_m;
  cov.diagonal() += (Vector6d() << fr, fr, fr, ft, ft, ft).finished();
  return 0.5 * (cov + cov.transpose());
}

// Translation and rotation of `measured` against `predicted` (T_a_b both).
std::pair<double, double> Offset(const Eigen::Isometry3d& predicted,
                                 const Eigen::Isometry3d& measured) {
  const Eigen::Isometry3d d = predicted.inverse() * measured;
  return {d.translation().norm(), Eigen::AngleAxisd(d.linear()).angle()};
}

struct Verifier {
  const DriveAdjustment::Options& o;
  PointIcp coarse;
  PointIcp fine;
  PointIcp self;  // a drive's own neighbouring submaps (the residual it fits itself with)

  // The point-to-plane RMS of `s` registered against its neighbour `n` in its own drive, from
  // their relative pose (fine pass only); empty where that fails.
  std::optional<double> SelfRms(const DriveSubmap& n, const DriveSubmap& s) {
    if (n.registration_cloud.size() < kMinRegistrationPoints ||
        s.registration_cloud.size() < kMinRegistrationPoints ||
        !self.SetTarget(n.registration_cloud.View()).ok()) {
      return std::nullopt;
    }
    auto r = self.Align(s.registration_cloud.View(), n.T_world_submap.inverse() * s.T_world_submap);
    if (!r.ok() || !r->IsUsable() || r->inlier_ratio < o.min_inlier_ratio) return std::nullopt;
    return r->rms_residual_m;
  }

  // Registers b's cloud against a's (set as the target of both ICPs) from each hypothesis.
  // `self_rms`: SelfRms of b (empty: not known).
  void Verify(const DriveSubmap& a, const DriveSubmap& b, std::optional<double> self_rms,
              DriveAdjustment::Overlap* ov) {
    const Eigen::Isometry3d T_init = a.T_world_submap.inverse() * b.T_world_submap;
    // The prior, and a 3x3 grid of world x/y shifts around it per offset.
    std::vector<Eigen::Vector3d> shifts = {Eigen::Vector3d::Zero()};
    for (double s : o.hypothesis_offsets_m) {
      for (int ix = -1; ix <= 1; ++ix) {
        for (int iy = -1; iy <= 1; ++iy) {
          if (ix != 0 || iy != 0) shifts.emplace_back(ix * s, iy * s, 0.0);
        }
      }
    }
    std::vector<RegistrationResult> hyps;
    const Eigen::Matrix3d R_a_world = a.T_world_submap.linear().transpose();
    for (const Eigen::Vector3d& shift : shifts) {
      Eigen::Isometry3d T0 = T_init;
      T0.translation() += R_a_world * shift;  // a world-x/y shift, in a's frame
      auto rc = coarse.Align(b.registration_cloud.View(), T0);
      if (!rc.ok() || !rc->IsUsable()) continue;
      auto rf = fine.Align(b.registration_cloud.View(), rc->T_target_source);
      if (!rf.ok() || !rf->IsUsable()) continue;
      hyps.push_back(std::move(rf).value());
    }
    ov->hypotheses_converged = static_cast<int>(hyps.size());
    if (hyps.empty()) {
      ov->verdict = "registration failed from every hypothesis";
      return;
    }
    // The best: the lowest point-to-plane residual among the hypotheses with enough inliers.
    auto by_rms = [](const RegistrationResult& x, const RegistrationResult& y) {
      if (x.rms_residual_m != y.rms_residual_m) return x.rms_residual_m < y.rms_residual_m;
      return x.inlier_ratio > y.inlier_ratio;
    };
    std::sort(hyps.begin(), hyps.end(), by_rms);
    auto first_ok = std::find_if(hyps.begin(), hyps.end(), [&](const RegistrationResult& h) {
      return h.inlier_ratio >= o.min_inlier_ratio;
    });
    if (first_ok == hyps.end()) {
      double most = 0.0;
      for (const RegistrationResult& h : hyps) most = std::max(most, h.inlier_ratio);
      ov->inlier_ratio = most;
      ov->verdict = "too few inliers (" + std::to_string(most) + ")";
      return;
    }
    const RegistrationResult best = *first_ok;
    ov->inlier_ratio = best.inlier_ratio;
    ov->rms_m = best.rms_residual_m;
    if (best.rms_residual_m > o.max_rms_m) {
      ov->verdict = "residual too large (" + std::to_string(best.rms_residual_m) + " m)";
      return;
    }
    ov->self_rms_m = self_rms.value_or(0.0);
    if (self_rms && best.rms_residual_m > o.max_rms_ratio_to_self * *self_rms) {
      ov->verdict = "residual " + std::to_string(best.rms_residual_m) + " m is more than " +
                    std::to_string(o.max_rms_ratio_to_self) + " x the drive's own (" +
                    std::to_string(*self_rms) + " m)";
      return;
    }
    // Ambiguous: another pose fits about as well (as many inliers, a residual not clearly worse).
    for (const RegistrationResult& h : hyps) {
      const auto [dt, dr] = Offset(best.T_target_source, h.T_target_source);
      if (dt <= o.hypothesis_agreement_m && dr <= o.hypothesis_agreement_rad) continue;
      if (h.inlier_ratio >= o.ambiguity_ratio * best.inlier_ratio &&
          h.rms_residual_m * o.ambiguity_ratio <= best.rms_residual_m) {
        ov->verdict = "ambiguous (a pose " + std::to_string(dt) + " m away fits as well: inliers " +
                      std::to_string(h.inlier_ratio) + ", rms " + std::to_string(h.rms_residual_m) +
                      " m)";
        return;
      }
    }
    ov->verified = true;
    ov->verdict = "verified";
    ov->T_a_b = best.T_target_source;
    ov->covariance = RegistrationCovariance(best, o);
  }
};

Status Positive(const char* field, double v) {
  if (v > 0.0) return OkStatus();
  return internal::OptionError("DriveAdjustment::Options", field, v, "must be > 0");
}

}  // namespace

Status DriveAdjustment::Options::Validate() const {
  SLAM_MMS_RETURN_IF_ERROR(Positive("overlap_distance_m", overlap_distance_m));
  SLAM_MMS_RETURN_IF_ERROR(Positive("max_pairs_per_submap", max_pairs_per_submap));
  for (double s : hypothesis_offsets_m) {
    SLAM_MMS_RETURN_IF_ERROR(Positive("hypothesis_offsets_m", s));
  }
  SLAM_MMS_RETURN_IF_ERROR(Positive("coarse_correspondence_m", coarse_correspondence_m));
  SLAM_MMS_RETURN_IF_ERROR(Positive("fine_correspondence_m", fine_correspondence_m));
  if (!(min_inlier_ratio > 0.0 && min_inlier_ratio <= 1.0)) {
    return internal::OptionError("DriveAdjustment::Options", "min_inlier_ratio", min_inlier_ratio,
                                 "must be in (0, 1]");
  }
  SLAM_MMS_RETURN_IF_ERROR(Positive("max_rms_m", max_rms_m));
  SLAM_MMS_RETURN_IF_ERROR(Positive("hypothesis_agreement_m", hypothesis_agreement_m));
  SLAM_MMS_RETURN_IF_ERROR(Positive("hypothesis_agreement_rad", hypothesis_agreement_rad));
  SLAM_MMS_RETURN_IF_ERROR(Positive("ambiguity_ratio", ambiguity_ratio));
  SLAM_MMS_RETURN_IF_ERROR(Positive("consistency_gate_chi2", consistency_gate_chi2));
  if (max_rejection_rounds < 0) {
    return internal::OptionError("DriveAdjustment::Options", "max_rejection_rounds",
                                 max_rejection_rounds, "must be >= 0");
  }
  SLAM_MMS_RETURN_IF_ERROR(
      Positive("registration_covariance_scale", registration_covariance_scale));
  SLAM_MMS_RETURN_IF_ERROR(Positive("registration_sigma_floor_rad", registration_sigma_floor_rad));
  SLAM_MMS_RETURN_IF_ERROR(Positive("registration_sigma_floor_m", registration_sigma_floor_m));
  SLAM_MMS_RETURN_IF_ERROR(Positive("max_rms_ratio_to_self", max_rms_ratio_to_self));
  if (!(gnss_bias_sigma_m >= 0.0)) {
    return internal::OptionError("DriveAdjustment::Options", "gnss_bias_sigma_m", gnss_bias_sigma_m,
                                 "must be >= 0");
  }
  if (variance_component_rounds < 0) {
    return internal::OptionError("DriveAdjustment::Options", "variance_component_rounds",
                                 variance_component_rounds, "must be >= 0");
  }
  SLAM_MMS_RETURN_IF_ERROR(
      Positive("variance_component_min_redundancy", variance_component_min_redundancy));
  if (!(variance_factor_min > 0.0 && variance_factor_min <= 1.0)) {
    return internal::OptionError("DriveAdjustment::Options", "variance_factor_min",
                                 variance_factor_min, "must be in (0, 1]");
  }
  if (!(variance_factor_max >= 1.0)) {
    return internal::OptionError("DriveAdjustment::Options", "variance_factor_max",
                                 variance_factor_max, "must be >= 1");
  }
  if (num_threads < 1 || num_threads > 64) {
    return internal::OptionError("DriveAdjustment::Options", "num_threads", num_threads,
                                 "must be in [1, 64]");
  }
  SLAM_MMS_RETURN_IF_ERROR(
      overlap_loss.Validate().WithContext("DriveAdjustment::Options::overlap_loss"));
  SLAM_MMS_RETURN_IF_ERROR(graph.Validate());
  return icp.Validate();
}

int DriveAdjustment::Result::num_accepted() const {
  return static_cast<int>(
      std::count_if(overlaps.begin(), overlaps.end(), [](const Overlap& o) { return o.accepted; }));
}

StatusOr<DriveAdjustment::Result> DriveAdjustment::Run(std::vector<Drive> drives,
                                                       const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (drives.empty()) return InvalidArgumentError("DriveAdjustment::Run: no drives");
  for (const Drive& d : drives) {
    if (d.result.submaps.empty()) {
      return InvalidArgumentError("DriveAdjustment::Run: drive '" + d.name + "' has no submaps");
    }
    // A datum bias would have to be added to every node of a run of the drive's own GNSS bias
    // nodes (a Gauss-Markov link decays whatever its first node starts from), which one GNSS
    // factor's single bias cannot express: the two are not combined.
    if (options.gnss_bias_sigma_m > 0.0 &&
        std::any_of(
            d.result.factors.begin(), d.result.factors.end(),
            [](const SubmapGraphFactor& f) { return f.kind == SubmapFactorKind::kGnssBias; })) {
      return InvalidArgumentError("DriveAdjustment::Run: drive '" + d.name +
                                  "' carries its own GNSS bias nodes (level2.gnss_bias_states), "
                                  "which gnss_bias_sigma_m cannot be combined with");
    }
  }
  Result out;
  out.origin = drives.front().result.origin;
  for (size_t d = 1; d < drives.size(); ++d) {
    MoveDrive(EnuToEnu(drives[d].result.origin, out.origin), &drives[d].result);
    drives[d].result.origin = out.origin;
  }
  for (const Drive& d : drives) {
    std::vector<Eigen::Isometry3d> poses;
    for (const DriveSubmap& s : d.result.submaps) poses.push_back(s.T_world_submap);
    out.T_world_submap_input.push_back(std::move(poses));
  }

  // Overlap candidates: a hash of every scan position, cells of overlap_distance_m.
  const double cell = options.overlap_distance_m;
  std::unordered_map<CellKey, std::vector<std::tuple<size_t, size_t, Eigen::Vector3d>>, CellHash>
      grid;
  for (size_t d = 0; d < drives.size(); ++d) {
    const auto& subs = drives[d].result.submaps;
    for (size_t k = 0; k < subs.size(); ++k) {
      for (const SubmapScanPose& p : subs[k].scans) {
        const Eigen::Vector3d x = p.T_world_scan.translation();
        grid[{static_cast<int64_t>(std::floor(x.x() / cell)),
              static_cast<int64_t>(std::floor(x.y() / cell))}]
            .emplace_back(d, k, x);
      }
    }
  }
  std::set<std::tuple<size_t, size_t, size_t, size_t>> seen;
  for (size_t db = 0; db < drives.size(); ++db) {
    const auto& subs_b = drives[db].result.submaps;
    for (size_t kb = 0; kb < subs_b.size(); ++kb) {
      const Eigen::Vector3d c = MiddlePosition(subs_b[kb]);
      const int64_t cx = static_cast<int64_t>(std::floor(c.x() / cell));
      const int64_t cy = static_cast<int64_t>(std::floor(c.y() / cell));
      std::map<std::pair<size_t, size_t>, double> nearest;  // (drive, submap) -> distance
      for (int64_t ix = cx - 1; ix <= cx + 1; ++ix) {
        for (int64_t iy = cy - 1; iy <= cy + 1; ++iy) {
          auto it = grid.find({ix, iy});
          if (it == grid.end()) continue;
          for (const auto& [da, ka, x] : it->second) {
            if (da == db) continue;
            const double dist = (x - c).norm();
            if (dist > options.overlap_distance_m) continue;
            auto [pos, inserted] = nearest.emplace(std::make_pair(da, ka), dist);
            if (!inserted) pos->second = std::min(pos->second, dist);
          }
        }
      }
      std::map<size_t, std::vector<std::pair<double, size_t>>> per_drive;
      for (const auto& [key, dist] : nearest) per_drive[key.first].emplace_back(dist, key.second);
      for (auto& [da, list] : per_drive) {
        std::sort(list.begin(), list.end());
        for (size_t i = 0; i < list.size() && i < static_cast<size_t>(options.max_pairs_per_submap);
             ++i) {
          // One test per unordered pair, drive_a < drive_b.
          const size_t ka = list[i].second;
          const auto key =
              da < db ? std::make_tuple(da, ka, db, kb) : std::make_tuple(db, kb, da, ka);
          if (!seen.insert(key).second) continue;
          Overlap ov;
          ov.drive_a = std::get<0>(key);
          ov.submap_a = drives[ov.drive_a].result.submaps[std::get<1>(key)].id;
          ov.drive_b = std::get<2>(key);
          ov.submap_b = drives[ov.drive_b].result.submaps[std::get<3>(key)].id;
          ov.distance_m = list[i].first;
          out.overlaps.push_back(ov);
        }
      }
    }
  }
  std::sort(out.overlaps.begin(), out.overlaps.end(), [](const Overlap& x, const Overlap& y) {
    return std::tie(x.drive_a, x.submap_a, x.drive_b, x.submap_b) <
           std::tie(y.drive_a, y.submap_a, y.drive_b, y.submap_b);
  });

  // Verification: one target (submap a) at a time.
  auto find = [&](size_t d, SubmapId id) -> const DriveSubmap& {
    return *FindSubmap(drives[d].result.submaps, id);
  };
  PointIcp::Options coarse_opt;
  static_cast<PointIcpOptions&>(coarse_opt) = options.icp;
  coarse_opt.max_correspondence_distance = options.coarse_correspondence_m;
  coarse_opt.num_threads = options.num_threads;
  PointIcp::Options fine_opt = coarse_opt;
  fine_opt.max_correspondence_distance = options.fine_correspondence_m;
  SLAM_MMS_ASSIGN_OR_RETURN(PointIcp coarse, PointIcp::Create(coarse_opt));
  SLAM_MMS_ASSIGN_OR_RETURN(PointIcp fine, PointIcp::Create(fine_opt));
  SLAM_MMS_ASSIGN_OR_RETURN(PointIcp self, PointIcp::Create(fine_opt));
  Verifier verifier{options, std::move(coarse), std::move(fine), std::move(self)};
  std::map<std::pair<size_t, SubmapId>, std::optional<double>> self_rms;
  for (const Overlap& ov : out.overlaps) {
    const auto key = std::make_pair(ov.drive_b, ov.submap_b);
    if (self_rms.count(key) != 0) continue;
    const auto& subs = drives[ov.drive_b].result.submaps;
    const auto it = FindSubmap(subs, ov.submap_b);
    std::optional<double> rms;
    if (subs.size() >= 2) {
      const auto n = it == subs.begin() ? std::next(it) : std::prev(it);
      rms = verifier.SelfRms(*n, *it);
    }
    self_rms[key] = rms;
  }
  std::pair<size_t, SubmapId> current_target{std::numeric_limits<size_t>::max(), 0};
  bool target_ok = false;
  for (Overlap& ov : out.overlaps) {
    const DriveSubmap& a = find(ov.drive_a, ov.submap_a);
    const DriveSubmap& b = find(ov.drive_b, ov.submap_b);
    if (current_target != std::make_pair(ov.drive_a, ov.submap_a)) {
      current_target = {ov.drive_a, ov.submap_a};
      target_ok = a.registration_cloud.size() >= kMinRegistrationPoints &&
                  verifier.coarse.SetTarget(a.registration_cloud.View()).ok() &&
                  verifier.fine.SetTarget(a.registration_cloud.View()).ok();
    }
    if (!target_ok || b.registration_cloud.size() < kMinRegistrationPoints) {
      ov.verdict = "too few points to register";
      continue;
    }
    verifier.Verify(a, b, self_rms[std::make_pair(ov.drive_b, ov.submap_b)], &ov);
    ov.accepted = ov.verified;
    const Eigen::Isometry3d T_prior = a.T_world_submap.inverse() * b.T_world_submap;
    if (ov.verified)
      std::tie(ov.offset_before_m, ov.rotation_before_rad) = Offset(T_prior, ov.T_a_b);
  }

  // Solve; reject what contradicts the rest; solve again.
  std::optional<SubmapGraph> graph;
  std::vector<FactorOrigin> origins;  // of the graph's factors
  for (int round = 0;; ++round) {
    origins.clear();
    SLAM_MMS_ASSIGN_OR_RETURN(SubmapGraph g,
                              BuildGraph(drives, out.overlaps, options, nullptr, &origins));
    SLAM_MMS_ASSIGN_OR_RETURN(out.summary, g.Solve(SolveTrigger::kFinish));
    graph.emplace(std::move(g));
    out.rejection_rounds = round;
    if (round >= options.max_rejection_rounds) break;
    bool rejected = false;
    for (Overlap& ov : out.overlaps) {
      if (!ov.accepted) continue;
      SLAM_MMS_ASSIGN_OR_RETURN(const Eigen::Isometry3d T_a_b, GraphRelativePose(*graph, ov));
      const Vector6d e = se3::Log(T_a_b.inverse() * ov.T_a_b);
      const double d2 = e.dot(ov.covariance.ldlt().solve(e));
      if (d2 > options.consistency_gate_chi2) {
        ov.accepted = false;
        ov.verdict = "inconsistent with the graph (chi2 " + std::to_string(d2) + ")";
        rejected = true;
      }
    }
    if (!rejected) break;
  }

  // Variance component estimation.
  if (options.variance_component_rounds > 0) {
    SLAM_MMS_RETURN_IF_ERROR(
        EstimateVarianceComponents(drives, out.overlaps, options, &*graph, origins, &out));
  }

  // The adjusted drives.
  out.drives = std::move(drives);
  for (size_t d = 0; d < out.drives.size(); ++d) {
    for (DriveSubmap& s : out.drives[d].result.submaps) {
      SLAM_MMS_ASSIGN_OR_RETURN(s.T_world_submap, graph->SubmapPose(GraphId(d, s.id)));
      for (SubmapScanPose& p : s.scans) p.T_world_scan = s.T_world_submap * p.T_submap_scan;
    }
    auto bias = graph->GnssBias(static_cast<int>(d));
    out.gnss_bias_m.push_back(bias.ok() ? *bias : Eigen::Vector3d::Zero());
  }
  for (Overlap& ov : out.overlaps) {
    if (!ov.verified) continue;
    SLAM_MMS_ASSIGN_OR_RETURN(const Eigen::Isometry3d T_a_b, GraphRelativePose(*graph, ov));
    std::tie(ov.offset_after_m, ov.rotation_after_rad) = Offset(T_a_b, ov.T_a_b);
    if (ov.accepted) ov.verdict = "accepted";
  }
  SLAM_MMS_LOG(kInfo) << "DriveAdjustment: " << out.drives.size() << " drives, "
                      << out.overlaps.size() << " overlaps tested, " << out.num_accepted()
                      << " accepted, " << out.rejection_rounds << " rejection rounds";
  return out;
}

}  // namespace slam_mms
