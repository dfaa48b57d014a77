// Per scan, in MappingSystem (Impl): the motion input level 1 gets from the POS (F_Odom, or
// F_Prein where the POS jumped or GNSS is out), the POS-only mapper of gnss_ins mode, the outage
// state, and each finished submap to level 2 with its estimates applied back (one way).
#include <algorithm>
#include <cmath>
#include <string>

#include "pipeline/mapping_system_impl.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/ins/imu_preintegration.hpp"

namespace slam_mms {

Status MappingSystem::Impl::ProcessQueued() {
  std::deque<Scan>& queue = input.scans();
  while (!queue.empty() && Ready(queue.front())) {
    Scan scan = std::move(queue.front());
    queue.pop_front();
    SLAM_MMS_RETURN_IF_ERROR(ProcessScan(scan));
  }
  input.TrimImuHistory(last_scan_start);
  ForgetOldPosStates();
  return OkStatus();
}

void MappingSystem::Impl::ForgetOldPosStates() {
  if (!have_scan) return;
  // The POS is asked for the queued scans (after the last processed one), for the scans of the
  // submaps not yet reported to level 2 (their POS attitudes), and, with an external POS, for
  // GNSS fixes as they come (a late one may be older than the scans: kPosStatesKeptS).
  Timestamp oldest = last_scan_start;
  if (loc) {
    const auto& submaps = loc->submaps();
    if (submaps_reported < submaps.size() && submaps[submaps_reported].start < oldest) {
      oldest = submaps[submaps_reported].start;
    }
  }
  ins.ForgetStatesBefore(oldest.PlusSeconds(-kPosStatesKeptS));
}

Status MappingSystem::Impl::ProcessScan(const Scan& scan) {
  auto [s0, s1] = PosOverScan(scan);
  LocalizationResult res;
  if (opt.mode == MappingMode::kGnssIns) {
    SLAM_MMS_ASSIGN_OR_RETURN(const bool mapped, MapWithPos(scan, s0, s1, &res));
    if (!mapped) return OkStatus();
  } else {
    const ScanMotionInput motion = MotionInput(scan, s0, s1);
    SLAM_MMS_ASSIGN_OR_RETURN(const bool localized, Localize(scan, motion, &res));
    if (!localized) return OkStatus();
  }
  last_scan_start = scan.stamp_start;
  have_scan = true;
  motion_builder.SetPrevious(s0.ok() ? std::optional<InsState>(*s0) : std::nullopt);
  results.push_back(res);
  if (callback) callback(results.back());
  return OkStatus();
}

std::pair<StatusOr<InsState>, StatusOr<InsState>> MappingSystem::Impl::PosOverScan(
    const Scan& scan) const {
  const bool pos_ok = ins.initialized() || external_pos;
  StatusOr<InsState> s0 = pos_ok
                              ? ins.StateAt(scan.stamp_start)
                              : StatusOr<InsState>(FailedPreconditionError("POS not initialized"));
  StatusOr<InsState> s1 = pos_ok
                              ? ins.StateAt(scan.stamp_end)
                              : StatusOr<InsState>(FailedPreconditionError("POS not initialized"));
  if (!s0.ok() && s1.ok() && scan.DurationSeconds() <= 0.25) {
    // The POS starts inside this scan (KITTI: the first OXTS record is stamped mid-scan): take
    // the scan-end state back to the scan start at constant velocity and, as the vehicle may be
    // turning (13 deg/s at the start of KITTI sequence 07: 1.3 deg in a scan), at the mean gyro
    // rate. Level 1 keeps the first scan's attitude as its reference.
    const double dt = s1->stamp.SecondsSince(scan.stamp_start);
    InsState back = *s1;
    back.stamp = scan.stamp_start;
    back.T_world_body.translation() -= s1->v_world_mps * dt;
    Eigen::Vector3d w = Eigen::Vector3d::Zero();
    int n = 0;
    for (const ImuSample& imu : input.imu_history()) {
      if (imu.stamp < scan.stamp_start || s1->stamp < imu.stamp) continue;
      w += imu.gyro_radps;
      ++n;
    }
    if (n > 0) {
      w = w / n - s1->gyro_bias_radps;
      back.T_world_body.linear() = s1->T_world_body.linear() * so3::Exp(-w * dt);
    }
    s0 = back;
  }
  return {std::move(s0), std::move(s1)};
}

StatusOr<bool> MappingSystem::Impl::MapWithPos(const Scan& scan, const StatusOr<InsState>& s0,
                                               const StatusOr<InsState>& s1,
                                               LocalizationResult* out) {
  LocalizationResult& res = *out;
  if (!s0.ok() || !s1.ok()) {
    ++skipped;
    SLAM_MMS_LOG(kWarning) << "gnss_ins: scan '" << scan.source << "' skipped: no POS state ("
                           << (!s0.ok() ? s0.status() : s1.status()).message() << ")";
    return false;
  }
  SLAM_MMS_ASSIGN_OR_RETURN(res, pos_mapper.Map(scan, *s0, *s1));
  return true;
}

ScanMotionInput MappingSystem::Impl::MotionInput(const Scan& scan, const StatusOr<InsState>& s0,
                                                 const StatusOr<InsState>& s1) {
  internal::MotionInputBuilder::Context context;
  context.g_world = ins.initialized() ? ins.gravity_world() : Eigen::Vector3d(0, 0, -9.80665);
  context.g_pos = ins.gravity_world();
  context.lidar_only = opt.mode == MappingMode::kLidarOnly;
  if (!context.lidar_only) {
    // An external POS is a solution over GNSS outages too (e.g. a smoothed one): F_Odom from it
    // throughout; the GNSS availability (where fixes are fed) only triggers level 2.
    const bool gnss_available =
        ins.gnss_prior().AvailabilityAt(scan.stamp_start) != GnssAvailability::kOutage;
    context.gnss_valid = external_pos || gnss_available;
    if (!external_pos || have_gnss_fed) UpdateOutageState(gnss_available, scan.stamp_start);
  }
  context.imu_from = have_scan ? last_scan_start : scan.stamp_start;
  if (context.lidar_only && results.empty() && s0.ok() &&
      opt.localizer.lidar_only_initial_velocity && s0->v_world_mps.allFinite()) {
    context.lidar_only_initial_v_world = s0->v_world_mps;
  }
  ScanMotionInput motion = motion_builder.Build(scan, s0, s1, context, input);
  // Where level 1 does not start from the POS pose (F_Odom does), the first scan is anchored at
  // it, as SuMa is started at a known pose.
  if (results.empty() && s0.ok() && motion.type != MotionFactorType::kOdometry) {
    loc->SetInitialPose(s0->T_world_body);
  }
  return motion;
}

StatusOr<bool> MappingSystem::Impl::Localize(const Scan& scan, const ScanMotionInput& motion,
                                             LocalizationResult* res) {
  auto r = loc->ProcessScan(scan, motion);
  if (!r.ok()) {
    if (r.status().code() == StatusCode::kInvalidArgument) {
      ++skipped;
      SLAM_MMS_LOG(kWarning) << "scan '" << scan.source << "' skipped: " << r.status().message();
      return OkStatus();
    }
    return r.status();
  }
  *res = std::move(r).value();
  MarkPosEpoch(scan, *res);
  SLAM_MMS_RETURN_IF_ERROR(ReportFinishedSubmaps());
  return true;
}

void MappingSystem::Impl::MarkPosEpoch(const Scan& scan, const LocalizationResult& res) {
  if (!level2 || !opt.level2.pos_attitude_cross_covariance || external_pos || !ins.initialized() ||
      res.submap_id == pos_epoch_submap) {
    return;
  }
  // The same scan ReportFinishedSubmaps will take the POS attitude at (checked there by stamp).
  // The correlation is read at the filter's newest state (the attitudes themselves at the
  // scan): a fraction of a scan past it where the host feeds the streams in time order. A host
  // that feeds the POS far ahead of the scans gets no chain (the priors).
  constexpr double kMaxPosEpochLagS = 0.5;
  const Timestamp t = scan.stamp_start;
  const StatusOr<InsState> now = ins.CurrentState();
  if (!now.ok() || now->stamp.SecondsSince(t) > kMaxPosEpochLagS ||
      ins.gnss_prior().AvailabilityAt(t) == GnssAvailability::kOutage || !ins.StateAt(t).ok()) {
    return;
  }
  PosEpoch e;
  e.stamp = t;
  if (pos_epoch_submap >= 0) {
    auto c = ins.AttitudeSinceEpoch();
    if (c.ok()) {
      auto chain = AttitudeChainFromCrossCovariance(c->R_world_body_epoch, c->cov_epoch,
                                                    c->R_world_body_now, c->cov_now, c->cross);
      if (chain.ok()) {
        e.link = SubmapManager::PosAttitude::Link{pos_epoch_submap, *chain};
      } else {
        SLAM_MMS_LOG(kWarning) << "submap " << res.submap_id
                               << ": no POS attitude correlation: " << chain.status().message();
      }
    }
  }
  if (!ins.MarkAttitudeEpoch().ok()) return;
  pos_epochs[res.submap_id] = e;
  pos_epoch_submap = res.submap_id;
}

void MappingSystem::Impl::UpdateOutageState(bool gnss_valid, Timestamp t) {
  if (!gnss_valid && !in_outage) {
    in_outage = true;
    outage_start = t;
    SLAM_MMS_LOG(kInfo) << "GNSS lost at " << t.ToKittiString()
                        << (external_pos ? ": level 1 keeps F_Odom from the external POS"
                                         : ": level 1 switches from F_Odom to F_Prein (IMU "
                                           "preintegration)");
  } else if (gnss_valid && in_outage) {
    in_outage = false;
    const double duration = t.SecondsSince(outage_start);
    SLAM_MMS_LOG(kInfo) << "GNSS back after " << duration << " s"
                        << (external_pos ? "" : ": level 1 switches from F_Prein back to F_Odom");
    if (level2 && duration >= opt.level2.long_outage_s) gnss_returned_pending = true;
  }
}

Status MappingSystem::Impl::ReportFinishedSubmaps() {
  if (!level2) return OkStatus();
  const auto& submaps = loc->submaps();
  while (submaps_reported < submaps.size() && submaps[submaps_reported].finished) {
    const int32_t id = submaps[submaps_reported].id;
    // The POS attitude for level 2's attitude prior, at the submap's first scan where GNSS
    // holds the POS, down-weighted fixes included (in an outage its attitude error outgrows its
    // covariance: on the demo drive with a 30 s outage, using it there raised full's ATE from
    // 0.30 to 0.33 m). Under single-point or no-fix GNSS the POS's attitude covariance is no
    // longer overconfident, its GNSS errors being Gauss-Markov states (InsFilter; attitude NEES
    // 2.2 on the 190 s drive, docs/results.md); without the prior level 2's yaw was
    // free there and followed the metre-level noise (1-6 deg on moving single-point drives of
    // the sweep, docs/sweep.md). It is taken to the
    // submap frame through level 1's relative pose: R_world_submap = R_world_body *
    // R_submap_body^T, and a right perturbation d of the body is R_submap_body * d of the
    // submap. The first scan may precede the POS (the POS can start inside it) and its first
    // fix. Without one, level 2 keeps level 1's roll/pitch, loosely, and a free yaw.
    const SubmapRecord& rec = submaps[submaps_reported];
    const GnssPrior& gp = ins.gnss_prior();
    std::optional<SubmapManager::PosAttitude> attitude;
    const bool pos_ready = external_pos || ins.initialized();
    for (size_t j = 0; pos_ready && j < rec.scan_stamps.size() && !attitude; ++j) {
      const Timestamp t = rec.scan_stamps[j];
      if (!external_pos && gp.AvailabilityAt(t) == GnssAvailability::kOutage) continue;
      StatusOr<InsState> s = ins.StateAt(t);
      if (!s.ok()) continue;
      const Eigen::Matrix3d R_sb = rec.T_submap_scan[j].linear();
      attitude = SubmapManager::PosAttitude{
          s->T_world_body.linear() * R_sb.transpose(),
          R_sb * s->cov_T_world_body.topLeftCorner<3, 3>() * R_sb.transpose(), std::nullopt};
      // The POS's own chain from the previous submap's attitude, where both attitudes were taken
      // at the scans their epochs were marked at (MarkPosEpoch).
      const auto e = pos_epochs.find(id);
      const bool at_epoch = e != pos_epochs.end() && e->second.stamp == t;
      if (at_epoch && e->second.link && e->second.link->previous_submap == last_attitude_at_epoch) {
        attitude->link = e->second.link;
      }
      last_attitude_at_epoch = at_epoch ? id : -1;
    }
    pos_epochs.erase(pos_epochs.begin(), pos_epochs.upper_bound(id));
    SLAM_MMS_ASSIGN_OR_RETURN(const std::vector<SubmapPoseUpdate> updates,
                              level2->OnSubmapFinished(*loc, id, gnss_returned_pending, attitude));
    SLAM_MMS_RETURN_IF_ERROR(ApplyLevel2(updates));
    gnss_returned_pending = false;
    ++submaps_reported;
  }
  return OkStatus();
}

Status MappingSystem::Impl::ApplyLevel2(const std::vector<SubmapPoseUpdate>& updates) {
  for (const SubmapPoseUpdate& u : updates) {
    SLAM_MMS_RETURN_IF_ERROR(loc->SetSubmapPose(u.id, u.T_world_submap));
  }
  return OkStatus();
}
}  // namespace slam_mms
