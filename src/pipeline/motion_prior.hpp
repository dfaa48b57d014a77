#pragma once
// MotionPrior: level 1's motion prior (Localizer, issue #19 part 2): where a scan is predicted
// from the previous one, and how the body moved over the scan for its de-skew, by the motion
// source of the scan's ScanMotionInput:
//   kOdometry        the POS relative motion (F_Odom, eq 12) where the previous scan had a POS
//                    pose;
//   kPreintegration  IMU preintegration (eq 13) from the previous optimized state (F_Prein);
//   otherwise        constant velocity from the last optimized poses (LiDAR only, or no IMU).
// The de-skew's constant velocity is measured over kDeskewVelocityIntervals scan intervals, not
// the last one: with the last interval, an error in the estimated rotation between two scans bends
// the next de-skewed scan, whose registration then errs the other way, and the alternating error
// grows (measured on the simulated drive: 40 deg of roll error after 8 s).
//
// Ownership: keeps the last optimized poses (current submap frame). Thread safety: not
// thread-safe.

#include <Eigen/Geometry>
#include <cstddef>
#include <deque>
#include <optional>
#include <utility>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/ins/imu_preintegration.hpp"
#include "slam_mms/pipeline/localizer.hpp"

namespace slam_mms::internal {

/// Scan intervals over which the constant-velocity de-skew measures the velocity.
inline constexpr size_t kDeskewVelocityIntervals = 3;

/// Pose T scaled along its twist: Exp(s * Log(T)).
inline Eigen::Isometry3d ScalePose(const Eigen::Isometry3d& T, double s) {
  return se3::Exp(s * se3::Log(T));
}

/// What the motion prior predicts for a scan before it is registered.
struct Prediction {
  Eigen::Isometry3d T_submap = Eigen::Isometry3d::Identity();  ///< T_submap_body.
  Eigen::Vector3d v_submap = Eigen::Vector3d::Zero();          ///< Body velocity in the submap.
  MotionFactorType factor = MotionFactorType::kNone;           ///< The motion factor to add.
  std::optional<ImuPreintegration> pre;  ///< F_Prein's preintegration (kPreintegration).
};

/// Level 1's optimized state of the previous scan (current submap frame).
struct PreviousScan {
  Timestamp stamp;
  Eigen::Isometry3d T_submap = Eigen::Isometry3d::Identity();  ///< T_submap_body.
  Eigen::Vector3d v_submap = Eigen::Vector3d::Zero();
  Vector6d bias = Vector6d::Zero();  ///< IMU biases [ba, bg].
  /// The previous scan had the POS pose pos_start (T_world_body at its start): F_Odom possible.
  bool has_pos = false;
  Eigen::Isometry3d pos_start = Eigen::Isometry3d::Identity();
  /// The body motion over the scan it was de-skewed with (T_bstart_bend) and its duration [s].
  Eigen::Isometry3d T_bstart_bend = Eigen::Isometry3d::Identity();
  double duration_s = 0.0;
};

class MotionPrior {
 public:
  MotionPrior() = default;
  /// `imu`: the preintegration noise; `use_imu_states`: the window has velocity and bias states
  /// (full mode), so a missing POS pose falls back to preintegration rather than constant
  /// velocity.
  MotionPrior(const ImuPreintegration::Options& imu, bool use_imu_states)
      : imu_(imu), use_imu_states_(use_imu_states) {}

  /// The pose and velocity predicted for `scan` and the motion factor that will tie it to the
  /// previous scan (kNone for a submap reference, which is predicted at the previous pose).
  Prediction Predict(const Scan& scan, const ScanMotionInput& motion, bool is_reference,
                     const PreviousScan& prev, const Eigen::Isometry3d& T_world_submap,
                     const Eigen::Vector3d& g_submap) const;

  /// T_bstart_bend, the body motion over the scan for its de-skew, from the predicted pose and
  /// velocity at its start (and the biases `bias` for preintegration). `constant_velocity`
  /// (optional): set to whether it came from the constant-velocity model.
  Eigen::Isometry3d DeskewMotion(const Scan& scan, const ScanMotionInput& motion,
                                 const Eigen::Isometry3d& T_submap_pred,
                                 const Eigen::Vector3d& v_submap_pred,
                                 const Eigen::Vector3d& g_submap, const Vector6d& bias,
                                 bool* constant_velocity = nullptr) const;

  /// Body motion over `duration` seconds at the mean velocity of the last `intervals` scan
  /// intervals (fewer at the start); empty before two poses.
  std::optional<Eigen::Isometry3d> ConstantVelocityMotion(double duration, size_t intervals) const;

  /// The optimized pose of a processed scan (keeps the last kDeskewVelocityIntervals + 1).
  void Record(Timestamp stamp, const Eigen::Isometry3d& T_submap_body);
  /// Before the first scan (at `stamp`, at the submap origin): the poses it would have had at
  /// the constant body velocity `v_submap` over the kDeskewVelocityIntervals intervals of
  /// `interval_s` before it, so that the first scans are de-skewed and predicted at it (lidar_only
  /// started from the POS's velocity). Replaces whatever was kept.
  void SeedVelocity(Timestamp stamp, const Eigen::Vector3d& v_submap, double interval_s);
  /// A new submap frame: the kept poses become T_new_old * T.
  void Reframe(const Eigen::Isometry3d& T_new_old);

 private:
  ImuPreintegration::Options imu_;
  bool use_imu_states_ = false;
  std::deque<std::pair<Timestamp, Eigen::Isometry3d>> recent_;
};

}  // namespace slam_mms::internal
