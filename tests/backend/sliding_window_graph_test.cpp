// SlidingWindowGraph: marginalization against the full batch, consistency checking, IMU
// preintegration factors through AddCostFunction, covariances, and invalid inputs.
#include "backend/sliding_window_graph.hpp"

#include <ceres/normal_prior.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include "backend/backend_test_util.hpp"
#include "backend/imu_preintegration_factor.hpp"
#include "backend/marginalization.hpp"
#include "backend/pose_block.hpp"
#include "backend/pose_prior_factor.hpp"
#include "backend/relative_pose_factor.hpp"

namespace slam_mms {
namespace {

using testing_backend::CheckAmbientJacobians;
using testing_backend::DiagonalCovariance;
using testing_backend::Perturb;

// A curved drive: 1 m steps with a slow yaw and some pitch/roll wiggle.
std::vector<Eigen::Isometry3d> TruthChain(int n) {
  std::vector<Eigen::Isometry3d> T(static_cast<size_t>(n));
  Eigen::Isometry3d cur = Eigen::Isometry3d::Identity();
  for (int i = 0; i < n; ++i) {
    T[static_cast<size_t>(i)] = cur;
    Vector6d step;
    step << 0.01 * std::sin(0.7 * i), 0.01 * std::cos(0.5 * i), 0.08, 1.0, 0.05, 0.01;
    cur = cur * se3::Exp(step);
  }
  return T;
}

struct Measurements {
  std::vector<Eigen::Isometry3d> odom;  // i -> i+1
  std::vector<Eigen::Isometry3d> skip;  // i -> i+2 (registration-like)
  std::vector<Eigen::Isometry3d> init;  // initial guesses
};

Measurements Simulate(const std::vector<Eigen::Isometry3d>& truth, uint32_t seed) {
  std::mt19937 rng(seed);
  Measurements m;
  const size_t n = truth.size();
  for (size_t i = 0; i + 1 < n; ++i) {
    m.odom.push_back(Perturb(truth[i].inverse() * truth[i + 1], rng, 0.01, 0.05));
  }
  for (size_t i = 0; i + 2 < n; ++i) {
    m.skip.push_back(Perturb(truth[i].inverse() * truth[i + 2], rng, 0.005, 0.03));
  }
  Eigen::Isometry3d cur = truth[0];
  for (size_t i = 0; i < n; ++i) {
    m.init.push_back(cur);
    if (i + 1 < n) cur = cur * m.odom[i];
  }
  return m;
}

// Builds the chain into `g`, solving after each state (the window slides as in level 1).
void RunChain(SlidingWindowGraph& g, const std::vector<Eigen::Isometry3d>& truth,
              const Measurements& m, bool solve_each_step) {
  const int n = static_cast<int>(truth.size());
  for (int i = 0; i < n; ++i) {
    StateInit init;
    init.T_frame_body = m.init[static_cast<size_t>(i)];
    ASSERT_TRUE(g.AddState(i, init).ok());
    if (i == 0) {
      ASSERT_TRUE(g.AddPosePrior(0, truth[0], DiagonalCovariance(1e-3, 1e-2)).ok());
    } else {
      ASSERT_TRUE(g.AddRelativePoseFactor(i - 1, i, m.odom[static_cast<size_t>(i - 1)],
                                          DiagonalCovariance(0.01, 0.05), FactorKind::kMotion)
                      .ok());
    }
    if (i >= 2) {
      auto out =
          g.AddRelativePoseFactor(i - 2, i, m.skip[static_cast<size_t>(i - 2)],
                                  DiagonalCovariance(0.005, 0.03), FactorKind::kRegistration);
      ASSERT_TRUE(out.ok());
      EXPECT_TRUE(out->id.has_value());
    }
    if (solve_each_step || i == n - 1) {
      auto s = g.Solve();
      ASSERT_TRUE(s.ok());
      ASSERT_TRUE(s->usable()) << s->message;
    }
  }
}

TEST(SlidingWindowGraphTest, MarginalizationMatchesFullBatch) {
  const auto truth = TruthChain(16);
  const auto meas = Simulate(truth, 42);
  SlidingWindowGraph::Options batch_opts;
  batch_opts.window_size = 100;
  auto batch = SlidingWindowGraph::Create(batch_opts);
  ASSERT_TRUE(batch.ok());
  RunChain(*batch, truth, meas, /*solve_each_step=*/false);

  SlidingWindowGraph::Options win_opts;
  win_opts.window_size = 4;
  auto window = SlidingWindowGraph::Create(win_opts);
  ASSERT_TRUE(window.ok());
  RunChain(*window, truth, meas, /*solve_each_step=*/true);
  EXPECT_EQ(window->StateIds().size(), 4u);
  EXPECT_EQ(window->num_marginalized_states(), 12);

  // The states still in the window agree with the batch estimate (up to linearisation).
  for (StateId id : window->StateIds()) {
    const Eigen::Isometry3d Tw = *window->Pose(id);
    const Eigen::Isometry3d Tb = *batch->Pose(id);
    EXPECT_LT((Tw.translation() - Tb.translation()).norm(), 2e-3) << "state " << id;
    RecordProperty("pos_diff_marg_vs_batch_m_state_" + std::to_string(id),
                   std::to_string((Tw.translation() - Tb.translation()).norm()));
    EXPECT_LT(RotationAngle(Tw.linear().transpose() * Tb.linear()), 2e-4) << "state " << id;
  }
  // ... and so does the marginal covariance of the latest pose.
  auto cov_w = window->PoseCovariance(15);
  auto cov_b = batch->PoseCovariance(15);
  ASSERT_TRUE(cov_w.ok()) << cov_w.status().ToString();
  ASSERT_TRUE(cov_b.ok()) << cov_b.status().ToString();
  EXPECT_LT((*cov_w - *cov_b).norm(), 0.02 * cov_b->norm());
  RecordProperty("cov_rel_diff_marg_vs_batch",
                 std::to_string((*cov_w - *cov_b).norm() / cov_b->norm()));
  RecordProperty("trace_batch", std::to_string(cov_b->trace()));
  // The estimate is better than dead reckoning.
  const double dr_err = (meas.init[15].translation() - truth[15].translation()).norm();
  const double est_err = (window->Pose(15)->translation() - truth[15].translation()).norm();
  EXPECT_LT(est_err, dr_err);
}

// The window's results must not depend on where the heap puts its factors: a drive run twice (or
// on a Dask worker and in the plain sequential path) gives the same bits. Ceres removes a leaving
// state's factors in the order of its set of them (their addresses) unless the graph removes them
// itself; the second run here allocates blocks of random sizes between the steps, so its factors
// land elsewhere.
std::vector<Eigen::Isometry3d> RunWithHeapNoise(SlidingWindowGraph::ExitMode mode, bool noise,
                                                Matrix6d* last_cov) {
  const auto truth = TruthChain(30);
  const auto m = Simulate(truth, 7);
  SlidingWindowGraph::Options o;
  o.window_size = 4;
  o.exit_mode = mode;
  auto g = SlidingWindowGraph::Create(o);
  EXPECT_TRUE(g.ok());
  std::mt19937 rng(3);
  std::vector<std::vector<char>> kept;
  const int n = static_cast<int>(truth.size());
  for (int i = 0; i < n; ++i) {
    if (noise) {
      for (int k = 0; k < 8; ++k) kept.emplace_back(16 + rng() % 700);
    }
    StateInit init;
    init.T_frame_body = m.init[static_cast<size_t>(i)];
    EXPECT_TRUE(g->AddState(i, init).ok());
    if (i == 0) {
      EXPECT_TRUE(g->AddPosePrior(0, truth[0], DiagonalCovariance(1e-3, 1e-2)).ok());
    } else {
      EXPECT_TRUE(g->AddRelativePoseFactor(i - 1, i, m.odom[static_cast<size_t>(i - 1)],
                                           DiagonalCovariance(0.01, 0.05), FactorKind::kMotion)
                      .ok());
    }
    if (noise) kept.emplace_back(16 + rng() % 300);
    if (i >= 2) {
      EXPECT_TRUE(g->AddRelativePoseFactor(i - 2, i, m.skip[static_cast<size_t>(i - 2)],
                                           DiagonalCovariance(0.005, 0.03),
                                           FactorKind::kRegistration)
                      .ok());
    }
    if (i >= 3) {
      EXPECT_TRUE(g->AddRelativePoseFactor(i - 3, i, truth[i - 3].inverse() * truth[i],
                                           DiagonalCovariance(0.02, 0.1), FactorKind::kRegistration)
                      .ok());
    }
    auto s = g->Solve();
    EXPECT_TRUE(s.ok() && s->usable());
  }
  std::vector<Eigen::Isometry3d> poses;
  for (StateId id : g->StateIds()) poses.push_back(*g->Pose(id));
  auto cov = g->PoseCovariance(n - 1);
  EXPECT_TRUE(cov.ok()) << cov.status().ToString();
  if (cov.ok()) *last_cov = *cov;
  return poses;
}

TEST(SlidingWindowGraphTest, ResultsDoNotDependOnWhereTheHeapPutsTheFactors) {
  for (auto mode :
       {SlidingWindowGraph::ExitMode::kMarginalize, SlidingWindowGraph::ExitMode::kFix}) {
    Matrix6d cov_a, cov_b;
    const auto a = RunWithHeapNoise(mode, /*noise=*/false, &cov_a);
    const auto b = RunWithHeapNoise(mode, /*noise=*/true, &cov_b);
    ASSERT_EQ(a.size(), b.size());
    ASSERT_FALSE(a.empty());
    for (size_t i = 0; i < a.size(); ++i) {
      // Bit for bit, not within a tolerance.
      EXPECT_EQ(0, std::memcmp(a[i].matrix().data(), b[i].matrix().data(), 16 * sizeof(double)))
          << "state " << i << ": " << (a[i].translation() - b[i].translation()).norm() << " m";
    }
    EXPECT_EQ(0, std::memcmp(cov_a.data(), cov_b.data(), 36 * sizeof(double)));
  }
}

TEST(SlidingWindowGraphTest, FixingOldStatesIsOverconfident) {
  const auto truth = TruthChain(16);
  const auto meas = Simulate(truth, 42);
  SlidingWindowGraph::Options batch_opts;
  batch_opts.window_size = 100;
  auto batch = SlidingWindowGraph::Create(batch_opts);
  ASSERT_TRUE(batch.ok());
  RunChain(*batch, truth, meas, false);
  SlidingWindowGraph::Options fix_opts;
  fix_opts.window_size = 4;
  fix_opts.exit_mode = SlidingWindowGraph::ExitMode::kFix;
  auto fixed = SlidingWindowGraph::Create(fix_opts);
  ASSERT_TRUE(fixed.ok());
  RunChain(*fixed, truth, meas, true);
  auto cov_f = fixed->PoseCovariance(15);
  auto cov_b = batch->PoseCovariance(15);
  ASSERT_TRUE(cov_f.ok()) << cov_f.status().ToString();
  // Fixed states carry no uncertainty: the latest pose looks far more certain than it is.
  EXPECT_LT(cov_f->trace(), 0.5 * cov_b->trace());
  RecordProperty("trace_fix_over_batch", std::to_string(cov_f->trace() / cov_b->trace()));
  RecordProperty(
      "pos_diff_fix_vs_batch_m",
      std::to_string((fixed->Pose(15)->translation() - batch->Pose(15)->translation()).norm()));
  // Old fixed states without a factor to a free state are dropped: the graph stays bounded.
  EXPECT_LE(fixed->StateIds().size(), 6u);
}

TEST(SlidingWindowGraphTest, MarginalPriorJacobiansMatchNumeric) {
  // Marginalize state 0 of a 3-state chain and check the prior's ambient Jacobians away from the
  // linearisation point.
  const auto truth = TruthChain(3);
  const auto meas = Simulate(truth, 3);
  ceres::Problem problem;
  std::vector<PoseBlock> blocks(3);
  for (int i = 0; i < 3; ++i) {
    blocks[static_cast<size_t>(i)] = PoseToBlock(meas.init[static_cast<size_t>(i)]);
    problem.AddParameterBlock(blocks[static_cast<size_t>(i)].data(), 7, NewPoseManifold());
  }
  std::vector<ceres::ResidualBlockId> rbs;
  for (int i = 0; i < 2; ++i) {
    auto f = RelativePoseFactor::Create(meas.odom[static_cast<size_t>(i)],
                                        DiagonalCovariance(0.01, 0.05));
    ASSERT_TRUE(f.ok());
    rbs.push_back(problem.AddResidualBlock(f->release(), nullptr,
                                           blocks[static_cast<size_t>(i)].data(),
                                           blocks[static_cast<size_t>(i) + 1].data()));
  }
  std::vector<ceres::ResidualBlockId> touching = {rbs[0]};
  auto prior = backend_internal::MarginalizeBlocks(problem, touching, {blocks[0].data()}, 1e-12);
  ASSERT_TRUE(prior.ok());
  ASSERT_TRUE(*prior);
  // Dropping state 0 leaves a rank-deficient prior on state 1 (a relative factor alone says
  // nothing absolute): all six directions unobserved -> zero rows, still a valid cost function.
  std::mt19937 rng(9);
  const Eigen::Isometry3d moved = Perturb(meas.init[1], rng, 0.2, 0.5);
  std::vector<std::vector<double>> x = {std::vector<double>(7)};
  PoseToBlock(moved, x[0].data());
  CheckAmbientJacobians(**prior, x, 1e-5);

  // With a prior on state 0 the marginal prior on state 1 is full rank; check it too.
  auto p0 = PosePriorFactor::Create(meas.init[0], DiagonalCovariance(0.02, 0.1));
  ASSERT_TRUE(p0.ok());
  touching.push_back(problem.AddResidualBlock(p0->release(), nullptr, blocks[0].data()));
  auto prior2 = backend_internal::MarginalizeBlocks(problem, touching, {blocks[0].data()}, 1e-12);
  ASSERT_TRUE(prior2.ok());
  CheckAmbientJacobians(**prior2, x, 1e-5);
  // At the linearisation point its residual whitened norm equals that of the eliminated factors
  // minimised over state 0 (here both are ~0 since the measurements are consistent there).
  const double* params[] = {blocks[1].data()};
  Vector6d r;
  ASSERT_TRUE((*prior2)->Evaluate(params, r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-6);
}

TEST(SlidingWindowGraphTest, InconsistentRegistrationIsRejectedAndCounted) {
  auto g = SlidingWindowGraph::Create();
  ASSERT_TRUE(g.ok());
  const auto truth = TruthChain(5);
  for (int i = 0; i < 5; ++i) {
    StateInit init;
    init.T_frame_body = truth[static_cast<size_t>(i)];
    ASSERT_TRUE(g->AddState(i, init).ok());
    if (i > 0) {
      ASSERT_TRUE(g->AddRelativePoseFactor(
                       i - 1, i,
                       truth[static_cast<size_t>(i - 1)].inverse() * truth[static_cast<size_t>(i)],
                       DiagonalCovariance(0.01, 0.1), FactorKind::kMotion)
                      .ok());
    }
  }
  const Matrix6d reg_cov = DiagonalCovariance(0.002, 0.02);
  // Agrees with the chained motion prediction 0 -> 3.
  const Eigen::Isometry3d T03 = truth[0].inverse() * truth[3];
  auto good = g->AddRelativePoseFactor(0, 3, T03 * Eigen::Translation3d(0.05, 0, 0), reg_cov,
                                       FactorKind::kRegistration);
  ASSERT_TRUE(good.ok());
  EXPECT_TRUE(good->consistency_checked);
  EXPECT_TRUE(good->consistent);
  EXPECT_TRUE(good->id.has_value());
  // 2 m off along x, with a prediction sigma of ~0.17 m: rejected.
  auto bad = g->AddRelativePoseFactor(0, 3, T03 * Eigen::Translation3d(2.0, 0, 0), reg_cov,
                                      FactorKind::kRegistration);
  ASSERT_TRUE(bad.ok());
  EXPECT_TRUE(bad->consistency_checked);
  EXPECT_FALSE(bad->consistent);
  EXPECT_FALSE(bad->id.has_value());
  EXPECT_GT(bad->mahalanobis_sq, g->options().consistency_gate_chi2);
  // A caller-given prediction (e.g. from IMU preintegration) is used when there is one.
  MotionPrediction pred{truth[3].inverse() * truth[4], DiagonalCovariance(0.01, 0.05)};
  auto with_pred =
      g->AddRelativePoseFactor(3, 4, pred.T_a_b * Eigen::Translation3d(0, 1.0, 0), reg_cov,
                               FactorKind::kRegistration, RobustLoss::Huber(2.0), pred);
  ASSERT_TRUE(with_pred.ok());
  EXPECT_FALSE(with_pred->consistent);
  const ConsistencyStats& st = g->consistency_stats();
  EXPECT_EQ(st.checked, 3);
  EXPECT_EQ(st.passed, 1);
  EXPECT_EQ(st.rejected, 2);
}

// MotionPrediction::enforce false (Localizer's recovery from a streak of rejections): the check is
// made and reported, the registration is added as it is, at its own covariance.
TEST(SlidingWindowGraphTest, AnUnenforcedPredictionReportsTheCheckAndKeepsTheRegistration) {
  auto g = SlidingWindowGraph::Create(SlidingWindowGraph::Options());
  ASSERT_TRUE(g.ok());
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(g->AddState(i, StateInit{}).ok());
  ASSERT_TRUE(
      g->AddPosePrior(0, Eigen::Isometry3d::Identity(), DiagonalCovariance(1e-3, 1e-3)).ok());
  ASSERT_TRUE(g->AddRelativePoseFactor(0, 1, Eigen::Isometry3d(Eigen::Translation3d(1.0, 0, 0)),
                                       DiagonalCovariance(0.01, 0.05), FactorKind::kMotion)
                  .ok());
  MotionPrediction pred{Eigen::Isometry3d(Eigen::Translation3d(1.0, 0, 0)),
                        DiagonalCovariance(0.01, 0.05)};
  pred.enforce = false;
  auto out = g->AddRelativePoseFactor(0, 1, Eigen::Isometry3d(Eigen::Translation3d(3.0, 0, 0)),
                                      DiagonalCovariance(0.01, 0.05), FactorKind::kRegistration,
                                      RobustLoss::None(), pred);
  ASSERT_TRUE(out.ok());
  EXPECT_TRUE(out->consistency_checked);
  EXPECT_FALSE(out->consistent);
  EXPECT_NEAR(out->mahalanobis_sq, 800.0, 1e-6);
  EXPECT_TRUE(out->id.has_value());
  EXPECT_EQ(out->covariance_scale, 1.0);
  EXPECT_EQ(g->consistency_stats().taken_inconsistent, 1);
  EXPECT_EQ(g->consistency_stats().rejected, 0);
  auto s = g->Solve();
  ASSERT_TRUE(s.ok() && s->usable());
  // Equal weights: halfway between the motion factor's 1 m and the registration's 3 m.
  EXPECT_NEAR(g->Pose(1)->translation().x(), 2.0, 1e-3);
}

TEST(SlidingWindowGraphTest, InconsistentRegistrationCanBeDownWeighted) {
  SlidingWindowGraph::Options o;
  o.inconsistency_action = SlidingWindowGraph::InconsistencyAction::kDownWeight;
  auto g = SlidingWindowGraph::Create(o);
  ASSERT_TRUE(g.ok());
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(g->AddState(i, StateInit{}).ok());
  ASSERT_TRUE(
      g->AddPosePrior(0, Eigen::Isometry3d::Identity(), DiagonalCovariance(1e-3, 1e-3)).ok());
  const Eigen::Isometry3d step(Eigen::Translation3d(1.0, 0, 0));
  ASSERT_TRUE(
      g->AddRelativePoseFactor(0, 1, step, DiagonalCovariance(0.01, 0.05), FactorKind::kMotion)
          .ok());
  auto out = g->AddRelativePoseFactor(0, 1, Eigen::Isometry3d(Eigen::Translation3d(3.0, 0, 0)),
                                      DiagonalCovariance(0.01, 0.05), FactorKind::kRegistration);
  ASSERT_TRUE(out.ok());
  EXPECT_TRUE(out->id.has_value());
  // d2 = 2^2 / (2 * 0.05^2) = 800; the covariance is inflated until d2 would sit on the gate.
  EXPECT_NEAR(out->mahalanobis_sq, 800.0, 1e-6);
  EXPECT_NEAR(out->covariance_scale, 800.0 / g->options().consistency_gate_chi2, 1e-6);
  EXPECT_EQ(g->consistency_stats().down_weighted, 1);
  auto s = g->Solve();
  ASSERT_TRUE(s.ok() && s->usable());
  // The down-weighted registration moves the estimate by ~5 cm instead of the 1 m an equal-weight
  // factor would: x = 1 + 2 * 0.05^2 / (0.05^2 + 35.6 * 0.05^2).
  EXPECT_NEAR(g->Pose(1)->translation().x(), 1.0 + 2.0 / (1.0 + out->covariance_scale), 1e-3);
}

TEST(SlidingWindowGraphTest, PreintegrationFactorsAndVelocityBiasMarginalization) {
  // Straight drive at 10 m/s, level, no rotation: the accelerometer reads -g in the body.
  const Eigen::Vector3d g_world(0, 0, -9.80665);
  const Eigen::Vector3d v(10.0, 0.0, 0.0);
  const double dt_state = 0.1;
  SlidingWindowGraph::Options o;
  o.window_size = 4;
  auto g = SlidingWindowGraph::Create(o);
  ASSERT_TRUE(g.ok());
  std::mt19937 rng(1);
  const int n = 12;
  for (int i = 0; i < n; ++i) {
    StateInit init;
    const Eigen::Isometry3d truth(Eigen::Translation3d(v * dt_state * i));
    init.T_frame_body = i == 0 ? truth : Perturb(truth, rng, 0.01, 0.3);
    init.v_frame = v + Eigen::Vector3d(0.5, -0.3, 0.2);
    init.imu_bias = Vector6d::Zero();
    ASSERT_TRUE(g->AddState(i, init).ok());
    if (i == 0) {
      ASSERT_TRUE(g->AddPosePrior(0, truth, DiagonalCovariance(1e-3, 1e-2)).ok());
      ceres::Matrix A = ceres::Matrix::Identity(3, 3) * 10.0;  // 0.1 m/s
      ceres::Vector b = v;
      ASSERT_TRUE(g->AddCostFunction(std::make_unique<ceres::NormalPrior>(A, b),
                                     {{0, StateBlock::kVelocity}})
                      .ok());
      ceres::Matrix B = ceres::Matrix::Identity(6, 6) * 100.0;
      ASSERT_TRUE(
          g->AddCostFunction(std::make_unique<ceres::NormalPrior>(B, ceres::Vector::Zero(6)),
                             {{0, StateBlock::kBias}})
              .ok());
    } else {
      ImuPreintegration pre;
      for (int k = 0; k < 10; ++k) {
        ASSERT_TRUE(pre.Integrate(-g_world, Eigen::Vector3d::Zero(), dt_state / 10).ok());
      }
      auto f = ImuPreintegrationFactor::Create(pre, g_world);
      ASSERT_TRUE(f.ok()) << f.status().ToString();
      auto id = g->AddCostFunction(std::move(*f), {{i - 1, StateBlock::kPose},
                                                   {i - 1, StateBlock::kVelocity},
                                                   {i - 1, StateBlock::kBias},
                                                   {i, StateBlock::kPose},
                                                   {i, StateBlock::kVelocity},
                                                   {i, StateBlock::kBias}});
      ASSERT_TRUE(id.ok()) << id.status().ToString();
    }
    auto s = g->Solve();
    ASSERT_TRUE(s.ok());
    ASSERT_TRUE(s->usable()) << s->message;
  }
  EXPECT_EQ(g->num_marginalized_states(), n - 4);
  const Eigen::Vector3d p_true = v * dt_state * (n - 1);
  EXPECT_LT((g->Pose(n - 1)->translation() - p_true).norm(), 0.01);
  EXPECT_LT((*g->Velocity(n - 1) - v).norm(), 0.01);
  EXPECT_LT(g->ImuBias(n - 1)->norm(), 0.01);
}

TEST(SlidingWindowGraphTest, CovarianceIsGuardedAgainstGaugeFreedom) {
  auto g = SlidingWindowGraph::Create();
  ASSERT_TRUE(g.ok());
  ASSERT_TRUE(g->AddState(0, StateInit{}).ok());
  ASSERT_TRUE(g->AddState(1, StateInit{}).ok());
  ASSERT_TRUE(g->AddRelativePoseFactor(0, 1, Eigen::Isometry3d::Identity(),
                                       DiagonalCovariance(0.01, 0.1), FactorKind::kMotion)
                  .ok());
  // Only a relative factor: absolute poses are unobservable.
  EXPECT_FALSE(g->PoseCovariance(1).ok());
  ASSERT_TRUE(
      g->AddPosePrior(0, Eigen::Isometry3d::Identity(), DiagonalCovariance(0.01, 0.1)).ok());
  auto cov = g->PoseCovariance(1);
  ASSERT_TRUE(cov.ok()) << cov.status().ToString();
  // Prior + one step: the variances add (rotation 2e-4, translation 2e-2 at zero rotation).
  EXPECT_NEAR((*cov)(0, 0), 2e-4, 1e-6);
  EXPECT_NEAR((*cov)(3, 3), 2e-2, 1e-4);
}

class AlwaysFails final : public ceres::SizedCostFunction<1, 7> {
 public:
  bool Evaluate(double const* const*, double*, double**) const override { return false; }
};

TEST(SlidingWindowGraphTest, InvalidInputsReturnStatusWithoutAborting) {
  SlidingWindowGraph::Options bad;
  bad.max_iterations = 0;
  EXPECT_EQ(SlidingWindowGraph::Create(bad).status().code(), StatusCode::kInvalidArgument);
  bad = {};
  bad.window_size = -1;
  EXPECT_FALSE(SlidingWindowGraph::Create(bad).ok());

  auto g = SlidingWindowGraph::Create();
  ASSERT_TRUE(g.ok());
  StateInit nan_init;
  nan_init.T_frame_body.translation().x() = std::nan("");
  EXPECT_FALSE(g->AddState(0, nan_init).ok());
  ASSERT_TRUE(g->AddState(1, StateInit{}).ok());
  EXPECT_FALSE(g->AddState(1, StateInit{}).ok());  // Not increasing.
  EXPECT_FALSE(g->AddState(0, StateInit{}).ok());
  ASSERT_TRUE(g->AddState(2, StateInit{}).ok());
  const Matrix6d cov = DiagonalCovariance(0.01, 0.1);
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  EXPECT_EQ(g->AddRelativePoseFactor(1, 7, I, cov, FactorKind::kMotion).status().code(),
            StatusCode::kNotFound);
  EXPECT_FALSE(g->AddRelativePoseFactor(1, 1, I, cov, FactorKind::kMotion).ok());
  Matrix6d not_pd = cov;
  not_pd(0, 0) = 0.0;
  EXPECT_FALSE(g->AddRelativePoseFactor(1, 2, I, not_pd, FactorKind::kMotion).ok());
  EXPECT_FALSE(g->AddPosePrior(2, I, Matrix6d::Constant(std::nan(""))).ok());
  EXPECT_FALSE(
      g->AddRelativePoseFactor(1, 2, I, cov, FactorKind::kMotion, RobustLoss::Huber(-1)).ok());
  // Cost functions: wrong block count, wrong size, missing block, duplicate block.
  EXPECT_FALSE(g->AddCostFunction(std::make_unique<AlwaysFails>(), {}).ok());
  EXPECT_FALSE(
      g->AddCostFunction(std::make_unique<AlwaysFails>(), {{1, StateBlock::kVelocity}}).ok());
  ceres::Matrix A = ceres::Matrix::Identity(3, 3);
  EXPECT_FALSE(g->AddCostFunction(std::make_unique<ceres::NormalPrior>(A, ceres::Vector::Zero(3)),
                                  {{1, StateBlock::kPose}})
                   .ok());
  auto rel = RelativePoseFactor::Create(I, cov);
  ASSERT_TRUE(rel.ok());
  EXPECT_FALSE(
      g->AddCostFunction(std::move(*rel), {{1, StateBlock::kPose}, {1, StateBlock::kPose}}).ok());
  EXPECT_FALSE(g->AddCostFunction(nullptr, {}).ok());
  EXPECT_EQ(g->Pose(99).status().code(), StatusCode::kNotFound);
  EXPECT_FALSE(g->Velocity(1).ok());
  EXPECT_FALSE(g->RemoveFactor(12345).ok());

  // Nothing to solve yet.
  auto empty = g->Solve();
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ(empty->termination, SolveTermination::kNothingToSolve);
  // A factor that cannot be evaluated makes the solve fail, reported in the summary.
  ASSERT_TRUE(g->AddCostFunction(std::make_unique<AlwaysFails>(), {{1, StateBlock::kPose}}).ok());
  auto failed = g->Solve();
  ASSERT_TRUE(failed.ok());
  EXPECT_EQ(failed->termination, SolveTermination::kFailure);
  EXPECT_FALSE(failed->usable());
  EXPECT_TRUE(g->Pose(1)->isApprox(I));
}

}  // namespace
}  // namespace slam_mms
