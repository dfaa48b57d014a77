#pragma once
// InsFilter::Impl: the error-state EKF's state and its prediction, update and reset steps, shared
// by ins_filter.cpp (options, initialisation, the data API, state queries). Private to the ins
// module.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>
#include <vector>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/ins/ins_filter.hpp"

namespace slam_mms {
namespace ins_detail {

// Error-state indices.
constexpr int kP = 0, kV = 3, kTh = 6, kBa = 9, kBg = 12, kBn = 15, kM = 18, kL = 20;
constexpr int kN = kInsErrorDim;
// Variance of b_gnss while the solution type's errors are white (kept positive for the smoother).
constexpr double kWhiteBiasVariance = 1e-10;
// Variance of the misalignment where it is not estimated (positive for the smoother) [rad^2].
constexpr double kFixedMisalignmentVariance = 1e-12;
// Variance of the lateral motion model where it is not estimated (positive for the smoother).
constexpr double kFixedLateralModelVariance = 1e-12;

inline bool PositiveFinite(double x) { return std::isfinite(x) && x > 0.0; }

struct Nominal {
  Timestamp stamp;
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();  // R_world_body
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();
  Eigen::Vector3d bn = Eigen::Vector3d::Zero();  // GNSS position bias (world)
  Eigen::Vector2d m = Eigen::Vector2d::Zero();   // IMU-to-vehicle misalignment (pitch, yaw)
  Eigen::Vector2d l = Eigen::Vector2d::Zero();   // lateral model (lever arm [m], sideslip)
};

// R_body_vehicle of the misalignment (pitch about body y, yaw about body z).
inline Eigen::Matrix3d BodyToVehicleRotation(const Eigen::Vector2d& m) {
  return so3::Exp(Eigen::Vector3d(0.0, m.x(), m.y()));
}

struct HistoryEntry {
  Nominal x;
  Matrix6d cov_pose;  // rotation first, right perturbation of T_world_body
};

// 6x6 pose covariance [omega, v_body] from the 18x18 [dp_world, dv, dtheta, ...]:
// T_hat Exp([w; rho]) = (R Exp(w), p + R rho) -> w = dtheta, rho = R^T dp.
inline Matrix6d PoseCovariance(const InsErrorMatrix& P, const Eigen::Matrix3d& R) {
  Eigen::Matrix<double, 6, kN> J = Eigen::Matrix<double, 6, kN>::Zero();
  J.block<3, 3>(0, kTh) = Eigen::Matrix3d::Identity();
  J.block<3, 3>(3, kP) = R.transpose();
  return J * P * J.transpose();
}

inline InsState ToInsState(const HistoryEntry& e) {
  InsState s;
  s.stamp = e.x.stamp;
  s.T_world_body = MakeIsometry(e.x.q.normalized(), e.x.p);
  s.v_world_mps = e.x.v;
  s.cov_T_world_body = e.cov_pose;
  s.accel_bias_mps2 = e.x.ba;
  s.gyro_bias_radps = e.x.bg;
  return s;
}

enum class Mode { kNone, kImu, kExternal };

}  // namespace ins_detail

// The filter's two files only (this header is private): the error-state layout and helpers
// unqualified, as in the equations.
using namespace ins_detail;  // NOLINT(google-build-using-namespace)

struct InsFilter::Impl {
  Options options;
  GnssPrior gnss;
  Mode mode = Mode::kNone;
  bool initialized = false;
  std::optional<Eigen::Quaterniond> pending_q;  // attitude waiting for a GNSS position
  Eigen::Vector3d pending_v = Eigen::Vector3d::Zero();
  Eigen::Vector3d pending_bg = Eigen::Vector3d::Zero();
  std::optional<Timestamp> pending_stamp;  // when pending_q / pending_v hold (carried by the IMU)
  // The stated 1-sigma roll, pitch, yaw of pending_q at pending_from (InitializeAttitude's
  // sigma_rpy_rad); empty: the options' init sigmas.
  std::optional<Eigen::Vector3d> pending_sigma_rpy;
  std::optional<Timestamp> pending_from;
  Nominal x;
  InsErrorMatrix P = InsErrorMatrix::Zero();
  std::optional<ImuSample> last_imu;
  std::deque<HistoryEntry> history;
  // MarkAttitudeEpoch: Cov(dx, dtheta at the epoch), transformed with every transition of P.
  struct AttitudeEpoch {
    Timestamp stamp;
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
    Eigen::Matrix3d cov = Eigen::Matrix3d::Identity();
    Eigen::Matrix<double, kN, 3> cross = Eigen::Matrix<double, kN, 3>::Zero();
  };
  std::optional<AttitudeEpoch> attitude_epoch;
  // Smoother record (options.record_steps): the transition since the last recorded step.
  std::vector<InsFilterStep> steps;
  InsErrorMatrix F_since_step = InsErrorMatrix::Identity();
  bool propagated_since_step = false;
  // GNSS error model: the solution type b_gnss belongs to (-1: none yet), its stationary
  // covariance and correlation time, the last used fix.
  int bias_model = -1;
  Eigen::Matrix3d bias_cov = kWhiteBiasVariance * Eigen::Matrix3d::Identity();
  double bias_tau_s = 30.0;
  std::optional<Timestamp> last_used_fix;
  // Motion constraints: the stationarity detector's window, the ZARU accumulator.
  std::deque<ImuSample> still_window;
  std::optional<Timestamp> last_zupt, last_nhc, zaru_start;
  Eigen::Vector3d zaru_sum = Eigen::Vector3d::Zero();
  int zaru_n = 0;
  int num_zupt = 0;
  bool nhc_refusal_logged = false;    // the first refusal of the NHC is logged, not every one
  bool misalignment_logged = false;   // the first settled misalignment estimate is logged
  bool lateral_model_logged = false;  // likewise the lateral model's

  static int ModelIndex(GnssFixType t) { return GnssSolutionClass(t); }
  const Options::GnssErrorModel& ErrorModel(int index) const {
    return index == 0   ? options.gnss_error_rtk_fixed
           : index == 1 ? options.gnss_error_rtk_float
                        : options.gnss_error_code;
  }

  // b_gnss's stationary covariance for a fix of this model: the correlated share of its measured
  // covariance C (the fix type's weight included, the innovation test's inflation not); a
  // negligible one where the model's errors are white.
  static Eigen::Matrix3d BiasCovariance(const Options::GnssErrorModel& em, const Eigen::Matrix3d& C,
                                        double innovation_weight) {
    if (!(em.correlated_fraction > 0.0)) return kWhiteBiasVariance * Eigen::Matrix3d::Identity();
    return em.correlated_fraction * C / innovation_weight;
  }

  // Whether a new GNSS solution can start at the current stamp: not where the recorded step
  // there already holds an update (its transition cannot be put before that update).
  bool CanStartSolutionHere() const {
    return !(options.record_steps && !steps.empty() && steps.back().stamp == x.stamp &&
             steps.back().updated);
  }

  // Clears the GNSS-model and constraint state (a new initialisation).
  void ResetAuxiliary() {
    x.bn.setZero();
    x.m = Eigen::Vector2d(options.vehicle_pitch_misalignment_rad,
                          options.vehicle_yaw_misalignment_rad);
    x.l = Eigen::Vector2d(options.vehicle_lever_arm_m, options.vehicle_sideslip_rad_per_mps2);
    bias_model = -1;
    bias_cov = kWhiteBiasVariance * Eigen::Matrix3d::Identity();
    last_used_fix.reset();
    still_window.clear();
    last_zupt.reset();
    last_nhc.reset();
    zaru_start.reset();
    zaru_sum.setZero();
    zaru_n = 0;
  }

  Eigen::Vector3d g() const {
    double gm = options.gravity_mps2;
    if (!(gm > 0.0)) {
      const GeodeticPoint o = gnss.origin();
      gm = gnss.has_origin() ? NormalGravity(o.latitude_deg, o.height_m) : 9.80665;
    }
    return Eigen::Vector3d(0.0, 0.0, -gm);
  }

  /// `sigma_rpy`: the attitude's stated roll, pitch, yaw sigmas [rad] (else the options').
  void InitCovariance(double sigma_p_h, double sigma_p_v,
                      const std::optional<Eigen::Vector3d>& sigma_rpy = std::nullopt) {
    attitude_epoch.reset();
    P.setZero();
    P.block<3, 3>(kP, kP).diagonal() << sigma_p_h * sigma_p_h, sigma_p_h * sigma_p_h,
        sigma_p_v * sigma_p_v;
    P.block<3, 3>(kV, kV).diagonal().setConstant(std::pow(options.init_sigma_velocity_mps, 2));
    // Roll/pitch/yaw sigmas mapped into the body-frame right perturbation approximately: the yaw
    // uncertainty is about world z, i.e. R^T z in body.
    const Eigen::Matrix3d R = x.q.toRotationMatrix();
    const double srp = options.init_sigma_roll_pitch_rad, sy = options.init_sigma_yaw_rad;
    const Eigen::Vector3d s = sigma_rpy.value_or(Eigen::Vector3d(srp, srp, sy));
    const Eigen::Matrix3d cov_world = s.cwiseAbs2().asDiagonal();
    P.block<3, 3>(kTh, kTh) = R.transpose() * cov_world * R;
    P.block<3, 3>(kBa, kBa).diagonal().setConstant(std::pow(options.init_sigma_accel_bias_mps2, 2));
    P.block<3, 3>(kBg, kBg).diagonal().setConstant(std::pow(options.init_sigma_gyro_bias_radps, 2));
    P.block<3, 3>(kBn, kBn) = bias_cov;
    P.block<2, 2>(kM, kM).diagonal().setConstant(MisalignmentVariance());
    P.block<2, 2>(kL, kL).diagonal() = LateralModelVariance();
  }

  // The misalignment is estimated where the constraint is on and its sigma positive.
  bool EstimatesMisalignment() const {
    return options.nhc_sigma_mps > 0.0 && options.vehicle_misalignment_sigma_rad > 0.0;
  }
  double MisalignmentVariance() const {
    return EstimatesMisalignment() ? std::pow(options.vehicle_misalignment_sigma_rad, 2)
                                   : kFixedMisalignmentVariance;
  }
  // The lateral model's sigmas (lever arm, sideslip) where each is estimated (the constraint on,
  // the sigma positive); 0 where the given value is exact.
  Eigen::Vector2d LateralModelSigmas() const {
    if (!(options.nhc_sigma_mps > 0.0)) return Eigen::Vector2d::Zero();
    return Eigen::Vector2d(options.vehicle_lever_arm_sigma_m,
                           options.vehicle_sideslip_sigma_rad_per_mps2);
  }
  Eigen::Vector2d LateralModelVariance() const {
    const Eigen::Vector2d s = LateralModelSigmas();
    return (s.array() > 0.0).select(s.array().square(), kFixedLateralModelVariance).matrix();
  }

  // A new GNSS solution starts: b_gnss restarts from zero with the stationary covariance `cov`
  // (its block of the transition is zero). Recorded as part of the propagation to this stamp:
  // AddGnss has recorded the step at x.stamp, which holds no update yet (CanStartSolutionHere).
  void ResetBias(const Eigen::Matrix3d& cov, double tau_s) {
    InsErrorMatrix Fr = InsErrorMatrix::Identity();
    Fr.block<3, 3>(kBn, kBn).setZero();
    P = Fr * P * Fr.transpose();
    P.block<3, 3>(kBn, kBn) = cov;
    if (attitude_epoch) attitude_epoch->cross = Fr * attitude_epoch->cross;
    x.bn.setZero();
    bias_cov = cov;
    bias_tau_s = tau_s;
    if (options.record_steps) {
      InsFilterStep& st = steps.back();
      st.F = Fr * st.F;
      st.P_prior = st.P_posterior = P;
      st.gnss_bias_prior = st.gnss_bias_posterior = x.bn;
    }
  }

  // EKF update with the innovation z - h(x) = H dx + n, n ~ N(0, Rm) (Joseph form), the
  // injection into the nominal state and the reset Jacobian of the attitude error.
  template <int M>
  void Update(const Eigen::Matrix<double, M, kN>& H, const Eigen::Matrix<double, M, 1>& innovation,
              const Eigen::Matrix<double, M, M>& Rm) {
    const Eigen::Matrix<double, M, M> S = H * P * H.transpose() + Rm;
    const Eigen::Matrix<double, kN, M> K = S.ldlt().solve(H * P).transpose();
    const InsErrorVector dx = K * innovation;
    const InsErrorMatrix IKH = InsErrorMatrix::Identity() - K * H;
    P = IKH * P * IKH.transpose() + K * Rm * K.transpose();
    const Eigen::Matrix3d R = x.q.toRotationMatrix();
    x.p += dx.template segment<3>(kP);
    x.v += dx.template segment<3>(kV);
    const Eigen::Vector3d dth = dx.template segment<3>(kTh);
    x.q = Eigen::Quaterniond(R * so3::Exp(dth)).normalized();
    x.ba += dx.template segment<3>(kBa);
    x.bg += dx.template segment<3>(kBg);
    x.bn += dx.template segment<3>(kBn);
    x.m += dx.template segment<2>(kM);
    x.l += dx.template segment<2>(kL);
    InsErrorMatrix G = InsErrorMatrix::Identity();
    G.block<3, 3>(kTh, kTh) -= 0.5 * so3::Hat(dth);
    P = G * P * G.transpose();
    P = 0.5 * (P + P.transpose());
    // The filtered error after the update, G ((I - K H) dx - K n), n independent of the past.
    if (attitude_epoch) attitude_epoch->cross = G * (IKH * attitude_epoch->cross);
  }

  // Zero-velocity update (+ gyro bias from the mean rate) while the IMU is still and the speed
  // low; the non-holonomic constraint while moving. After the propagation to `sample`.
  void ApplyMotionConstraints(const ImuSample& sample) {
    const Timestamp t = sample.stamp;
    bool still = false;
    if (options.zupt) {
      still_window.push_back(sample);
      while (!still_window.empty() &&
             t.SecondsSince(still_window.front().stamp) > options.zupt_window_s + 1e-9) {
        still_window.pop_front();
      }
      const double span = t.SecondsSince(still_window.front().stamp);
      still = still_window.size() >= 3 && span >= 0.8 * options.zupt_window_s &&
              x.v.norm() < options.zupt_max_speed_mps;
      const Eigen::Matrix3d R = x.q.toRotationMatrix();
      for (size_t i = 0; still && i < still_window.size(); ++i) {
        const ImuSample& s = still_window[i];
        still = (s.gyro_radps - x.bg).norm() < options.zupt_max_gyro_radps &&
                (R * (s.accel_mps2 - x.ba) + g()).norm() < options.zupt_max_accel_mps2;
      }
    }
    if (!still) {
      zaru_start.reset();
      zaru_sum.setZero();
      zaru_n = 0;
    } else {
      if (!zaru_start) zaru_start = t;
      zaru_sum += sample.gyro_radps;
      ++zaru_n;
      if (!last_zupt || t.SecondsSince(*last_zupt) >= options.zupt_interval_s - 1e-9) {
        // Rows 0-2: v = 0; rows 3-5 (with >= 2 samples): mean rate = bg.
        const bool zaru = zaru_n >= 2;
        Eigen::Matrix<double, 6, kN> H = Eigen::Matrix<double, 6, kN>::Zero();
        Eigen::Matrix<double, 6, 1> z = Eigen::Matrix<double, 6, 1>::Zero();
        Eigen::Matrix<double, 6, 6> Rm = Eigen::Matrix<double, 6, 6>::Identity();
        H.block<3, 3>(0, kV).setIdentity();
        z.head<3>() = -x.v;
        // Likewise a velocity the detector cannot see: up to zupt_max_accel_mps2 over the window.
        const double dv_max = options.zupt_max_accel_mps2 * options.zupt_window_s;
        Rm.topLeftCorner<3, 3>() *=
            options.zupt_sigma_mps * options.zupt_sigma_mps + dv_max * dv_max / 3.0;
        if (zaru) {
          const double T = std::max(t.SecondsSince(*zaru_start), 1e-3);
          H.block<3, 3>(3, kBg).setIdentity();
          z.tail<3>() = zaru_sum / zaru_n - x.bg;
          // The detector cannot tell a rate below its threshold from none: the vehicle's own
          // residual rate (rocking, a real OXTS's standing jitter of up to 0.015 rad/s) is
          // taken as uniform within it, not as bias (else the bias follows it and the attitude
          // stops following the vehicle).
          const double rate_var = options.zupt_max_gyro_radps * options.zupt_max_gyro_radps / 3.0;
          Rm.bottomRightCorner<3, 3>() *=
              options.gyro_noise_density * options.gyro_noise_density / T + rate_var;
          Update<6>(H, z, Rm);
        } else {
          Update<3>(H.topRows<3>(), z.head<3>(), Rm.topLeftCorner<3, 3>());
        }
        ++num_zupt;
        last_zupt = t;
        zaru_start = t;
        zaru_sum.setZero();
        zaru_n = 0;
        Record();
      }
      return;
    }
    if (options.nhc_sigma_mps > 0.0 && x.v.norm() > options.nhc_min_speed_mps &&
        (!last_nhc || t.SecondsSince(*last_nhc) >= options.zupt_interval_s - 1e-9)) {
      // The vehicle's velocity v_veh = M^T R^T v, M = R_body_vehicle:
      // ~ v_veh_hat + M^T R_hat^T dv + M^T [R_hat^T v_hat]x dtheta + [v_veh_hat]x (0, dm);
      // rows y, z. What the lateral model allows of them at the IMU (rate w in the vehicle
      // frame, lever l0, sideslip l1): (l0 w_z + l1 v_x^2 w_z, -l0 w_y); the constraint is their
      // difference = 0. Its dependence on v_x and on the gyro bias (through w) is left out:
      // l1 v_x w_z and l0 * bg are second order.
      const Eigen::Matrix3d Mt = BodyToVehicleRotation(x.m).transpose();
      const Eigen::Matrix3d Rt = x.q.toRotationMatrix().transpose();
      const Eigen::Vector3d vb = Rt * x.v;
      const Eigen::Vector3d vv = Mt * vb;
      const Eigen::Vector3d wv = Mt * (sample.gyro_radps - x.bg);
      const Eigen::Vector2d d_lever(wv.z(), -wv.y());
      const Eigen::Vector2d d_slip(vv.x() * vv.x() * wv.z(), 0.0);
      Eigen::Matrix<double, 3, kN> J = Eigen::Matrix<double, 3, kN>::Zero();
      J.block<3, 3>(0, kV) = Mt * Rt;
      J.block<3, 3>(0, kTh) = Mt * so3::Hat(vb);
      if (EstimatesMisalignment()) J.block<3, 2>(0, kM) = so3::Hat(vv).rightCols<2>();
      Eigen::Matrix<double, 2, kN> H = J.bottomRows<2>();
      // The given values stay exact where not estimated (as the misalignment's).
      const Eigen::Vector2d lateral_sigmas = LateralModelSigmas();
      if (lateral_sigmas.x() > 0.0) H.col(kL) = -d_lever;
      if (lateral_sigmas.y() > 0.0) H.col(kL + 1) = -d_slip;
      const Eigen::Vector2d z = x.l.x() * d_lever + x.l.y() * d_slip - vv.tail<2>();
      // A correlated error as the white noise of its low-frequency spectral density (the
      // interval since the last update, refused ones included, at least the nominal one).
      const double dt_nhc =
          std::max(last_nhc ? t.SecondsSince(*last_nhc) : 0.0, options.zupt_interval_s);
      const Eigen::Vector2d tau(options.nhc_lateral_correlation_time_s,
                                options.nhc_vertical_correlation_time_s);
      const Eigen::Vector2d correlation_factor = (2.0 * tau / std::max(dt_nhc, 1e-3)).cwiseMax(1.0);
      const Eigen::Matrix2d Rm = Eigen::Matrix2d(
          (options.nhc_sigma_mps * options.nhc_sigma_mps * correlation_factor).asDiagonal());
      last_nhc = t;
      // The innovation test: where the vehicle does not keep to its x axis (not a car, a skid,
      // an IMU mounted otherwise, broken input motion), the constraint is refused rather than
      // pulled against the GNSS (chi-square, 2 dof, 99.9 %).
      constexpr double kNhcGateChi2 = 13.82;
      const Eigen::Matrix2d S = H * P * H.transpose() + Rm;
      if (z.dot(S.ldlt().solve(z)) > kNhcGateChi2) {
        if (!nhc_refusal_logged) {
          nhc_refusal_logged = true;
          SLAM_MMS_LOG(kInfo) << "InsFilter: the non-holonomic constraint does not hold (vehicle "
                              << "y/z velocity " << -z.x() << " / " << -z.y()
                              << " m/s beyond the lateral model): refused where it fails its "
                              << "innovation test";
        }
        return;
      }
      Update<2>(H, z, Rm);
      Record();
      if (EstimatesMisalignment() && !misalignment_logged) {
        // Once both angles are known to 0.1 deg: what the user's mounting calibration is.
        const Eigen::Vector2d sigma = P.block<2, 2>(kM, kM).diagonal().cwiseSqrt();
        if (sigma.maxCoeff() < 0.1 * M_PI / 180.0) {
          misalignment_logged = true;
          SLAM_MMS_LOG(kInfo) << "InsFilter: IMU-to-vehicle misalignment pitch "
                              << x.m.x() * 180.0 / M_PI << " +- " << sigma.x() * 180.0 / M_PI
                              << " deg, yaw " << x.m.y() * 180.0 / M_PI << " +- "
                              << sigma.y() * 180.0 / M_PI << " deg";
        }
      }
      if (!lateral_model_logged && lateral_sigmas.x() > 0.0) {
        // Once the lever arm is known to 0.1 m.
        const Eigen::Vector2d sigma_l = P.block<2, 2>(kL, kL).diagonal().cwiseSqrt();
        if (sigma_l.x() < 0.1) {
          lateral_model_logged = true;
          SLAM_MMS_LOG(kInfo) << "InsFilter: the IMU is " << x.l.x() << " +- " << sigma_l.x()
                              << " m ahead of the vehicle's non-holonomic point; sideslip "
                              << x.l.y() << " +- " << sigma_l.y() << " rad/(m/s^2)";
        }
      }
    }
  }

  void Record() {
    HistoryEntry e{x, PoseCovariance(P, x.q.toRotationMatrix())};
    if (options.record_steps) RecordStep(e);
    if (!history.empty() && history.back().x.stamp == x.stamp) {
      history.back() = e;
    } else {
      history.push_back(e);
    }
    while (history.size() > 2 &&
           history.back().x.stamp.SecondsSince(history.front().x.stamp) > options.history_s) {
      history.pop_front();
    }
  }

  // A propagation starts a new step; an update (no propagation since) rewrites the last step's
  // a-posteriori part. Initialisation clears the record first (history.empty()).
  void RecordStep(const HistoryEntry& e) {
    if (history.empty()) steps.clear();
    if (steps.empty() || propagated_since_step) {
      InsFilterStep st;
      st.stamp = x.stamp;
      st.prior = ToInsState(e);
      st.posterior = st.prior;
      st.P_prior = P;
      st.P_posterior = P;
      st.gnss_bias_prior = st.gnss_bias_posterior = x.bn;
      st.vehicle_misalignment_prior = st.vehicle_misalignment_posterior = x.m;
      st.vehicle_lateral_model_prior = st.vehicle_lateral_model_posterior = x.l;
      st.F = steps.empty() ? InsErrorMatrix::Identity() : F_since_step;
      steps.push_back(st);
    } else {
      InsFilterStep& st = steps.back();
      st.posterior = ToInsState(e);
      st.P_posterior = P;
      st.gnss_bias_posterior = x.bn;
      st.vehicle_misalignment_posterior = x.m;
      st.vehicle_lateral_model_posterior = x.l;
      st.updated = true;
    }
    F_since_step.setIdentity();
    propagated_since_step = false;
  }

  // Nominal + covariance propagation over dt with bias-corrected mean measurements.
  void Propagate(const Eigen::Vector3d& accel, const Eigen::Vector3d& gyro, double dt) {
    const Eigen::Vector3d a = accel - x.ba;
    const Eigen::Vector3d w = gyro - x.bg;
    const Eigen::Matrix3d R = x.q.toRotationMatrix();
    const Eigen::Vector3d phi = w * dt;
    const Eigen::Matrix3d dR = so3::Exp(phi);
    const Eigen::Matrix3d R_mid = R * so3::Exp(0.5 * phi);
    const Eigen::Vector3d acc_world = R_mid * a + g();
    const double dt2 = dt * dt;

    InsErrorMatrix F = InsErrorMatrix::Identity();
    const Eigen::Matrix3d a_hat = so3::Hat(a);
    F.block<3, 3>(kP, kV) = Eigen::Matrix3d::Identity() * dt;
    F.block<3, 3>(kP, kTh) = -0.5 * R_mid * a_hat * dt2;
    F.block<3, 3>(kP, kBa) = -0.5 * R_mid * dt2;
    F.block<3, 3>(kV, kTh) = -R_mid * a_hat * dt;
    F.block<3, 3>(kV, kBa) = -R_mid * dt;
    F.block<3, 3>(kTh, kTh) = dR.transpose();
    F.block<3, 3>(kTh, kBg) = -so3::RightJacobian(phi) * dt;
    const double e_bn = std::exp(-dt / bias_tau_s);
    F.block<3, 3>(kBn, kBn) *= e_bn;
    InsErrorMatrix Q = InsErrorMatrix::Zero();
    const double qa = std::pow(options.accel_noise_density, 2) * dt;
    const double qg = std::pow(options.gyro_noise_density, 2) * dt;
    Q.block<3, 3>(kP, kP).diagonal().setConstant(qa * dt2 / 3.0);
    Q.block<3, 3>(kP, kV).diagonal().setConstant(qa * dt / 2.0);
    Q.block<3, 3>(kV, kP).diagonal().setConstant(qa * dt / 2.0);
    Q.block<3, 3>(kV, kV).diagonal().setConstant(qa);
    Q.block<3, 3>(kTh, kTh).diagonal().setConstant(qg);
    Q.block<3, 3>(kBa, kBa).diagonal().setConstant(std::pow(options.accel_bias_random_walk, 2) *
                                                   dt);
    Q.block<3, 3>(kBg, kBg).diagonal().setConstant(std::pow(options.gyro_bias_random_walk, 2) * dt);
    Q.block<3, 3>(kBn, kBn) = (1.0 - e_bn * e_bn) * bias_cov;
    P = F * P * F.transpose() + Q;
    P = 0.5 * (P + P.transpose());
    if (attitude_epoch) attitude_epoch->cross = F * attitude_epoch->cross;
    if (options.record_steps) {
      F_since_step = F * F_since_step;
      propagated_since_step = true;
    }

    x.p += x.v * dt + 0.5 * acc_world * dt2;
    x.v += acc_world * dt;
    x.q = Eigen::Quaterniond(R * dR).normalized();
    x.bn *= e_bn;
  }

  // Nominal-only prediction with a held sample (for extrapolated queries).
  static Nominal Extrapolate(Nominal n, const ImuSample& s, const Eigen::Vector3d& g, double dt) {
    const Eigen::Vector3d a = s.accel_mps2 - n.ba;
    const Eigen::Vector3d w = s.gyro_radps - n.bg;
    const Eigen::Matrix3d R = n.q.toRotationMatrix();
    const Eigen::Vector3d acc_world = R * so3::Exp(0.5 * w * dt) * a + g;
    n.p += n.v * dt + 0.5 * acc_world * dt * dt;
    n.v += acc_world * dt;
    n.q = Eigen::Quaterniond(R * so3::Exp(w * dt)).normalized();
    n.stamp = n.stamp.PlusSeconds(dt);
    return n;
  }
};

}  // namespace slam_mms
