#include "pipeline/motion_prior.hpp"

#include <algorithm>
#include <utility>

#include "slam_mms/core/logging.hpp"

namespace slam_mms::internal {
Prediction MotionPrior::Predict(const Scan& scan, const ScanMotionInput& motion, bool is_reference,
                                const PreviousScan& prev, const Eigen::Isometry3d& T_world_submap,
                                const Eigen::Vector3d& g_submap) const {
  Prediction out;
  out.T_submap = prev.T_submap;
  out.v_submap = prev.v_submap;
  out.factor = is_reference ? MotionFactorType::kNone : motion.type;
  if (is_reference) return out;
  const double dt = scan.stamp_start.SecondsSince(prev.stamp);
  if (out.factor == MotionFactorType::kOdometry && !prev.has_pos) {
    out.factor = use_imu_states_ && !motion.imu.empty() ? MotionFactorType::kPreintegration
                                                        : MotionFactorType::kConstantVelocity;
  }
  if (out.factor == MotionFactorType::kOdometry) {
    out.T_submap = prev.T_submap * (prev.pos_start.inverse() * motion.T_world_body_pos_start);
    out.v_submap = T_world_submap.linear().transpose() * motion.v_world_pos;
  } else if (out.factor == MotionFactorType::kPreintegration) {
    ImuPreintegration pre(imu_, prev.bias.head<3>(), prev.bias.tail<3>());
    const Status st = pre.IntegrateWindow(motion.imu, prev.stamp, scan.stamp_start);
    if (st.ok() && pre.num_samples() > 0) {
      const NavState e = pre.Predict(prev.T_submap, prev.v_submap, g_submap);
      out.T_submap = MakeIsometry(e.q_world_body, e.p_world);
      out.v_submap = e.v_world;
      out.pre = std::move(pre);
    } else {
      SLAM_MMS_LOG(kWarning) << "Localizer: scan " << scan.index
                             << ": IMU does not cover the scan interval (" << st.message()
                             << "); constant-velocity prediction instead";
      out.factor = MotionFactorType::kConstantVelocity;
    }
  }
  if (out.factor == MotionFactorType::kConstantVelocity) {
    // The prediction follows the last interval (it tracks acceleration; registration corrects
    // it, so it does not feed back like the de-skew).
    if (auto motion_cv = ConstantVelocityMotion(dt, 1)) out.T_submap = prev.T_submap * *motion_cv;
  }
  return out;
}

Eigen::Isometry3d MotionPrior::DeskewMotion(const Scan& scan, const ScanMotionInput& motion,
                                            const Eigen::Isometry3d& T_submap_pred,
                                            const Eigen::Vector3d& v_submap_pred,
                                            const Eigen::Vector3d& g_submap, const Vector6d& bias,
                                            bool* constant_velocity) const {
  const double duration = scan.DurationSeconds();
  if (constant_velocity) *constant_velocity = false;
  switch (motion.type) {
    case MotionFactorType::kOdometry:
      return motion.T_world_body_pos_start.inverse() * motion.T_world_body_pos_end;
    case MotionFactorType::kPreintegration: {
      ImuPreintegration pre(imu_, bias.head<3>(), bias.tail<3>());
      if (pre.IntegrateWindow(motion.imu, scan.stamp_start, scan.stamp_end).ok() &&
          pre.num_samples() > 0) {
        const NavState e = pre.Predict(T_submap_pred, v_submap_pred, g_submap);
        Eigen::Isometry3d T_end = MakeIsometry(e.q_world_body, e.p_world);
        return T_submap_pred.inverse() * T_end;
      }
      [[fallthrough]];
    }
    default:
      if (constant_velocity) *constant_velocity = true;
      return ConstantVelocityMotion(duration, kDeskewVelocityIntervals)
          .value_or(Eigen::Isometry3d::Identity());
  }
}

std::optional<Eigen::Isometry3d> MotionPrior::ConstantVelocityMotion(double duration,
                                                                     size_t intervals) const {
  if (recent_.size() < 2) return std::nullopt;
  const size_t first = recent_.size() - 1 - std::min(intervals, recent_.size() - 1);
  const auto& [t0, T0] = recent_[first];
  const auto& [t1, T1] = recent_.back();
  const double dt = t1.SecondsSince(t0);
  if (!(dt > 1e-3)) return std::nullopt;
  return ScalePose(T0.inverse() * T1, duration / dt);
}

void MotionPrior::Record(Timestamp stamp, const Eigen::Isometry3d& T_submap_body) {
  recent_.emplace_back(stamp, T_submap_body);
  while (recent_.size() > kDeskewVelocityIntervals + 1) recent_.pop_front();
}

void MotionPrior::SeedVelocity(Timestamp stamp, const Eigen::Vector3d& v_submap,
                               double interval_s) {
  recent_.clear();
  for (size_t k = kDeskewVelocityIntervals; k >= 1; --k) {
    const double t = static_cast<double>(k) * interval_s;
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.translation() = -t * v_submap;
    recent_.emplace_back(stamp.PlusSeconds(-t), T);
  }
}

void MotionPrior::Reframe(const Eigen::Isometry3d& T_new_old) {
  for (auto& [stamp, T] : recent_) T = T_new_old * T;
}

}  // namespace slam_mms::internal
