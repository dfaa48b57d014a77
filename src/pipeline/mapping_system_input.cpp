// The sensor buffer of MappingSystem (Impl): IMU and GNSS into the POS in time order, held back
// until the first scan fixes the outage reference; scans queued until the POS covers them.
#include <algorithm>
#include <cmath>
#include <string>

#include "pipeline/mapping_system_impl.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/ins/imu_preintegration.hpp"

namespace slam_mms {

Status MappingSystem::Impl::FeedImu(const ImuSample& s) {
  input.RecordImu(s);
  if (external_pos) return OkStatus();
  Status st = ins.AddImu(s);
  if (st.ok()) input.MarkPosInput(s.stamp);
  return st;
}

Status MappingSystem::Impl::FeedGnss(const GnssFix& fix) {
  have_gnss_fed = true;
  auto decision = external_pos ? DecideAgainstExternalPos(fix) : ins.AddGnss(fix);
  if (!decision.ok()) return decision.status();
  input.MarkPosInput(fix.stamp);
  if (decision->usable() && level2) {
    level2->AddGnssMeasurement(decision->measurement, opt.ins.gnss.t_body_antenna);
  }
  if (decision->decision == GnssDecision::kReject) {
    SLAM_MMS_LOG(kDebug) << "GNSS fix at " << fix.stamp.ToKittiString()
                         << " rejected: " << decision->reason;
  }
  return OkStatus();
}

StatusOr<GnssDecisionResult> MappingSystem::Impl::DecideAgainstExternalPos(const GnssFix& fix) {
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

Status MappingSystem::Impl::FlushPending() {
  return input.ReleaseHeld([this](const ImuSample& s) { return FeedImu(s); },
                           [this](const GnssFix& fix) { return FeedGnss(fix); });
}

bool MappingSystem::Impl::Ready(const Scan& scan) const {
  if (finished) return true;
  if (opt.mode == MappingMode::kLidarOnly && !results.empty()) return true;
  return input.PosCovers(scan);
}

}  // namespace slam_mms
