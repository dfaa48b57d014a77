// PosSmoother: the RTS backward pass equals the batch least-squares solution of a linear model, and
// on a noisy simulated drive with a 60 s GNSS outage the smoothed error inside the outage is far
// below the forward filter's.
#include "ins/pos_smoother.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cstdio>
#include <random>

#include "ins/synthetic_drive.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms {
namespace {

constexpr int kN = kInsErrorDim;
using VectorNd = InsErrorVector;
using testing::SyntheticDrive;
using testing::TruthState;

using testing::kOrigin;
using testing::kT0;

// The linear state x = [p, v, theta, ba, bg, bn, m] as a nominal InsState (bn, m: the step's GNSS
// bias and IMU-to-vehicle misalignment).
// theta stays exactly zero in the linear test (decoupled and never measured), so the filter's
// right-perturbation error on it is linear too.
InsState ToState(const VectorNd& x, Timestamp stamp) {
  InsState s;
  s.stamp = stamp;
  s.T_world_body = MakeIsometry(so3::Exp(x.segment<3>(6)), x.head<3>());
  s.v_world_mps = x.segment<3>(3);
  s.accel_bias_mps2 = x.segment<3>(9);
  s.gyro_bias_radps = x.segment<3>(12);
  return s;
}

// The 15 nominal components (the smoother returns InsStates, without the GNSS bias and the
// misalignment).
Eigen::Matrix<double, 15, 1> FromState(const InsState& s) {
  Eigen::Matrix<double, 15, 1> x;
  x << s.T_world_body.translation(), s.v_world_mps, so3::Log(s.T_world_body.linear()),
      s.accel_bias_mps2, s.gyro_bias_radps;
  return x;
}

TEST(PosSmootherTest, RtsEqualsBatchLeastSquaresOnALinearModel) {
  // x_{k+1} = F x_k + w (p += v dt, v -= ba dt, random walks), z_k = H x_k + n with H observing
  // position and (every third step) velocity; some steps without a measurement.
  constexpr int kSteps = 25;
  const double dt = 0.1;
  InsErrorMatrix F = InsErrorMatrix::Identity();
  F.block<3, 3>(0, 3) = dt * Eigen::Matrix3d::Identity();
  F.block<3, 3>(3, 9) = -dt * Eigen::Matrix3d::Identity();
  F(0, 12) = 0.05;               // a gyro-bias coupling, so every block is exercised
  F.block<3, 3>(15, 15) *= 0.9;  // the GNSS bias: Gauss-Markov
  F(4, 19) = 0.1;                // the misalignment (a random constant) couples into a velocity
  F(5, 20) = 0.05;               // and the lateral model (random constants)
  VectorNd q_diag;
  q_diag << Eigen::Vector3d::Constant(1e-4), Eigen::Vector3d::Constant(4e-3),
      Eigen::Vector3d::Constant(1e-6), Eigen::Vector3d::Constant(1e-5),
      Eigen::Vector3d::Constant(1e-8), Eigen::Vector3d::Constant(2e-3), Eigen::Vector2d(1e-9, 1e-9),
      Eigen::Vector2d(1e-9, 1e-9);
  const InsErrorMatrix Q = q_diag.asDiagonal();
  VectorNd p0_diag;
  p0_diag << Eigen::Vector3d::Constant(0.25), Eigen::Vector3d::Constant(0.04),
      Eigen::Vector3d::Constant(1e-4), Eigen::Vector3d::Constant(1e-3),
      Eigen::Vector3d::Constant(1e-6), Eigen::Vector3d::Constant(0.01), Eigen::Vector2d(3e-4, 3e-4),
      Eigen::Vector2d(0.5, 1e-4);
  const InsErrorMatrix P0 = p0_diag.asDiagonal();
  VectorNd m0 = VectorNd::Zero();
  m0.head<6>() << 1.0, -2.0, 0.5, 10.0, 0.3, -0.1;

  std::mt19937 rng(7);
  std::normal_distribution<double> n01(0.0, 1.0);
  auto randn = [&](int n) {
    Eigen::VectorXd v(n);
    for (int i = 0; i < n; ++i) v(i) = n01(rng);
    return v;
  };
  // Truth and measurements.
  std::vector<VectorNd> truth(kSteps);
  truth[0] = m0 + p0_diag.cwiseSqrt().cwiseProduct(randn(kN));
  truth[0].segment<3>(6).setZero();
  for (int k = 1; k < kSteps; ++k) {
    truth[k] = F * truth[k - 1] + q_diag.cwiseSqrt().cwiseProduct(randn(kN));
    truth[k].segment<3>(6).setZero();
  }
  struct Meas {
    Eigen::MatrixXd H;
    Eigen::VectorXd z;
    Eigen::MatrixXd R;
  };
  std::vector<std::optional<Meas>> meas(kSteps);
  for (int k = 0; k < kSteps; ++k) {
    if (k % 5 == 2) continue;  // no fix at these steps
    const int m = (k % 3 == 0) ? 6 : 3;
    Meas z;
    z.H = Eigen::MatrixXd::Zero(m, kN);
    z.H.leftCols(m).setIdentity();
    z.H.block<3, 3>(0, 15).setIdentity();  // the position fix holds the GNSS bias
    if (m == 6) {
      // As the NHC does: the misalignment and the lateral model in the velocity rows.
      z.H.block<2, 2>(4, 18) = 5.0 * Eigen::Matrix2d::Identity();
      z.H.block<2, 2>(4, 20) << -0.3, -20.0, 0.1, 0.0;
    }
    z.R = Eigen::MatrixXd::Identity(m, m) * 0.01;
    z.z = z.H * truth[k] + 0.1 * randn(m);
    meas[k] = z;
  }

  // Forward Kalman filter, recorded as InsFilter would.
  std::vector<InsFilterStep> steps;
  VectorNd x = m0;
  InsErrorMatrix P = P0;
  for (int k = 0; k < kSteps; ++k) {
    InsFilterStep st;
    st.stamp = kT0.PlusSeconds(k * dt);
    if (k > 0) {
      x = F * x;
      P = F * P * F.transpose() + Q;
      st.F = F;
    }
    st.prior = ToState(x, st.stamp);
    st.gnss_bias_prior = x.segment<3>(15);
    st.vehicle_misalignment_prior = x.segment<2>(18);
    st.vehicle_lateral_model_prior = x.tail<2>();
    st.P_prior = P;
    if (meas[k]) {
      const Meas& z = *meas[k];
      const Eigen::MatrixXd S = z.H * P * z.H.transpose() + z.R;
      const Eigen::MatrixXd K = P * z.H.transpose() * S.inverse();
      x += K * (z.z - z.H * x);
      P = (InsErrorMatrix::Identity() - K * z.H) * P;
      P = 0.5 * (P + P.transpose()).eval();
      st.updated = true;
    }
    st.posterior = ToState(x, st.stamp);
    st.gnss_bias_posterior = x.segment<3>(15);
    st.vehicle_misalignment_posterior = x.segment<2>(18);
    st.vehicle_lateral_model_posterior = x.tail<2>();
    st.P_posterior = P;
    steps.push_back(st);
  }
  std::vector<InsErrorMatrix> P_smoothed;
  auto smoothed = PosSmoother::Smooth(steps, &P_smoothed);
  ASSERT_TRUE(smoothed.ok()) << smoothed.status().ToString();
  ASSERT_EQ(smoothed->size(), static_cast<size_t>(kSteps));

  // Batch: minimise |x0 - m0|^2_P0 + sum |x_k - F x_{k-1}|^2_Q + sum |z_k - H x_k|^2_R (normal
  // equations over all kN * kSteps unknowns); its inverse information is the smoothed covariance.
  const int n = kN * kSteps;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  const InsErrorMatrix P0i = P0.inverse(), Qi = Q.inverse();
  A.block<kN, kN>(0, 0) += P0i;
  b.segment<kN>(0) += P0i * m0;
  for (int k = 1; k < kSteps; ++k) {
    // r = x_k - F x_{k-1}: J = [-F, I].
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(kN, n);
    J.block<kN, kN>(0, kN * (k - 1)) = -F;
    J.block<kN, kN>(0, kN * k).setIdentity();
    A += J.transpose() * Qi * J;
  }
  for (int k = 0; k < kSteps; ++k) {
    if (!meas[k]) continue;
    const Meas& z = *meas[k];
    const Eigen::MatrixXd Ri = z.R.inverse();
    A.block(kN * k, kN * k, kN, kN) += z.H.transpose() * Ri * z.H;
    b.segment<kN>(kN * k) += z.H.transpose() * Ri * z.z;
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(A);
  const Eigen::VectorXd x_batch = ldlt.solve(b);
  const Eigen::MatrixXd P_batch = ldlt.solve(Eigen::MatrixXd::Identity(n, n));
  double max_dx = 0.0, max_dP = 0.0;
  for (int k = 0; k < kSteps; ++k) {
    const Eigen::Matrix<double, 15, 1> xs = FromState((*smoothed)[k]);
    max_dx = std::max(max_dx, (xs - x_batch.segment<15>(kN * k)).cwiseAbs().maxCoeff());
    max_dP = std::max(
        max_dP, (P_smoothed[k] - P_batch.block(kN * k, kN * k, kN, kN)).cwiseAbs().maxCoeff());
  }
  std::printf("RTS vs batch least squares (%d steps, %d states): max |dx| %.3g, max |dP| %.3g\n",
              kSteps, kN, max_dx, max_dP);
  EXPECT_LT(max_dx, 1e-9);
  EXPECT_LT(max_dP, 1e-9);
  // The smoother is not the filter: the first state moved (a property, not a tautology).
  EXPECT_GT((FromState((*smoothed)[0]) - FromState(steps[0].posterior)).norm(), 1e-3);
}

TEST(PosSmootherTest, RejectsBadSteps) {
  EXPECT_EQ(PosSmoother::Smooth({}).status().code(), StatusCode::kInvalidArgument);
  InsFilterStep a;
  a.stamp = kT0;
  a.P_prior = a.P_posterior = InsErrorMatrix::Identity();
  InsFilterStep b = a;
  EXPECT_EQ(PosSmoother::Smooth({a, b}).status().code(), StatusCode::kInvalidArgument);  // order
  b.stamp = kT0.PlusSeconds(0.01);
  b.P_prior = InsErrorMatrix::Zero();
  EXPECT_EQ(PosSmoother::Smooth({a, b}).status().code(), StatusCode::kInvalidArgument);  // P
  b.P_prior = InsErrorMatrix::Identity();
  b.prior.v_world_mps.x() = std::nan("");
  EXPECT_EQ(PosSmoother::Smooth({a, b}).status().code(), StatusCode::kInvalidArgument);
  PosSmoother::Options o;
  o.gnss_outages = {{10.0, -1.0}};
  const Status s = o.Validate();
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("gnss_outages[0]"), std::string::npos) << s.message();
  EXPECT_EQ(PosSmoother::Run(PosSmoother::Options(), {}, {}, std::nullopt).status().code(),
            StatusCode::kFailedPrecondition);
}

// A noisy 240 s drive along the analytic trajectory (testing::MakeNoisyDrive): tactical IMU noise
// and biases (the filter's own model), RTK fixes of 2/3 cm at 10 Hz, GNSS withheld in [100, 160) s.
using testing::MakeNoisyDrive;
using testing::NoisyDrive;

TEST(PosSmootherTest, SmoothedErrorInsideAnOutageIsFarBelowTheForwardError) {
  PosSmoother::Options o;
  o.ins.gravity_mps2 = 9.80665;  // the generator's
  o.ins.gnss.t_body_antenna = Eigen::Vector3d(0.5, 0.2, 1.2);
  o.origin = kOrigin;
  o.outage_reference = kT0;
  o.gnss_outages = {{100.0, 60.0}};
  const NoisyDrive d = MakeNoisyDrive(o.ins, 240.0, 3, kT0, kOrigin);
  auto r = PosSmoother::Run(o, d.imu, d.gnss, d.initial);
  ASSERT_TRUE(r.ok()) << r.status().ToString();
  ASSERT_EQ(r->forward.size(), r->smoothed.size());
  ASSERT_GT(r->smoothed.size(), 20000u);

  const SyntheticDrive drive;
  double fwd_out = 0.0, sm_out = 0.0, fwd_att_out = 0.0, sm_att_out = 0.0;
  double sm_rms_fixed = 0.0, fwd_rms_fixed = 0.0;
  int n_fixed = 0, n_out = 0, n_nees_in = 0;
  double nees_sum = 0.0;
  for (size_t i = 0; i < r->smoothed.size(); ++i) {
    const double t = r->smoothed[i].stamp.SecondsSince(kT0);
    const TruthState tr = drive.At(t);
    const double ef = (r->forward[i].T_world_body.translation() - tr.p).norm();
    const Eigen::Vector3d es_vec = tr.p - r->smoothed[i].T_world_body.translation();
    const double es = es_vec.norm();
    const double af =
        RotationAngle(r->forward[i].T_world_body.linear().transpose() * tr.R) * 180.0 / M_PI;
    const double as =
        RotationAngle(r->smoothed[i].T_world_body.linear().transpose() * tr.R) * 180.0 / M_PI;
    if (t >= 100.0 && t < 160.0) {
      fwd_out = std::max(fwd_out, ef);
      sm_out = std::max(sm_out, es);
      fwd_att_out = std::max(fwd_att_out, af);
      sm_att_out = std::max(sm_att_out, as);
      if (i % 100 == 0) {
        // Position NEES (3 dof) of the smoothed state, world frame: cov_world = R cov_body R^T.
        const Eigen::Matrix3d R = r->smoothed[i].T_world_body.linear();
        const Eigen::Matrix3d C =
            R * r->smoothed[i].cov_T_world_body.bottomRightCorner<3, 3>() * R.transpose();
        const double nees = es_vec.dot(C.ldlt().solve(es_vec));
        nees_sum += nees;
        ++n_out;
        if (nees > 0.0717 && nees < 12.84) ++n_nees_in;  // 3 dof, 99 % two-sided
      }
    } else if (t > 10.0 && t < 100.0) {
      sm_rms_fixed += es * es;
      fwd_rms_fixed += ef * ef;
      ++n_fixed;
    }
  }
  sm_rms_fixed = std::sqrt(sm_rms_fixed / n_fixed);
  fwd_rms_fixed = std::sqrt(fwd_rms_fixed / n_fixed);
  std::printf(
      "240 s noisy drive, outage [100, 160) s: max position error in the outage forward %.3f m, "
      "smoothed %.3f m (%.1fx lower); attitude forward %.3f deg, smoothed %.3f deg; RTK "
      "10-100 s RMS forward %.4f m, smoothed %.4f m; smoothed position NEES in the outage mean "
      "%.2f (3 dof), %d/%d inside the 99 %% bounds\n",
      fwd_out, sm_out, fwd_out / sm_out, fwd_att_out, sm_att_out, fwd_rms_fixed, sm_rms_fixed,
      nees_sum / n_out, n_nees_in, n_out);
  EXPECT_GT(fwd_out, 0.3);            // the forward filter drifts in 60 s...
  EXPECT_LT(sm_out, 0.25 * fwd_out);  // ...the smoother ties both ends of the outage
  EXPECT_LT(sm_att_out, fwd_att_out);
  EXPECT_LT(sm_rms_fixed, fwd_rms_fixed);  // smoothing also helps where GNSS is good
  EXPECT_GT(n_nees_in, 0.8 * n_out);
}

}  // namespace
}  // namespace slam_mms
