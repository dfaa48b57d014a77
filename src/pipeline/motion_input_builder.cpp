#include "pipeline/motion_input_builder.hpp"

#include <vector>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/ins/imu_preintegration.hpp"

namespace slam_mms::internal {

std::optional<std::pair<double, double>> MotionInputBuilder::PosJump(const InsState& a,
                                                                     const InsState& b,
                                                                     const SensorBuffer& imu,
                                                                     const Eigen::Vector3d& g_pos) {
  if (!(a.stamp < b.stamp)) return std::nullopt;
  const std::vector<ImuSample> samples = imu.ImuBetween(a.stamp, b.stamp);
  ImuPreintegration pre(ImuPreintegration::Options(), a.accel_bias_mps2, a.gyro_bias_radps);
  if (samples.empty() || !pre.IntegrateWindow(samples, a.stamp, b.stamp).ok()) {
    return std::nullopt;
  }
  const NavState e = pre.Predict(a.T_world_body, a.v_world_mps, g_pos);
  const double dp = (e.p_world - b.T_world_body.translation()).norm();
  const double dr =
      Eigen::AngleAxisd(e.q_world_body.toRotationMatrix().transpose() * b.T_world_body.linear())
          .angle();
  return std::make_pair(dp, dr);
}

bool MotionInputBuilder::PosJumped(const Scan& scan, const InsState& s0, const InsState& s1,
                                   const SensorBuffer& imu, const Eigen::Vector3d& g_pos) {
  for (const auto& [a, b] :
       {std::make_pair(prev_pos_, std::optional<InsState>(s0)),
        std::make_pair(std::optional<InsState>(s0), std::optional<InsState>(s1))}) {
    if (!a) continue;
    const auto jump = PosJump(*a, *b, imu, g_pos);
    if (!jump || (jump->first <= max_jump_m_ && jump->second <= max_jump_rad_)) continue;
    ++pos_jumps_;
    SLAM_MMS_LOG(kInfo) << "POS jumped by " << jump->first << " m, " << jump->second
                        << " rad beyond its IMU before scan '" << scan.source
                        << "': level 1 uses F_Prein for it, not F_Odom";
    return true;
  }
  return false;
}

ScanMotionInput MotionInputBuilder::Build(const Scan& scan, const StatusOr<InsState>& s0,
                                          const StatusOr<InsState>& s1, const Context& context,
                                          const SensorBuffer& imu) {
  ScanMotionInput motion;
  motion.g_world = context.g_world;
  if (context.lidar_only) {
    motion.type = MotionFactorType::kConstantVelocity;
    if (context.lidar_only_initial_v_world)
      motion.v_world_pos = *context.lidar_only_initial_v_world;
    return motion;
  }
  if (context.gnss_valid && s0.ok() && s1.ok() && !PosJumped(scan, *s0, *s1, imu, context.g_pos)) {
    motion.type = MotionFactorType::kOdometry;
    motion.T_world_body_pos_start = s0->T_world_body;
    motion.T_world_body_pos_end = s1->T_world_body;
    motion.v_world_pos = s0->v_world_mps;
    motion.pos_bias << s0->accel_bias_mps2, s0->gyro_bias_radps;
    return motion;
  }
  motion.type = MotionFactorType::kPreintegration;
  if (s0.ok()) {
    motion.v_world_pos = s0->v_world_mps;
    motion.pos_bias << s0->accel_bias_mps2, s0->gyro_bias_radps;
  }
  motion.imu = imu.ImuBetween(context.imu_from, scan.stamp_end);
  if (motion.imu.empty()) motion.type = MotionFactorType::kConstantVelocity;
  return motion;
}

}  // namespace slam_mms::internal
