#include "slam_mms/pipeline/mapping_system.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>
#include <string>
#include <thread>

#include "core/option_error.hpp"
#include "pipeline/voxel_accumulator.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/core/voxel_downsample.hpp"
#include "slam_mms/ins/imu_preintegration.hpp"
#include "slam_mms/pipeline/scan_deskewer.hpp"

namespace slam_mms {

Status MappingSystem::Options::Validate() const {
  if (!T_body_lidar.matrix().allFinite()) {
    return InvalidArgumentError("MappingSystem::Options::T_body_lidar is not finite");
  }
  const Eigen::Matrix3d R = T_body_lidar.linear();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-6) {
    return InvalidArgumentError(
        "MappingSystem::Options::T_body_lidar has a rotation that is not orthonormal");
  }
  for (size_t i = 0; i < gnss_outages.size(); ++i) {
    const auto& [start, duration] = gnss_outages[i];
    if (!std::isfinite(start) || !(duration > 0.0)) {
      return InvalidArgumentError("MappingSystem::Options::gnss_outages[" + std::to_string(i) +
                                  "] = (" + std::to_string(start) + ", " +
                                  std::to_string(duration) +
                                  "); start must be finite and duration > 0");
    }
  }
  if (!(map_max_range_m > 0.0)) {
    return internal::OptionError("MappingSystem::Options", "map_max_range_m", map_max_range_m,
                                 "must be > 0");
  }
  if (!(map_voxel_m > 0.0)) {
    return internal::OptionError("MappingSystem::Options", "map_voxel_m", map_voxel_m,
                                 "must be > 0");
  }
  if (!(max_pos_jump_m > 0.0)) {
    return internal::OptionError("MappingSystem::Options", "max_pos_jump_m", max_pos_jump_m,
                                 "must be > 0");
  }
  if (!(max_pos_jump_rad > 0.0)) {
    return internal::OptionError("MappingSystem::Options", "max_pos_jump_rad", max_pos_jump_rad,
                                 "must be > 0");
  }
  if (num_threads < 1) {
    return internal::OptionError("MappingSystem::Options", "num_threads", num_threads,
                                 "must be >= 1");
  }
  if (mode == MappingMode::kGnssInsSmoothed) {
    return InvalidArgumentError(
        "MappingSystem::Options::mode = gnss_ins_smoothed; an offline method: RunDrive smooths the "
        "whole IMU/GNSS stream first (PosSmoother), or feed a smoothed POS with AddInsPose in "
        "gnss_ins mode");
  }
  SLAM_MMS_RETURN_IF_ERROR(ins.Validate());
  if (mode != MappingMode::kGnssIns) {
    Localizer::Options loc = localizer;
    loc.mode = mode;
    SLAM_MMS_RETURN_IF_ERROR(loc.Validate());
    SLAM_MMS_RETURN_IF_ERROR(level2.Validate());
  }
  return OkStatus();
}

struct MappingSystem::Impl {
  Options opt;
  InsFilter ins;
  std::unique_ptr<Localizer> loc;
  std::unique_ptr<SubmapManager> level2;
  ScanDeskewer deskewer;

  bool external_pos = false;
  bool have_first_scan = false;
  bool finished = false;
  std::vector<ImuSample> pending_imu;  // before the first scan (outage reference unknown)
  std::vector<GnssFix> pending_gnss;
  std::deque<ImuSample> imu_history;  // for preintegration
  std::deque<Scan> queue;
  Timestamp last_imu;
  Timestamp last_gnss;
  Timestamp last_pos_input;
  bool have_pos_input = false;
  Timestamp last_scan_start;
  bool have_scan = false;

  std::vector<LocalizationResult> results;
  std::function<void(const LocalizationResult&)> callback;
  int skipped = 0;
  int pos_jumps = 0;
  std::optional<InsState> prev_pos;  // the POS state at the previous scan's start
  bool in_outage = false;
  Timestamp outage_start;
  bool gnss_returned_pending = false;
  bool have_gnss_fed = false;  // GNSS fixes reached the GnssPrior (also with an external POS)
  size_t submaps_reported = 0;

  // gnss_ins mode.
  Trajectory pos_trajectory;
  internal::VoxelAccumulator pos_map;
  PointCloud deskewed;

  Status FeedImu(const ImuSample& s) {
    imu_history.push_back(s);
    if (external_pos) return OkStatus();
    Status st = ins.AddImu(s);
    if (st.ok()) MarkPosInput(s.stamp);
    return st;
  }

  Status FeedGnss(const GnssFix& fix) {
    have_gnss_fed = true;
    auto decision = external_pos ? DecideAgainstExternalPos(fix) : ins.AddGnss(fix);
    if (!decision.ok()) return decision.status();
    MarkPosInput(fix.stamp);
    if (decision->usable() && level2) {
      level2->AddGnssMeasurement(decision->measurement, opt.ins.gnss.t_body_antenna);
    }
    if (decision->decision == GnssDecision::kReject) {
      SLAM_MMS_LOG(kDebug) << "GNSS fix at " << fix.stamp.ToKittiString()
                           << " rejected: " << decision->reason;
    }
    return OkStatus();
  }

  /// With an external POS the fixes are not fused: each is decided (GnssPrior: outage windows,
  /// type, innovation against the POS antenna position at the fix time) for level 2 only.
  StatusOr<GnssDecisionResult> DecideAgainstExternalPos(const GnssFix& fix) {
    const Eigen::Vector3d& t_ba = opt.ins.gnss.t_body_antenna;
    StatusOr<InsState> s = ins.StateAt(fix.stamp);
    if (!s.ok()) return ins.mutable_gnss_prior().Process(fix, nullptr);
    // p_antenna = p + R t_ba; with T = T_hat Exp([w; rho]): dp_antenna = R (rho - [t_ba]x w).
    const Eigen::Matrix3d R = s->T_world_body.linear();
    Eigen::Matrix<double, 3, 6> J;
    J << -R * so3::Hat(t_ba), R;
    GnssPrediction pred;
    pred.p_world_antenna = s->T_world_body.translation() + R * t_ba;
    pred.cov_world_antenna = J * s->cov_T_world_body * J.transpose();
    return ins.mutable_gnss_prior().Process(fix, &pred);
  }

  void MarkPosInput(Timestamp t) {
    if (!have_pos_input || last_pos_input < t) last_pos_input = t;
    have_pos_input = true;
  }

  /// Replays the data buffered before the first scan, merged in time order.
  Status FlushPending() {
    size_t i = 0, j = 0;
    while (i < pending_imu.size() || j < pending_gnss.size()) {
      const bool take_imu =
          j >= pending_gnss.size() ||
          (i < pending_imu.size() && pending_imu[i].stamp <= pending_gnss[j].stamp);
      if (take_imu) {
        SLAM_MMS_RETURN_IF_ERROR(FeedImu(pending_imu[i++]));
      } else {
        SLAM_MMS_RETURN_IF_ERROR(FeedGnss(pending_gnss[j++]));
      }
    }
    pending_imu.clear();
    pending_gnss.clear();
    return OkStatus();
  }

  bool Ready(const Scan& scan) const {
    if (finished) return true;
    if (opt.mode == MappingMode::kLidarOnly && !results.empty()) return true;
    return have_pos_input && scan.stamp_end <= last_pos_input;
  }

  std::vector<ImuSample> ImuBetween(Timestamp from, Timestamp to) const {
    std::vector<ImuSample> out;
    for (const ImuSample& s : imu_history) {
      if (s.stamp.SecondsSince(from) >= -0.2 && to.SecondsSince(s.stamp) >= -0.2) out.push_back(s);
    }
    return out;
  }

  /// How far the POS moved from `a` to `b` beyond what its IMU measured between them (position
  /// [m], rotation [rad]); empty where the IMU does not cover [a, b].
  std::optional<std::pair<double, double>> PosJump(const InsState& a, const InsState& b) const {
    if (!(a.stamp < b.stamp)) return std::nullopt;
    const std::vector<ImuSample> imu = ImuBetween(a.stamp, b.stamp);
    ImuPreintegration pre(ImuPreintegration::Options(), a.accel_bias_mps2, a.gyro_bias_radps);
    if (imu.empty() || !pre.IntegrateWindow(imu, a.stamp, b.stamp).ok()) return std::nullopt;
    NavState s;
    s.q_world_body = Eigen::Quaterniond(a.T_world_body.linear());
    s.p_world = a.T_world_body.translation();
    s.v_world = a.v_world_mps;
    const NavState e = pre.Predict(s, ins.gravity_world());
    const double dp = (e.p_world - b.T_world_body.translation()).norm();
    const double dr =
        Eigen::AngleAxisd(e.q_world_body.toRotationMatrix().transpose() * b.T_world_body.linear())
            .angle();
    return std::make_pair(dp, dr);
  }

  /// Whether the POS jumped from the previous scan to this one or within this scan (then its
  /// relative motion is no odometry measurement).
  bool PosJumped(const Scan& scan, const InsState& s0, const InsState& s1) {
    for (const auto& [a, b] :
         {std::make_pair(prev_pos, std::optional<InsState>(s0)),
          std::make_pair(std::optional<InsState>(s0), std::optional<InsState>(s1))}) {
      if (!a) continue;
      const auto jump = PosJump(*a, *b);
      if (!jump || (jump->first <= opt.max_pos_jump_m && jump->second <= opt.max_pos_jump_rad)) {
        continue;
      }
      ++pos_jumps;
      SLAM_MMS_LOG(kInfo) << "POS jumped by " << jump->first << " m, " << jump->second
                          << " rad beyond its IMU before scan '" << scan.source
                          << "': level 1 uses F_Prein for it, not F_Odom";
      return true;
    }
    return false;
  }

  Status ProcessQueued() {
    while (!queue.empty() && Ready(queue.front())) {
      Scan scan = std::move(queue.front());
      queue.pop_front();
      SLAM_MMS_RETURN_IF_ERROR(ProcessScan(scan));
    }
    // Keep ~5 s of IMU behind the oldest scan still to come.
    const Timestamp keep_from = (queue.empty() ? last_scan_start : queue.front().stamp_start);
    while (!imu_history.empty() && keep_from.SecondsSince(imu_history.front().stamp) > 5.0) {
      imu_history.pop_front();
    }
    return OkStatus();
  }

  Status ProcessScan(const Scan& scan) {
    const bool pos_ok = ins.initialized() || external_pos;
    StatusOr<InsState> s0 =
        pos_ok ? ins.StateAt(scan.stamp_start)
               : StatusOr<InsState>(FailedPreconditionError("POS not initialized"));
    StatusOr<InsState> s1 =
        pos_ok ? ins.StateAt(scan.stamp_end)
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
      for (const ImuSample& imu : imu_history) {
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
    LocalizationResult res;
    if (opt.mode == MappingMode::kGnssIns) {
      if (!s0.ok() || !s1.ok()) {
        ++skipped;
        SLAM_MMS_LOG(kWarning) << "gnss_ins: scan '" << scan.source << "' skipped: no POS state ("
                               << (!s0.ok() ? s0.status() : s1.status()).message() << ")";
        return OkStatus();
      }
      const Eigen::Isometry3d T_bstart_bend = s0->T_world_body.inverse() * s1->T_world_body;
      SLAM_MMS_RETURN_IF_ERROR(deskewer.Deskew(scan, T_bstart_bend, opt.T_body_lidar, &deskewed));
      const internal::ScanStamp stamp{scan.stamp_start.nanoseconds(), &scan.cloud.time_offsets_s(),
                                      scan.index};
      pos_map.Add(deskewed, s0->T_world_body * opt.T_body_lidar, opt.map_max_range_m, &stamp);
      StampedPose pose;
      pose.stamp = scan.stamp_start;
      pose.T_world_body = s0->T_world_body;
      pose.cov_T_world_body = s0->cov_T_world_body;
      SLAM_MMS_RETURN_IF_ERROR(pos_trajectory.Add(pose));
      res.scan_index = scan.index;
      res.stamp = scan.stamp_start;
      res.T_world_body = s0->T_world_body;
      res.cov_T_world_body = s0->cov_T_world_body;
      res.motion_factor = MotionFactorType::kPos;
    } else {
      ScanMotionInput motion;
      motion.g_world = ins.initialized() ? ins.gravity_world() : Eigen::Vector3d(0, 0, -9.80665);
      const bool lidar_only = opt.mode == MappingMode::kLidarOnly;
      if (lidar_only) {
        motion.type = MotionFactorType::kConstantVelocity;
        if (results.empty() && s0.ok()) {
          loc->SetInitialPose(s0->T_world_body);  // the anchor, as SuMa is started at a known pose
        }
      } else {
        // An external POS is a solution over GNSS outages too (e.g. a smoothed one): F_Odom from it
        // throughout; the GNSS availability (where fixes are fed) only triggers level 2.
        const bool gnss_available =
            ins.gnss_prior().AvailabilityAt(scan.stamp_start) != GnssAvailability::kOutage;
        const bool gnss_valid = external_pos || gnss_available;
        if (!external_pos || have_gnss_fed) UpdateOutageState(gnss_available, scan.stamp_start);
        if (gnss_valid && s0.ok() && s1.ok() && !PosJumped(scan, *s0, *s1)) {
          motion.type = MotionFactorType::kOdometry;
          motion.T_world_body_pos_start = s0->T_world_body;
          motion.T_world_body_pos_end = s1->T_world_body;
          motion.v_world_pos = s0->v_world_mps;
          motion.pos_bias << s0->accel_bias_mps2, s0->gyro_bias_radps;
        } else {
          motion.type = MotionFactorType::kPreintegration;
          if (s0.ok()) {
            motion.v_world_pos = s0->v_world_mps;
            motion.pos_bias << s0->accel_bias_mps2, s0->gyro_bias_radps;
            if (results.empty()) loc->SetInitialPose(s0->T_world_body);
          }
          const Timestamp from = have_scan ? last_scan_start : scan.stamp_start;
          motion.imu = ImuBetween(from, scan.stamp_end);
          if (motion.imu.empty()) motion.type = MotionFactorType::kConstantVelocity;
        }
      }
      auto r = loc->ProcessScan(scan, motion);
      if (!r.ok()) {
        if (r.status().code() == StatusCode::kInvalidArgument) {
          ++skipped;
          SLAM_MMS_LOG(kWarning) << "scan '" << scan.source
                                 << "' skipped: " << r.status().message();
          return OkStatus();
        }
        return r.status();
      }
      res = std::move(r).value();
      SLAM_MMS_RETURN_IF_ERROR(ReportFinishedSubmaps());
    }
    last_scan_start = scan.stamp_start;
    have_scan = true;
    prev_pos = s0.ok() ? std::optional<InsState>(*s0) : std::nullopt;
    results.push_back(res);
    if (callback) callback(results.back());
    return OkStatus();
  }

  void UpdateOutageState(bool gnss_valid, Timestamp t) {
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

  /// Hands the submaps level 1 has finished to level 2, in order.
  Status ReportFinishedSubmaps() {
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
            R_sb * s->cov_T_world_body.topLeftCorner<3, 3>() * R_sb.transpose()};
      }
      SLAM_MMS_ASSIGN_OR_RETURN(
          const std::vector<SubmapPoseUpdate> updates,
          level2->OnSubmapFinished(*loc, id, gnss_returned_pending, attitude));
      SLAM_MMS_RETURN_IF_ERROR(ApplyLevel2(updates));
      gnss_returned_pending = false;
      ++submaps_reported;
    }
    return OkStatus();
  }

  /// The one way level 2 reaches level 1: its estimates, applied to the submaps (and their
  /// surfels) in order.
  Status ApplyLevel2(const std::vector<SubmapPoseUpdate>& updates) {
    for (const SubmapPoseUpdate& u : updates) {
      SLAM_MMS_RETURN_IF_ERROR(loc->SetSubmapPose(u.id, u.T_world_submap));
    }
    return OkStatus();
  }

  Status AcceptTime(const char* stream, Timestamp t, Timestamp* last, bool have_last) {
    if (have_last && t < *last) {
      return InvalidArgumentError(std::string("MappingSystem: ") + stream + " at " +
                                  t.ToKittiString() + " is older than the previous one at " +
                                  last->ToKittiString() + " (data must come in time order)");
    }
    *last = t;
    return OkStatus();
  }
  bool have_imu = false;
  bool have_gnss = false;
};

MappingSystem::MappingSystem(const Options& options) : impl_(std::make_unique<Impl>()) {
  impl_->opt = options;
}
MappingSystem::~MappingSystem() = default;

StatusOr<std::unique_ptr<MappingSystem>> MappingSystem::Create(const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  std::unique_ptr<MappingSystem> sys(new MappingSystem(options));
  Impl& m = *sys->impl_;
  SLAM_MMS_ASSIGN_OR_RETURN(m.ins, InsFilter::Create(options.ins));
  if (options.origin) {
    SLAM_MMS_RETURN_IF_ERROR(m.ins.mutable_gnss_prior().SetOrigin(*options.origin));
  }
  ScanDeskewer::Options dopt;
  dopt.num_threads = options.num_threads;
  SLAM_MMS_ASSIGN_OR_RETURN(m.deskewer, ScanDeskewer::Create(dopt));
  m.pos_map = internal::VoxelAccumulator(options.map_voxel_m, /*track_first_observation=*/true);
  if (options.mode != MappingMode::kGnssIns) {
    Localizer::Options lopt = options.localizer;
    lopt.mode = options.mode;
    lopt.map_voxel_m = options.map_voxel_m;
    lopt.map_max_range_m = options.map_max_range_m;
    SLAM_MMS_ASSIGN_OR_RETURN(m.loc, Localizer::Create(lopt, options.T_body_lidar));
    SubmapManager::Options l2 = options.level2;
    if (options.mode == MappingMode::kLidarOnly) l2.use_gnss = false;
    if (l2.enabled) {
      SLAM_MMS_ASSIGN_OR_RETURN(m.level2, SubmapManager::Create(l2));
    }
  }
  return sys;
}

Status MappingSystem::AddImu(const ImuSample& sample) {
  Impl& m = *impl_;
  if (m.finished) return FailedPreconditionError("MappingSystem::AddImu after Finish()");
  if (!sample.accel_mps2.allFinite() || !sample.gyro_radps.allFinite()) {
    return InvalidArgumentError("MappingSystem::AddImu: non-finite sample at " +
                                sample.stamp.ToKittiString());
  }
  SLAM_MMS_RETURN_IF_ERROR(m.AcceptTime("IMU sample", sample.stamp, &m.last_imu, m.have_imu));
  m.have_imu = true;
  if (!m.have_first_scan) {
    m.pending_imu.push_back(sample);
    return OkStatus();
  }
  SLAM_MMS_RETURN_IF_ERROR(m.FeedImu(sample));
  return m.ProcessQueued();
}

Status MappingSystem::AddGnss(const GnssFix& fix) {
  Impl& m = *impl_;
  if (m.finished) return FailedPreconditionError("MappingSystem::AddGnss after Finish()");
  SLAM_MMS_RETURN_IF_ERROR(m.AcceptTime("GNSS fix", fix.stamp, &m.last_gnss, m.have_gnss));
  m.have_gnss = true;
  if (!m.have_first_scan) {
    m.pending_gnss.push_back(fix);
    return OkStatus();
  }
  SLAM_MMS_RETURN_IF_ERROR(m.FeedGnss(fix));
  return m.ProcessQueued();
}

Status MappingSystem::InitializePos(const InsState& state) {
  Impl& m = *impl_;
  if (!state.T_world_body.matrix().allFinite() || !state.v_world_mps.allFinite()) {
    return InvalidArgumentError("MappingSystem::InitializePos: non-finite state");
  }
  // The stamp lets the IMU carry the attitude to the first usable fix (which may come later).
  return m.ins.InitializeAttitude(Eigen::Quaterniond(state.T_world_body.linear()),
                                  state.v_world_mps, state.stamp);
}

Status MappingSystem::AddInsPose(const InsState& state) {
  Impl& m = *impl_;
  m.external_pos = true;
  SLAM_MMS_RETURN_IF_ERROR(m.ins.AddExternalPose(state));
  m.MarkPosInput(state.stamp);
  if (!m.have_first_scan) return OkStatus();
  return m.ProcessQueued();
}

Status MappingSystem::AddScan(const Scan& scan) {
  Impl& m = *impl_;
  if (m.finished) return FailedPreconditionError("MappingSystem::AddScan after Finish()");
  if (scan.cloud.empty()) {
    ++m.skipped;
    SLAM_MMS_LOG(kWarning) << "scan '" << scan.source << "' (index " << scan.index
                           << ") skipped: no points";
    return OkStatus();
  }
  const auto& points = scan.cloud.points();
  if (std::none_of(points.begin(), points.end(),
                   [](const Eigen::Vector3f& p) { return p.allFinite(); })) {
    ++m.skipped;
    SLAM_MMS_LOG(kWarning) << "scan '" << scan.source << "' (index " << scan.index
                           << ") skipped: no finite point";
    return OkStatus();
  }
  if (!(scan.stamp_start <= scan.stamp_end)) {
    ++m.skipped;
    SLAM_MMS_LOG(kWarning) << "scan '" << scan.source << "' skipped: stamp_end before stamp_start";
    return OkStatus();
  }
  const Timestamp newest = m.queue.empty() ? (m.have_scan ? m.last_scan_start : Timestamp())
                                           : m.queue.back().stamp_start;
  if ((m.have_scan || !m.queue.empty()) && !(newest < scan.stamp_start)) {
    ++m.skipped;
    SLAM_MMS_LOG(kWarning) << "scan '" << scan.source << "' skipped: it starts at "
                           << scan.stamp_start.ToKittiString()
                           << ", not after the previous scan at " << newest.ToKittiString();
    return OkStatus();
  }
  if (!m.have_first_scan) {
    m.have_first_scan = true;
    m.ins.mutable_gnss_prior().SetReferenceTime(scan.stamp_start);
    for (const auto& [start, duration] : m.opt.gnss_outages) {
      SLAM_MMS_RETURN_IF_ERROR(m.ins.mutable_gnss_prior().AddOutageWindow(start, duration));
    }
    SLAM_MMS_RETURN_IF_ERROR(m.FlushPending());
  }
  m.queue.push_back(scan);
  return m.ProcessQueued();
}

Status MappingSystem::Finish() {
  Impl& m = *impl_;
  if (m.finished) return OkStatus();
  if (!m.have_first_scan) SLAM_MMS_RETURN_IF_ERROR(m.FlushPending());
  m.finished = true;
  SLAM_MMS_RETURN_IF_ERROR(m.ProcessQueued());
  if (m.loc) {
    m.loc->FinishCurrentSubmap();
    SLAM_MMS_RETURN_IF_ERROR(m.ReportFinishedSubmaps());
    if (m.level2) {
      SLAM_MMS_ASSIGN_OR_RETURN(const std::vector<SubmapPoseUpdate> updates,
                                m.level2->Finish(*m.loc));
      SLAM_MMS_RETURN_IF_ERROR(m.ApplyLevel2(updates));
    }
  }
  return OkStatus();
}

const std::vector<LocalizationResult>& MappingSystem::results() const { return impl_->results; }

void MappingSystem::SetResultCallback(std::function<void(const LocalizationResult&)> callback) {
  impl_->callback = std::move(callback);
}

Trajectory MappingSystem::FinalTrajectory() const {
  const Impl& m = *impl_;
  if (!m.loc) return m.pos_trajectory;
  std::vector<StampedPose> poses;
  for (const SubmapRecord& rec : m.loc->submaps()) {
    for (size_t j = 0; j < rec.T_submap_scan.size(); ++j) {
      StampedPose p;
      p.stamp = rec.scan_stamps[j];
      p.T_world_body = rec.T_world_submap * rec.T_submap_scan[j];
      // Rotate the submap-relative covariance (right perturbation: unchanged by left composition).
      p.cov_T_world_body = rec.cov_submap_scan[j];
      poses.push_back(p);
    }
  }
  std::sort(poses.begin(), poses.end(),
            [](const StampedPose& a, const StampedPose& b) { return a.stamp < b.stamp; });
  Trajectory traj;
  for (const StampedPose& p : poses) {
    if (!traj.Add(p).ok()) continue;  // duplicates cannot happen; guard anyway
  }
  return traj;
}

PointCloud MappingSystem::FinalMap() const { return FinalMap(nullptr); }

namespace {

// Per voxel of VoxelDownsample(cloud, voxel_m), in its output order (voxels sorted by
// integer key, the same floor(p / voxel) of the float point): the stamps of the voxel's earliest
// point. Empty when `in` does not match `cloud`.
MapPointStamps EarliestPerVoxel(const PointCloud& cloud, const MapPointStamps& in, double voxel_m) {
  MapPointStamps out;
  if (in.size() != cloud.size() || in.scan_index.size() != cloud.size()) return out;
  struct Key {
    int32_t ix, iy, iz;
    uint32_t index;
  };
  const double inv = 1.0 / voxel_m;
  std::vector<Key> keys;
  keys.reserve(cloud.size());
  for (size_t i = 0; i < cloud.size(); ++i) {
    const Eigen::Vector3f& p = cloud.points()[i];
    if (!p.allFinite()) continue;
    keys.push_back({static_cast<int32_t>(std::floor(p.x() * inv)),
                    static_cast<int32_t>(std::floor(p.y() * inv)),
                    static_cast<int32_t>(std::floor(p.z() * inv)), static_cast<uint32_t>(i)});
  }
  std::sort(keys.begin(), keys.end(), [](const Key& a, const Key& b) {
    if (a.ix != b.ix) return a.ix < b.ix;
    if (a.iy != b.iy) return a.iy < b.iy;
    if (a.iz != b.iz) return a.iz < b.iz;
    return a.index < b.index;
  });
  for (size_t begin = 0; begin < keys.size();) {
    size_t end = begin + 1;
    size_t best = keys[begin].index;
    while (end < keys.size() && keys[end].ix == keys[begin].ix && keys[end].iy == keys[begin].iy &&
           keys[end].iz == keys[begin].iz) {
      if (in.time_ns[keys[end].index] < in.time_ns[best]) best = keys[end].index;
      ++end;
    }
    out.time_ns.push_back(in.time_ns[best]);
    out.scan_index.push_back(in.scan_index[best]);
    begin = end;
  }
  return out;
}

}  // namespace

PointCloud MappingSystem::FinalMap(MapPointStamps* stamps) const {
  const Impl& m = *impl_;
  if (stamps != nullptr) stamps->clear();
  if (!m.loc) {
    return stamps != nullptr ? m.pos_map.Cloud(&stamps->time_ns, &stamps->scan_index)
                             : m.pos_map.Cloud();
  }
  PointCloud merged;
  MapPointStamps merged_stamps;
  bool all_stamped = stamps != nullptr;
  size_t total = 0;
  for (const SubmapRecord& rec : m.loc->submaps()) total += rec.cloud_size;
  merged.reserve(total);
  MapPointStamps submap_stamps;
  for (const SubmapRecord& rec : m.loc->submaps()) {
    // From memory, or read back from the spill folder (Localizer::Options::spill_dir).
    auto cloud = m.loc->SubmapCloud(rec.id, Localizer::CloudKind::kMap,
                                    stamps != nullptr ? &submap_stamps : nullptr);
    if (!cloud.ok()) {
      SLAM_MMS_LOG(kError) << "MappingSystem::FinalMap: submap " << rec.id
                           << " left out: " << cloud.status().ToString();
      continue;
    }
    const Eigen::Matrix3f R = rec.T_world_submap.linear().cast<float>();
    const Eigen::Vector3f t = rec.T_world_submap.translation().cast<float>();
    for (size_t i = 0; i < cloud->size(); ++i) {
      merged.Add(R * cloud->points()[i] + t, cloud->intensities()[i]);
    }
    if (all_stamped && submap_stamps.size() == cloud->size()) {
      merged_stamps.time_ns.insert(merged_stamps.time_ns.end(), submap_stamps.time_ns.begin(),
                                   submap_stamps.time_ns.end());
      merged_stamps.scan_index.insert(merged_stamps.scan_index.end(),
                                      submap_stamps.scan_index.begin(),
                                      submap_stamps.scan_index.end());
    } else {
      all_stamped = false;
    }
  }
  // The centroids and the stamps are two independent sorts of the merged cloud: the stamps on a
  // second thread where asked for.
  MapPointStamps earliest;
  std::thread stamp_thread;
  if (all_stamped && m.opt.num_threads > 1) {
    stamp_thread =
        std::thread([&] { earliest = EarliestPerVoxel(merged, merged_stamps, m.opt.map_voxel_m); });
  } else if (all_stamped) {
    earliest = EarliestPerVoxel(merged, merged_stamps, m.opt.map_voxel_m);
  }
  auto down = VoxelDownsample(merged, m.opt.map_voxel_m);
  if (stamp_thread.joinable()) stamp_thread.join();
  if (!down.ok()) {
    if (all_stamped) *stamps = std::move(merged_stamps);
    return merged;
  }
  if (all_stamped) {
    if (earliest.size() == down->size()) {
      *stamps = std::move(earliest);
    } else {
      SLAM_MMS_LOG(kWarning) << "MappingSystem::FinalMap: point stamps do not match the map ("
                             << earliest.size() << " vs " << down->size() << "), left out";
    }
  }
  return std::move(down).value();
}

std::vector<Surfel> MappingSystem::SurfelMapSnapshot() const {
  if (!impl_->loc) return {};
  return impl_->loc->AllSurfels();
}

StatusOr<GeodeticPoint> MappingSystem::Origin() const {
  const GnssPrior& prior = impl_->ins.gnss_prior();
  if (!prior.has_origin()) {
    return FailedPreconditionError(
        "MappingSystem::Origin: no valid GNSS fix yet and no origin set");
  }
  return prior.origin();
}

std::vector<GnssAvailabilityInterval> MappingSystem::GnssAvailability() const {
  return impl_->ins.gnss_prior().AvailabilityIntervals();
}

int MappingSystem::num_pos_jumps() const { return impl_->pos_jumps; }
int MappingSystem::num_skipped_scans() const { return impl_->skipped; }

SubmapManager::Stats MappingSystem::level2_stats() const {
  return impl_->level2 ? impl_->level2->stats() : SubmapManager::Stats{};
}

const MappingSystem::Options& MappingSystem::options() const { return impl_->opt; }

}  // namespace slam_mms
