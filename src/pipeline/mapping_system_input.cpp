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
  imu_history.push_back(s);
  if (external_pos) return OkStatus();
  Status st = ins.AddImu(s);
  if (st.ok()) MarkPosInput(s.stamp);
  return st;
}

Status MappingSystem::Impl::FeedGnss(const GnssFix& fix) {
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

void MappingSystem::Impl::MarkPosInput(Timestamp t) {
  if (!have_pos_input || last_pos_input < t) last_pos_input = t;
  have_pos_input = true;
}

Status MappingSystem::Impl::FlushPending() {
  size_t i = 0, j = 0;
  while (i < pending_imu.size() || j < pending_gnss.size()) {
    const bool take_imu = j >= pending_gnss.size() ||
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

bool MappingSystem::Impl::Ready(const Scan& scan) const {
  if (finished) return true;
  if (opt.mode == MappingMode::kLidarOnly && !results.empty()) return true;
  return have_pos_input && scan.stamp_end <= last_pos_input;
}

std::vector<ImuSample> MappingSystem::Impl::ImuBetween(Timestamp from, Timestamp to) const {
  std::vector<ImuSample> out;
  for (const ImuSample& s : imu_history) {
    if (s.stamp.SecondsSince(from) >= -0.2 && to.SecondsSince(s.stamp) >= -0.2) out.push_back(s);
  }
  return out;
}

Status MappingSystem::Impl::AcceptTime(const char* stream, Timestamp t, Timestamp* last,
                                       bool have_last) {
  if (have_last && t < *last) {
    return InvalidArgumentError(std::string("MappingSystem: ") + stream + " at " +
                                t.ToKittiString() + " is older than the previous one at " +
                                last->ToKittiString() + " (data must come in time order)");
  }
  *last = t;
  return OkStatus();
}
}  // namespace slam_mms
