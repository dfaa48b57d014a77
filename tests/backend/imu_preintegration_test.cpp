#include "slam_mms/ins/imu_preintegration.hpp"

#include <ceres/ceres.h>
#include <ceres/normal_prior.h>
#include <gtest/gtest.h>

#include <random>

#include "backend/gnss_position_factor.hpp"
#include "backend/imu_preintegration_factor.hpp"
#include "backend/pose_block.hpp"
#include "ins/numeric_jacobian.hpp"
#include "ins/synthetic_drive.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms {
namespace {

using testing::SyntheticDrive;
using testing::TruthState;

const Timestamp kT0 = Timestamp::FromSeconds(1317000000.0);

std::vector<ImuSample> PerfectSamples(const SyntheticDrive& drive, double t_a, double t_b,
                                      double rate_hz,
                                      const Eigen::Vector3d& ba = Eigen::Vector3d::Zero(),
                                      const Eigen::Vector3d& bg = Eigen::Vector3d::Zero()) {
  std::vector<ImuSample> out;
  const int n = static_cast<int>(std::round((t_b - t_a) * rate_hz));
  for (int k = 0; k <= n; ++k) {
    ImuSample s = drive.PerfectImu(t_a + k / rate_hz, kT0);
    s.accel_mps2 += ba;
    s.gyro_radps += bg;
    out.push_back(s);
  }
  return out;
}

std::vector<double> Pose(const TruthState& s) {
  const PoseBlock b = PoseToBlock(MakeIsometry(s.R, s.p));
  return std::vector<double>(b.begin(), b.end());
}

TEST(SyntheticDriveTest, AngularRateAndSpecificForceMatchFiniteDifferences) {
  // The generator itself: R(t)^T R(t+h) = Exp(w h) and p'' = a (else every test below is moot).
  const SyntheticDrive drive;
  for (double t : {0.0, 3.7, 17.2, 55.0}) {
    const double h = 1e-4;
    const TruthState a = drive.At(t - h), b = drive.At(t + h), c = drive.At(t);
    const Eigen::Vector3d w_fd = so3::Log(a.R.transpose() * b.R) / (2 * h);
    EXPECT_LT((w_fd - c.w_body).norm(), 1e-6) << t;
    EXPECT_LT(((b.p - a.p) / (2 * h) - c.v).norm(), 1e-6) << t;
    EXPECT_LT(((b.v - a.v) / (2 * h) - c.a).norm(), 1e-6) << t;
  }
}

TEST(ImuPreintegrationTest, PerfectImuReproducesTheTruth) {
  const SyntheticDrive drive;
  const double t_i = 12.0, t_j = 13.0;
  ImuPreintegration pre(ImuPreintegration::Options(), Eigen::Vector3d::Zero(),
                        Eigen::Vector3d::Zero());
  ASSERT_TRUE(pre.IntegrateWindow(PerfectSamples(drive, t_i - 0.2, t_j + 0.2, 200.0),
                                  kT0.PlusSeconds(t_i), kT0.PlusSeconds(t_j))
                  .ok());
  EXPECT_NEAR(pre.delta_t_s(), 1.0, 1e-9);
  const TruthState si = drive.At(t_i), sj = drive.At(t_j);
  NavState nav_i;
  nav_i.q_world_body = Eigen::Quaterniond(si.R);
  nav_i.p_world = si.p;
  nav_i.v_world = si.v;
  const NavState nav_j = pre.Predict(nav_i, Eigen::Vector3d(0, 0, -drive.gravity()));
  const double rot_err = RotationAngle(nav_j.q_world_body.toRotationMatrix().transpose() * sj.R);
  EXPECT_LT((nav_j.p_world - sj.p).norm(), 1e-4);
  EXPECT_LT((nav_j.v_world - sj.v).norm(), 1e-4);
  EXPECT_LT(rot_err, 1e-6);
  // The pose-and-velocity overload is the same prediction, bit for bit.
  Eigen::Isometry3d T_i = Eigen::Isometry3d::Identity();
  T_i.linear() = si.R;
  T_i.translation() = si.p;
  const NavState nav_j2 = pre.Predict(T_i, si.v, Eigen::Vector3d(0, 0, -drive.gravity()));
  EXPECT_EQ(nav_j2.p_world, nav_j.p_world);
  EXPECT_EQ(nav_j2.v_world, nav_j.v_world);
  EXPECT_EQ(nav_j2.q_world_body.coeffs(), nav_j.q_world_body.coeffs());
  // Covariance: symmetric positive definite.
  const Matrix9d& C = pre.covariance();
  EXPECT_TRUE(C.isApprox(C.transpose(), 1e-12));
  EXPECT_GT(Eigen::SelfAdjointEigenSolver<Matrix9d>(C).eigenvalues().minCoeff(), 0.0);

  // The factor at the truth: residual ~ 0 (unwhitened).
  auto factor = ImuPreintegrationFactor::Create(pre, Eigen::Vector3d(0, 0, -drive.gravity()));
  ASSERT_TRUE(factor.ok()) << factor.status().message();
  std::vector<double> pi = Pose(si), pj = Pose(sj), vi(si.v.data(), si.v.data() + 3),
                      vj(sj.v.data(), sj.v.data() + 3), bi(6, 0.0), bj(6, 0.0);
  const double* params[6] = {pi.data(), vi.data(), bi.data(), pj.data(), vj.data(), bj.data()};
  const Eigen::Matrix<double, 15, 1> r = (*factor)->UnwhitenedResidual(params);
  EXPECT_LT(r.segment<3>(0).norm(), 1e-6);
  EXPECT_LT(r.segment<3>(3).norm(), 1e-4);
  EXPECT_LT(r.segment<3>(6).norm(), 1e-4);
  EXPECT_EQ(r.tail<6>().norm(), 0.0);
}

TEST(ImuPreintegrationTest, BiasJacobiansPredictReintegration) {
  const SyntheticDrive drive;
  const auto samples = PerfectSamples(drive, 20.0, 21.0, 100.0);
  const Eigen::Vector3d ba0(0.01, -0.02, 0.03), bg0(1e-3, -2e-3, 5e-4);
  ImuPreintegration lin(ImuPreintegration::Options(), ba0, bg0);
  ASSERT_TRUE(lin.IntegrateWindow(samples, samples.front().stamp, samples.back().stamp).ok());
  const Eigen::Vector3d dba(2e-3, 1e-3, -3e-3), dbg(2e-4, -1e-4, 3e-4);
  ImuPreintegration re(ImuPreintegration::Options(), ba0 + dba, bg0 + dbg);
  ASSERT_TRUE(re.IntegrateWindow(samples, samples.front().stamp, samples.back().stamp).ok());
  // First-order correction must remove almost all of the change (the rest is second order).
  const double err_R_uncorr = RotationAngle(lin.delta_R().transpose() * re.delta_R());
  const double err_R = RotationAngle(lin.CorrectedDeltaR(bg0 + dbg).transpose() * re.delta_R());
  const double err_v_uncorr = (lin.delta_v() - re.delta_v()).norm();
  const double err_v = (lin.CorrectedDeltaV(ba0 + dba, bg0 + dbg) - re.delta_v()).norm();
  const double err_p_uncorr = (lin.delta_p() - re.delta_p()).norm();
  const double err_p = (lin.CorrectedDeltaP(ba0 + dba, bg0 + dbg) - re.delta_p()).norm();
  EXPECT_LT(err_R, 1e-3 * err_R_uncorr);
  EXPECT_LT(err_v, 1e-2 * err_v_uncorr);
  EXPECT_LT(err_p, 1e-2 * err_p_uncorr);
}

TEST(ImuPreintegrationTest, RejectsBadInput) {
  ImuPreintegration pre;
  EXPECT_FALSE(pre.Integrate(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0).ok());
  EXPECT_FALSE(pre.Integrate(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 5.0).ok());
  EXPECT_FALSE(
      pre.Integrate(Eigen::Vector3d::Constant(std::nan("")), Eigen::Vector3d::Zero(), 0.01).ok());
  EXPECT_FALSE(
      ImuPreintegrationFactor::Create(pre, Eigen::Vector3d(0, 0, -9.8)).ok());  // no samples
  ImuPreintegration::Options bad;
  bad.gyro_noise_density = -1.0;
  EXPECT_FALSE(bad.Validate().ok());
}

TEST(ImuPreintegrationFactorTest, JacobiansMatchNumericDifferentiation) {
  const SyntheticDrive drive;
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d ba_lin(0.02, -0.01, 0.03), bg_lin(1e-3, 2e-3, -1e-3);
  ImuPreintegration pre(ImuPreintegration::Options(), ba_lin, bg_lin);
  ASSERT_TRUE(pre.IntegrateWindow(PerfectSamples(drive, 30.0, 30.5, 100.0, ba_lin, bg_lin),
                                  kT0.PlusSeconds(30.0), kT0.PlusSeconds(30.5))
                  .ok());
  auto factor = ImuPreintegrationFactor::Create(pre, Eigen::Vector3d(0, 0, -9.80665));
  ASSERT_TRUE(factor.ok());
  std::unique_ptr<ceres::Manifold> pose_manifold(NewPoseManifold());
  for (int trial = 0; trial < 5; ++trial) {
    // States near (not at) the truth and biases away from the linearisation point, so every term
    // of every Jacobian is exercised.
    auto perturb = [&](const TruthState& s) {
      Eigen::Vector3d w(n(rng), n(rng), n(rng));
      return MakeIsometry(s.R * so3::Exp(0.05 * w), s.p + Eigen::Vector3d(n(rng), n(rng), n(rng)));
    };
    const TruthState si = drive.At(30.0), sj = drive.At(30.5);
    const PoseBlock bpi = PoseToBlock(perturb(si)), bpj = PoseToBlock(perturb(sj));
    std::vector<std::vector<double>> params(6);
    params[0].assign(bpi.begin(), bpi.end());
    params[3].assign(bpj.begin(), bpj.end());
    for (int b : {1, 4}) params[b] = {n(rng) * 3, n(rng) * 3, n(rng)};
    for (int b : {2, 5}) {
      params[b] = {ba_lin.x() + 0.01 * n(rng), ba_lin.y() + 0.01 * n(rng),
                   ba_lin.z() + 0.01 * n(rng), bg_lin.x() + 1e-3 * n(rng),
                   bg_lin.y() + 1e-3 * n(rng), bg_lin.z() + 1e-3 * n(rng)};
    }
    for (int block = 0; block < 6; ++block) {
      const bool is_pose = block == 0 || block == 3;
      const auto J = testing::CompareJacobian(**factor, params, block,
                                              is_pose ? pose_manifold.get() : nullptr, 1e-6);
      const double scale = std::max(1.0, J.numeric.cwiseAbs().maxCoeff());
      EXPECT_LT((J.analytic - J.numeric).cwiseAbs().maxCoeff(), 1e-5 * scale)
          << "block " << block << " trial " << trial << "\nanalytic\n"
          << J.analytic << "\nnumeric\n"
          << J.numeric;
    }
    // Ambient Jacobians also hold for a non-unit quaternion block (the residual normalises it).
    for (int block : {0, 3}) {
      std::vector<std::vector<double>> scaled = params;
      for (int k = 3; k < 7; ++k) scaled[block][k] *= 1.3;
      const auto J = testing::CompareJacobian(**factor, scaled, block, nullptr, 1e-6);
      const double scale = std::max(1.0, J.numeric.cwiseAbs().maxCoeff());
      EXPECT_LT((J.analytic - J.numeric).cwiseAbs().maxCoeff(), 1e-5 * scale)
          << "ambient " << block;
    }
  }
}

TEST(GnssPositionFactorTest, JacobianMatchesNumericDifferentiationAndResidual) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  std::unique_ptr<ceres::Manifold> pose_manifold(NewPoseManifold());
  const Eigen::Vector3d lever(0.3, -0.5, 1.2);
  Eigen::Matrix3d cov;
  cov << 0.04, 0.01, 0.0, 0.01, 0.09, 0.0, 0.0, 0.0, 0.25;
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::Isometry3d T = MakeIsometry(so3::Exp(Eigen::Vector3d(n(rng), n(rng), n(rng))),
                                             Eigen::Vector3d(n(rng), n(rng), n(rng)) * 10);
    const Eigen::Vector3d z = T * lever + Eigen::Vector3d(n(rng), n(rng), n(rng));
    auto f = GnssPositionFactor::Create(z, cov, lever);
    ASSERT_TRUE(f.ok());
    const PoseBlock b = PoseToBlock(T);
    std::vector<std::vector<double>> params = {std::vector<double>(b.begin(), b.end())};
    const auto J = testing::CompareJacobian(**f, params, 0, pose_manifold.get(), 1e-6);
    EXPECT_LT((J.analytic - J.numeric).cwiseAbs().maxCoeff(), 1e-6) << J.analytic << "\n"
                                                                    << J.numeric;
    std::vector<std::vector<double>> scaled = params;
    for (int k = 3; k < 7; ++k) scaled[0][k] *= 0.8;
    const auto Ja = testing::CompareJacobian(**f, scaled, 0, nullptr, 1e-6);
    EXPECT_LT((Ja.analytic - Ja.numeric).cwiseAbs().maxCoeff(), 1e-6) << "ambient";
    // Whitened residual: r^T r == e^T cov^-1 e (eq 24 with the lever arm).
    const Eigen::Vector3d e = T * lever - z;
    const Eigen::VectorXd r = testing::EvaluateResidual(**f, params);
    EXPECT_NEAR(r.squaredNorm(), e.dot(cov.inverse() * e), 1e-9);
  }
  EXPECT_FALSE(
      GnssPositionFactor::Create(Eigen::Vector3d::Zero(), -Eigen::Matrix3d::Identity(), lever)
          .ok());
  EXPECT_FALSE(GnssPositionFactor::Create(Eigen::Vector3d::Constant(std::nan("")),
                                          Eigen::Matrix3d::Identity(), lever)
                   .ok());
}

TEST(ImuPreintegrationFactorTest, SlidingWindowEstimatesTheBiases) {
  // Beyond the paper: a window of preintegration + GNSS factors recovers constant IMU biases.
  const SyntheticDrive drive;
  const Eigen::Vector3d ba_true(0.05, -0.03, 0.08), bg_true(1e-3, -5e-4, 8e-4);
  // 30 s with changing turn rate and acceleration: over a short window of near-constant turning a
  // yaw-gyro bias and a horizontal accelerometer bias are nearly indistinguishable (both give a
  // ramp in world acceleration), so the window must see the motion change.
  const double dt = 1.0, t_first = 40.0;
  const int num_states = 31;
  const auto samples = PerfectSamples(drive, t_first - 0.1, t_first + dt * (num_states - 1) + 0.1,
                                      100.0, ba_true, bg_true);
  const Eigen::Vector3d g(0, 0, -drive.gravity());
  std::vector<PoseBlock> poses(num_states);
  std::vector<std::array<double, 3>> vels(num_states);
  std::vector<std::array<double, 6>> biases(num_states);
  ceres::Problem problem;
  // Initial guess: dead reckoning from the true first state with zero biases (drifts).
  NavState nav;
  const TruthState s0 = drive.At(t_first);
  nav.q_world_body = Eigen::Quaterniond(s0.R);
  nav.p_world = s0.p;
  nav.v_world = s0.v;
  for (int k = 0; k < num_states; ++k) {
    poses[k] = PoseToBlock(MakeIsometry(nav.q_world_body, nav.p_world));
    vels[k] = {nav.v_world.x(), nav.v_world.y(), nav.v_world.z()};
    biases[k].fill(0.0);
    problem.AddParameterBlock(poses[k].data(), 7, NewPoseManifold());
    const TruthState s = drive.At(t_first + k * dt);
    auto gf = GnssPositionFactor::Create(s.p, 0.02 * 0.02 * Eigen::Matrix3d::Identity(),
                                         Eigen::Vector3d::Zero());
    ASSERT_TRUE(gf.ok());
    problem.AddResidualBlock(gf->release(), new ceres::HuberLoss(3.0), poses[k].data());
    if (k + 1 < num_states) {
      ImuPreintegration pre(ImuPreintegration::Options(), Eigen::Vector3d::Zero(),
                            Eigen::Vector3d::Zero());
      ASSERT_TRUE(pre.IntegrateWindow(samples, kT0.PlusSeconds(t_first + k * dt),
                                      kT0.PlusSeconds(t_first + (k + 1) * dt))
                      .ok());
      nav = pre.Predict(nav, g);
    }
  }
  for (int k = 0; k + 1 < num_states; ++k) {
    ImuPreintegration pre(ImuPreintegration::Options(), Eigen::Vector3d::Zero(),
                          Eigen::Vector3d::Zero());
    ASSERT_TRUE(pre.IntegrateWindow(samples, kT0.PlusSeconds(t_first + k * dt),
                                    kT0.PlusSeconds(t_first + (k + 1) * dt))
                    .ok());
    auto f = ImuPreintegrationFactor::Create(pre, g);
    ASSERT_TRUE(f.ok());
    problem.AddResidualBlock(f->release(), nullptr, poses[k].data(), vels[k].data(),
                             biases[k].data(), poses[k + 1].data(), vels[k + 1].data(),
                             biases[k + 1].data());
  }
  // Bias prior (0 +- 0.1 m/s^2, 0.01 rad/s) and a known first attitude.
  ceres::Matrix prior_sqrt_info = ceres::Matrix::Zero(6, 6);
  prior_sqrt_info.diagonal() << 10, 10, 10, 100, 100, 100;
  problem.AddResidualBlock(new ceres::NormalPrior(prior_sqrt_info, Eigen::VectorXd::Zero(6)),
                           nullptr, biases[0].data());
  problem.SetParameterBlockConstant(poses[0].data());
  ceres::Solver::Options options;
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-12;
  options.gradient_tolerance = 1e-14;
  options.parameter_tolerance = 1e-12;
  options.linear_solver_type = ceres::DENSE_SCHUR;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  ASSERT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
  const int last = num_states - 1;
  const Eigen::Vector3d ba_est(biases[last][0], biases[last][1], biases[last][2]);
  const Eigen::Vector3d bg_est(biases[last][3], biases[last][4], biases[last][5]);
  EXPECT_LT((ba_est - ba_true).norm(), 5e-3) << ba_est.transpose();
  EXPECT_LT((bg_est - bg_true).norm(), 5e-5) << bg_est.transpose() << "\n" << summary.FullReport();
  const TruthState s_last = drive.At(t_first + last * dt);
  EXPECT_LT((PoseFromBlock(poses[last]).translation() - s_last.p).norm(), 0.02);
  EXPECT_LT(RotationAngle(PoseFromBlock(poses[last]).linear().transpose() * s_last.R), 1e-3);
}

}  // namespace
}  // namespace slam_mms
