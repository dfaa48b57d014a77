#pragma once
// MotionInputBuilder: MappingSystem's choice of level 1's motion input for a scan (issue #19, part
// 2): F_Odom from the POS while GNSS holds it and the POS did not jump, else IMU preintegration
// (F_Prein) over the IMU samples since the previous scan, else constant velocity; constant
// velocity throughout in lidar_only.
//
// A POS "jump" is a correction (GNSS back after an outage, float -> fixed) that moves the POS
// farther than its own IMU measured: more than max_pos_jump_m or max_pos_jump_rad from the
// previous scan's start to this one's, or within this scan. Its relative motion then is no
// odometry measurement, and that interval uses F_Prein. Only checked where IMU samples cover the
// interval.
//
// Ownership: holds the previous scan's POS state and the jump count. Thread safety: not
// thread-safe.

#include <Eigen/Core>
#include <optional>
#include <utility>

#include "pipeline/sensor_buffer.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/pipeline/localizer.hpp"

namespace slam_mms::internal {

class MotionInputBuilder {
 public:
  struct Context {
    bool lidar_only = false;
    /// F_Odom is allowed: GNSS is available at the scan (or the POS is external, valid anyway).
    bool gnss_valid = false;
    /// The motion input's gravity (world).
    Eigen::Vector3d g_world = Eigen::Vector3d(0.0, 0.0, -9.80665);
    /// The POS filter's gravity, for the jump check.
    Eigen::Vector3d g_pos = Eigen::Vector3d(0.0, 0.0, -9.80665);
    /// Start of the preintegration window: the previous processed scan's start (or this one's).
    Timestamp imu_from;
    /// lidar_only's first scan: the POS velocity it starts from (Level1Options::
    /// lidar_only_initial_velocity); empty: none.
    std::optional<Eigen::Vector3d> lidar_only_initial_v_world;
  };

  MotionInputBuilder() = default;
  MotionInputBuilder(double max_pos_jump_m, double max_pos_jump_rad)
      : max_jump_m_(max_pos_jump_m), max_jump_rad_(max_pos_jump_rad) {}

  /// The motion input of `scan` from the POS states at its start and end (either may be an
  /// error: no POS there) and the IMU samples of `imu`.
  ScanMotionInput Build(const Scan& scan, const StatusOr<InsState>& s0,
                        const StatusOr<InsState>& s1, const Context& context,
                        const SensorBuffer& imu);
  /// After a scan was processed: the POS state at its start (empty: none).
  void SetPrevious(std::optional<InsState> s0) { prev_pos_ = std::move(s0); }

  /// How far the POS moved from `a` to `b` beyond what its IMU (biases of `a`) measured between
  /// them: position [m], rotation [rad]; empty where the IMU does not cover [a, b].
  static std::optional<std::pair<double, double>> PosJump(const InsState& a, const InsState& b,
                                                          const SensorBuffer& imu,
                                                          const Eigen::Vector3d& g_pos);
  /// Scan intervals where the POS jumped.
  int num_pos_jumps() const { return pos_jumps_; }

 private:
  bool PosJumped(const Scan& scan, const InsState& s0, const InsState& s1, const SensorBuffer& imu,
                 const Eigen::Vector3d& g_pos);

  double max_jump_m_ = 0.06;
  double max_jump_rad_ = 0.006;
  std::optional<InsState> prev_pos_;
  int pos_jumps_ = 0;
};

}  // namespace slam_mms::internal
