#pragma once
// On-manifold IMU preintegration (Forster, Carlone, Dellaert, Scaramuzza, T-RO 2017; paper eq 13):
// the relative motion (dR, dv, dp) between two states i and j from the IMU samples in between, with
// its 9x9 covariance and the first-order Jacobians with respect to the biases, so that a bias
// change corrects the deltas without re-integration (the paper fixes the biases; we estimate them).
//
//     dR_ij = prod_k Exp((w_k - bg) dt_k)
//     dv_ij = sum_k dR_ik (a_k - ba) dt_k
//     dp_ij = sum_k [ dv_ik dt_k + 1/2 dR_ik (a_k - ba) dt_k^2 ]                         (eq 13)
//
// Within one sample interval the specific force is rotated with the interval's mid attitude
// (dR_ik Exp(w dt / 2) instead of eq 13's dR_ik): second order, ~10x more accurate at 100 Hz.
// Error state order [dtheta (right perturbation of dR), dv, dp] everywhere in this class.
//
// Thread safety: a value type; concurrent const calls are safe, mutation needs exclusive access.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "slam_mms/core/imu_noise.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms {

using Matrix9d = Eigen::Matrix<double, 9, 9>;

/// A navigation state for prediction: world-frame position, velocity and attitude.
struct NavState {
  Eigen::Quaterniond q_world_body = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_world = Eigen::Vector3d::Zero();
};

class ImuPreintegration {
 public:
  /// IMU noise model, continuous-time densities (discrete sigma = density / sqrt(dt)).
  struct Options {
    double gyro_noise_density = 1.7e-4;   ///< Gyro white noise [rad/s/sqrt(Hz)] (~0.6 deg/sqrt(h)).
    double accel_noise_density = 2.0e-3;  ///< Accelerometer white noise [m/s^2/sqrt(Hz)].
    double gyro_bias_random_walk = 2.0e-5;   ///< Gyro bias random walk [rad/s^2/sqrt(Hz)].
    double accel_bias_random_walk = 3.0e-4;  ///< Accel bias random walk [m/s^3/sqrt(Hz)].
    double max_sample_dt_s = 0.6;            ///< Longest accepted interval of one sample [s].

    [[nodiscard]] Status Validate() const;
    /// The four densities from a datasheet (a validated spec; bias random walks from instability
    /// and correlation time).
    void SetImuNoise(const ImuNoiseSpec& spec);
  };

  ImuPreintegration();
  /// `accel_bias`, `gyro_bias`: the linearisation point of the biases (b_bar).
  ImuPreintegration(const Options& options, const Eigen::Vector3d& accel_bias_mps2,
                    const Eigen::Vector3d& gyro_bias_radps);

  /// Integrates one measurement held constant over `dt_s` (> 0, <= max_sample_dt_s).
  [[nodiscard]] Status Integrate(const Eigen::Vector3d& accel_mps2,
                                 const Eigen::Vector3d& gyro_radps, double dt_s);

  /// Integrates the samples covering [t_start, t_end]: each interval between consecutive samples
  /// uses the mean of its two end samples (second order accurate), clipped to the window; before
  /// the first / after the last sample the nearest sample is held. Samples must be time-ordered and
  /// cover the window within max_sample_dt_s.
  [[nodiscard]] Status IntegrateWindow(const std::vector<ImuSample>& samples, Timestamp t_start,
                                       Timestamp t_end);

  /// Resets the deltas to identity with a new bias linearisation point.
  void Reset(const Eigen::Vector3d& accel_bias_mps2, const Eigen::Vector3d& gyro_bias_radps);

  // ---- the deltas at the linearisation point (eq 13)
  // ---------------------------------------------
  const Eigen::Matrix3d& delta_R() const { return dR_; }
  const Eigen::Vector3d& delta_v() const { return dv_; }
  const Eigen::Vector3d& delta_p() const { return dp_; }
  double delta_t_s() const { return dt_; }
  int num_samples() const { return num_samples_; }
  /// Covariance of [dtheta, dv, dp].
  const Matrix9d& covariance() const { return cov_; }
  const Eigen::Vector3d& accel_bias_lin() const { return ba_lin_; }
  const Eigen::Vector3d& gyro_bias_lin() const { return bg_lin_; }

  // ---- bias Jacobians: d(delta)/d(bias) at the linearisation point
  // --------------------------------
  const Eigen::Matrix3d& dR_dbg() const { return dR_dbg_; }
  const Eigen::Matrix3d& dv_dba() const { return dv_dba_; }
  const Eigen::Matrix3d& dv_dbg() const { return dv_dbg_; }
  const Eigen::Matrix3d& dp_dba() const { return dp_dba_; }
  const Eigen::Matrix3d& dp_dbg() const { return dp_dbg_; }

  /// Deltas corrected to first order for biases (ba, bg) instead of the linearisation point.
  Eigen::Matrix3d CorrectedDeltaR(const Eigen::Vector3d& gyro_bias_radps) const;
  Eigen::Vector3d CorrectedDeltaV(const Eigen::Vector3d& accel_bias_mps2,
                                  const Eigen::Vector3d& gyro_bias_radps) const;
  Eigen::Vector3d CorrectedDeltaP(const Eigen::Vector3d& accel_bias_mps2,
                                  const Eigen::Vector3d& gyro_bias_radps) const;

  /// The state j predicted from state i (gravity vector g_world, e.g. (0, 0, -9.80665)), with
  /// the biases at their linearisation point:
  ///   R_j = R_i dR, v_j = v_i + g dt + R_i dv, p_j = p_i + v_i dt + 1/2 g dt^2 + R_i dp.
  NavState Predict(const NavState& state_i, const Eigen::Vector3d& g_world) const;
  /// The same from a pose T_frame_body and velocity v_frame (in `frame`, gravity g_frame there).
  NavState Predict(const Eigen::Isometry3d& T_frame_body, const Eigen::Vector3d& v_frame,
                   const Eigen::Vector3d& g_frame) const;

  const Options& options() const { return options_; }

 private:
  Options options_;
  Eigen::Vector3d ba_lin_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg_lin_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d dR_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d dv_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d dp_ = Eigen::Vector3d::Zero();
  double dt_ = 0.0;
  int num_samples_ = 0;
  Matrix9d cov_ = Matrix9d::Zero();
  Eigen::Matrix3d dR_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dba_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dba_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dbg_ = Eigen::Matrix3d::Zero();
};

}  // namespace slam_mms
