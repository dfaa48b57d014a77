// SubmapGraph (level 2): GNSS priors pull a drifting chain onto the truth, a loop removes the drift
// of a LiDAR-only square, a bad loop is down-weighted by the robust loss, bounded solves, scan
// poses, loop candidates against a brute-force oracle, Gauss-Markov GNSS biases against the
// generalised least-squares closed form, invalid inputs.
#include "slam_mms/backend/submap_graph.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <vector>

#include "backend/backend_test_util.hpp"

namespace slam_mms {
namespace {

using testing_backend::DiagonalCovariance;
using testing_backend::Perturb;

// A square of side `side_m` with submaps every `step_m`, driving counter-clockwise; the last node
// is back at the first.
std::vector<Eigen::Isometry3d> SquareTruth(double side_m, double step_m) {
  std::vector<Eigen::Isometry3d> T;
  const int per_side = static_cast<int>(std::lround(side_m / step_m));
  Eigen::Isometry3d cur = Eigen::Isometry3d::Identity();
  for (int s = 0; s < 4; ++s) {
    for (int k = 0; k < per_side; ++k) {
      T.push_back(cur);
      cur = cur * Eigen::Translation3d(step_m, 0, 0);
      if (k == per_side - 1) cur = cur * Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ());
    }
  }
  T.push_back(cur);
  return T;
}

std::vector<Eigen::Isometry3d> CurveTruth(int n) {
  std::vector<Eigen::Isometry3d> T;
  Eigen::Isometry3d cur = Eigen::Isometry3d::Identity();
  for (int i = 0; i < n; ++i) {
    T.push_back(cur);
    Vector6d step;
    step << 0.002 * std::sin(0.3 * i), 0.003 * std::cos(0.2 * i), 0.05 * std::sin(0.1 * i), 10.0,
        0.0, 0.1 * std::sin(0.05 * i);
    cur = cur * se3::Exp(step);
  }
  return T;
}

struct Chain {
  std::vector<Eigen::Isometry3d> odom;
  std::vector<Eigen::Isometry3d> init;
};

// Reckon measurements with noise and a systematic yaw bias (the drift of a LiDAR-only chain).
Chain MakeChain(const std::vector<Eigen::Isometry3d>& truth, uint32_t seed, double yaw_bias_rad) {
  std::mt19937 rng(seed);
  Chain c;
  for (size_t i = 0; i + 1 < truth.size(); ++i) {
    Eigen::Isometry3d m = Perturb(truth[i].inverse() * truth[i + 1], rng, 0.003, 0.05);
    m = m * Eigen::AngleAxisd(yaw_bias_rad, Eigen::Vector3d::UnitZ());
    c.odom.push_back(m);
  }
  Eigen::Isometry3d cur = truth[0];
  for (size_t i = 0; i < truth.size(); ++i) {
    c.init.push_back(cur);
    if (i + 1 < truth.size()) cur = cur * c.odom[i];
  }
  return c;
}

SubmapGraph BuildChainGraph(const SubmapGraph::Options& o,
                            const std::vector<Eigen::Isometry3d>& truth, const Chain& c) {
  auto g = SubmapGraph::Create(o);
  EXPECT_TRUE(g.ok());
  for (size_t i = 0; i < truth.size(); ++i) {
    EXPECT_TRUE(g->AddSubmap(static_cast<SubmapId>(i), c.init[i]).ok());
    if (i > 0) {
      EXPECT_TRUE(g->AddReckonFactor(static_cast<SubmapId>(i - 1), static_cast<SubmapId>(i),
                                     c.odom[i - 1], DiagonalCovariance(0.005, 0.05))
                      .ok());
    }
  }
  return std::move(*g);
}

double PositionError(const SubmapGraph& g, const std::vector<Eigen::Isometry3d>& truth, size_t i) {
  return (g.SubmapPose(static_cast<SubmapId>(i))->translation() - truth[i].translation()).norm();
}

double MaxPositionError(const SubmapGraph& g, const std::vector<Eigen::Isometry3d>& truth) {
  double e = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) e = std::max(e, PositionError(g, truth, i));
  return e;
}

TEST(SubmapGraphTest, GnssPriorsPullANoisyChainOntoTheTruth) {
  const auto truth = CurveTruth(60);
  const Chain c = MakeChain(truth, 17, 0.002);
  auto g = BuildChainGraph(SubmapGraph::Options(), truth, c);
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 0.05);
  for (size_t i = 0; i < truth.size(); ++i) {
    const Eigen::Vector3d fix = truth[i].translation() + Eigen::Vector3d(n(rng), n(rng), n(rng));
    ASSERT_TRUE(
        g.AddGnssPrior(static_cast<SubmapId>(i), fix, 0.0025 * Eigen::Matrix3d::Identity()).ok());
  }
  double dr_sq = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) {
    dr_sq += (c.init[i].translation() - truth[i].translation()).squaredNorm();
  }
  auto s = g.Solve(SolveTrigger::kFinish);
  ASSERT_TRUE(s.ok());
  ASSERT_TRUE(s->usable()) << s->message;
  double sq = 0.0, yaw_sq = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) {
    sq += std::pow(PositionError(g, truth, i), 2);
    // Heading is observable from GNSS positions; roll about the direction of travel is not.
    const Eigen::Matrix3d dR =
        truth[i].linear().transpose() * g.SubmapPose(static_cast<SubmapId>(i))->linear();
    yaw_sq += std::pow(RollPitchYaw(dR).z(), 2);
  }
  const double rmse = std::sqrt(sq / truth.size());
  const double dr_rmse = std::sqrt(dr_sq / truth.size());
  EXPECT_GT(dr_rmse, 5.0);  // The chain really drifts.
  EXPECT_LT(rmse, 0.087);   // Below the 3D noise of the GNSS fixes (sqrt(3) * 0.05 m).
  EXPECT_LT(std::sqrt(yaw_sq / truth.size()), 0.01);
  // The covariance of a node is finite and below the GNSS variance.
  auto cov = g.SubmapCovariance(30);
  ASSERT_TRUE(cov.ok()) << cov.status().ToString();
  const double trans_var = cov->bottomRightCorner<3, 3>().trace();
  EXPECT_LT(trans_var, 3 * 0.0025);
}

TEST(SubmapGraphTest, LoopReducesLidarOnlyDriftOfASquareAtLeastFiveTimes) {
  const auto truth = SquareTruth(100.0, 10.0);  // 41 submaps, the last back at the start.
  const Chain c = MakeChain(truth, 23, 0.003);
  auto g = BuildChainGraph(SubmapGraph::Options(), truth, c);
  const size_t last = truth.size() - 1;
  auto s0 = g.Solve(SolveTrigger::kRequested);
  ASSERT_TRUE(s0.ok() && s0->usable());
  const double drift_before = PositionError(g, truth, last);
  // The loop: the last submap registered against the first (the caller verified it).
  EXPECT_EQ(g.LoopCandidates(g.SubmapPose(static_cast<SubmapId>(last))->translation(),
                             static_cast<SubmapId>(last))
                    .size() > 0,
            drift_before < g.options().loop_candidate_distance_m);
  std::mt19937 rng(3);
  const Eigen::Isometry3d T_0_last = Perturb(truth[0].inverse() * truth[last], rng, 0.002, 0.03);
  ASSERT_TRUE(
      g.AddLoopFactor(0, static_cast<SubmapId>(last), T_0_last, DiagonalCovariance(0.002, 0.03))
          .ok());
  auto s1 = g.Solve(SolveTrigger::kLoopClosed);
  ASSERT_TRUE(s1.ok());
  ASSERT_TRUE(s1->usable()) << s1->message;
  const double drift_after = PositionError(g, truth, last);
  RecordProperty("drift_before_m", std::to_string(drift_before));
  RecordProperty("drift_after_m", std::to_string(drift_after));
  EXPECT_GT(drift_before, 5.0);
  EXPECT_GE(drift_before / drift_after, 5.0) << drift_before << " -> " << drift_after;
}

TEST(SubmapGraphTest, BadLoopIsDownWeightedByTheRobustLoss) {
  const auto truth = SquareTruth(100.0, 10.0);
  const Chain c = MakeChain(truth, 29, 0.003);
  const size_t last = truth.size() - 1;
  std::mt19937 rng(4);
  const Eigen::Isometry3d good = Perturb(truth[0].inverse() * truth[last], rng, 0.002, 0.03);
  // A false loop: submap 20 (the far corner) claimed 15 m from where it is relative to submap 10.
  const Eigen::Isometry3d bad =
      truth[10].inverse() * truth[20] * Eigen::Translation3d(15.0, 8.0, 0.0);

  auto run = [&](const RobustLoss& loss, bool with_bad) {
    SubmapGraph::Options o;
    o.loop_loss = loss;
    auto g = BuildChainGraph(o, truth, c);
    auto cg =
        g.AddLoopFactor(0, static_cast<SubmapId>(last), good, DiagonalCovariance(0.002, 0.03));
    EXPECT_TRUE(cg.ok());
    EXPECT_TRUE(cg->chain_available);
    EXPECT_LT(cg->mahalanobis_sq, 22.46);  // Agrees with the chain (99.9 % gate).
    if (with_bad) {
      auto cb = g.AddLoopFactor(10, 20, bad, DiagonalCovariance(0.002, 0.03));
      EXPECT_TRUE(cb.ok());
      EXPECT_GT(cb->mahalanobis_sq, 1000.0);  // Contradicts it.
    }
    auto s = g.Solve(SolveTrigger::kLoopClosed);
    EXPECT_TRUE(s.ok() && s->usable());
    return MaxPositionError(g, truth);
  };
  const double good_only = run(SubmapGraph::Options().loop_loss, false);
  const double robust = run(SubmapGraph::Options().loop_loss, true);
  const double plain = run(RobustLoss::None(), true);
  RecordProperty("max_err_good_only_m", std::to_string(good_only));
  RecordProperty("max_err_robust_m", std::to_string(robust));
  RecordProperty("max_err_plain_m", std::to_string(plain));
  EXPECT_LT(robust, good_only + 0.1);  // The bad loop barely moves the map ...
  EXPECT_GT(plain, 3.0 * robust);      // ... while without a robust loss it bends it.
}

TEST(SubmapGraphTest, SolveIsBoundedToRecentLoopAndOutageNodes) {
  const auto truth = CurveTruth(100);
  const Chain c = MakeChain(truth, 31, 0.0);
  SubmapGraph::Options o;
  o.active_submaps = 10;
  auto g = BuildChainGraph(o, truth, c);
  ASSERT_TRUE(g.Solve(SolveTrigger::kRequested).ok());
  EXPECT_EQ(g.last_num_free_submaps(), 10);
  ASSERT_TRUE(
      g.AddLoopFactor(30, 95, truth[30].inverse() * truth[95], DiagonalCovariance(0.01, 0.1)).ok());
  ASSERT_TRUE(g.Solve(SolveTrigger::kLoopClosed).ok());
  EXPECT_EQ(g.last_num_free_submaps(), 70);  // Nodes 30..99.
  ASSERT_TRUE(g.Solve(SolveTrigger::kRequested).ok());
  EXPECT_EQ(g.last_num_free_submaps(), 10);  // The loop was absorbed.
  auto fin = g.Solve(SolveTrigger::kFinish);
  ASSERT_TRUE(fin.ok() && fin->usable());
  EXPECT_EQ(g.last_num_free_submaps(), 99);  // All but the gauge (no GNSS).

  // GNSS on 0..39, an outage on 40..79, GNSS again on 80..99.
  auto h = BuildChainGraph(o, truth, c);
  for (size_t i = 0; i < truth.size(); ++i) {
    if (i >= 40 && i < 80) continue;
    ASSERT_TRUE(h.AddGnssPrior(static_cast<SubmapId>(i), truth[i].translation(),
                               0.01 * Eigen::Matrix3d::Identity())
                    .ok());
  }
  ASSERT_TRUE(h.Solve(SolveTrigger::kGnssReturned).ok());
  EXPECT_EQ(h.last_num_free_submaps(), 61);  // From node 39, the last GNSS node before the outage.
}

TEST(SubmapGraphTest, ScanPosesFollowTheirSubmapAndGnssLeverArmIsHonoured) {
  auto g = SubmapGraph::Create();
  ASSERT_TRUE(g.ok());
  const Eigen::Isometry3d T_world_submap =
      Eigen::Translation3d(100, -50, 3) *
      Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.1, 0.2, 1).normalized());
  std::mt19937 rng(2);
  ASSERT_TRUE(g->AddSubmap(7, Perturb(T_world_submap, rng, 0.05, 1.0)).ok());
  const Eigen::Vector3d lever(0.5, -0.3, 1.2);
  const std::vector<Eigen::Isometry3d> T_submap_scans = {
      Eigen::Isometry3d::Identity(),
      Eigen::Translation3d(8, 1, 0) * Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()),
      Eigen::Translation3d(15, 6, 0.5) * Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ())};
  for (size_t k = 0; k < T_submap_scans.size(); ++k) {
    ASSERT_TRUE(g->AddScan(7, static_cast<int64_t>(k), Timestamp::FromSeconds(1.0 + 0.1 * k),
                           T_submap_scans[k])
                    .ok());
    const Eigen::Vector3d p_antenna = T_world_submap * T_submap_scans[k] * lever;
    ASSERT_TRUE(
        g->AddGnssPrior(7, p_antenna, 1e-4 * Eigen::Matrix3d::Identity(), T_submap_scans[k], lever)
            .ok());
  }
  auto s = g->Solve(SolveTrigger::kFinish);
  ASSERT_TRUE(s.ok() && s->usable()) << s->message;
  const Eigen::Isometry3d est = *g->SubmapPose(7);
  EXPECT_LT((est.translation() - T_world_submap.translation()).norm(), 1e-4);
  EXPECT_LT(RotationAngle(est.linear().transpose() * T_world_submap.linear()), 1e-5);
  const auto scans = g->ScanPoses();
  ASSERT_EQ(scans.size(), 3u);
  for (size_t k = 0; k < scans.size(); ++k) {
    EXPECT_EQ(scans[k].submap, 7);
    EXPECT_EQ(scans[k].scan_id, static_cast<int64_t>(k));
    EXPECT_TRUE(scans[k].T_world_scan.isApprox(est * T_submap_scans[k], 1e-12));
  }
}

TEST(SubmapGraphTest, LoopCandidatesMatchBruteForce) {
  SubmapGraph::Options o;
  o.loop_candidate_distance_m = 15.0;
  o.loop_min_submap_gap = 4;
  auto g = SubmapGraph::Create(o);
  ASSERT_TRUE(g.ok());
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-50.0, 50.0);
  for (int i = 0; i < 40; ++i) {
    ASSERT_TRUE(g->AddSubmap(i, Eigen::Isometry3d(Eigen::Translation3d(u(rng), u(rng), 0))).ok());
    ASSERT_TRUE(g->AddScan(i, 0, Timestamp(),
                           Eigen::Isometry3d(Eigen::Translation3d(u(rng) / 5, u(rng) / 5, 0)))
                    .ok());
  }
  const auto scans = g->ScanPoses();
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d q(u(rng), u(rng), 0);
    const SubmapId current = 10 + trial;
    std::vector<std::pair<double, SubmapId>> oracle;
    for (SubmapId id = 0; id + 4 <= current; ++id) {
      double d = (g->SubmapPose(id)->translation() - q).norm();
      for (const auto& s : scans) {
        if (s.submap == id) d = std::min(d, (s.T_world_scan.translation() - q).norm());
      }
      if (d < 15.0) oracle.emplace_back(d, id);
    }
    std::sort(oracle.begin(), oracle.end());
    const auto cand = g->LoopCandidates(q, current);
    ASSERT_EQ(cand.size(), oracle.size());
    for (size_t k = 0; k < cand.size(); ++k) {
      EXPECT_EQ(cand[k].submap, oracle[k].second);
      EXPECT_NEAR(cand[k].distance_m, oracle[k].first, 1e-9);
    }
  }
}

// N fixes of one point whose errors are a Gauss-Markov bias (stationary S, transition phi from
// one fix to the next) plus white noise W: the generalised least-squares variance of the point,
// (1^T Sigma^-1 1)^-1 with Sigma_ij = S phi^|i-j| + W delta_ij, per axis.
double GlsVariance(int n, double s, double w, double phi) {
  Eigen::MatrixXd Sigma(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) Sigma(i, j) = s * std::pow(phi, std::abs(i - j)) + (i == j) * w;
  }
  const Eigen::VectorXd one = Eigen::VectorXd::Ones(n);
  return 1.0 / one.dot(Sigma.ldlt().solve(one));
}

// The same fixes in the graph: a bias node per fix, the first with the stationary prior, each
// later one linked to the previous (AddGnssBiasLink); the point's marginal variance.
double GraphVariance(int n, double s, double w, double phi) {
  auto g = SubmapGraph::Create();
  EXPECT_TRUE(g.ok());
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  EXPECT_TRUE(g->AddSubmap(0, I).ok());  // with GNSS no node is the gauge
  EXPECT_TRUE(g->AddPosePrior(0, I, DiagonalCovariance(1e-3, 10.0)).ok());  // the rotation
  const Eigen::Matrix3d S = s * Eigen::Matrix3d::Identity(), W = w * Eigen::Matrix3d::Identity();
  for (int k = 0; k < n; ++k) {
    const Status st =
        k == 0 ? g->AddGnssBias(0, S) : g->AddGnssBiasLink(k - 1, k, phi, (1.0 - phi * phi) * S);
    EXPECT_TRUE(st.ok()) << st.ToString();
    EXPECT_TRUE(g->AddGnssPrior(0, Eigen::Vector3d::Zero(), W, I, Eigen::Vector3d::Zero(), k).ok());
  }
  auto cov = g->SubmapCovariance(0);
  EXPECT_TRUE(cov.ok()) << cov.status().ToString();
  return cov.ok() ? (*cov)(3, 3) : -1.0;
}

TEST(SubmapGraphTest, GaussMarkovGnssBiasesWeighFixesAsTheirCorrelationSays) {
  // From independent fixes (phi 0: (S + W) / N) towards one shared bias (phi 1: S + W / N).
  for (double phi : {0.0, 0.5, 0.9, 0.99, 0.999}) {
    const double gls = GlsVariance(20, 0.04, 0.004, phi);
    const double graph = GraphVariance(20, 0.04, 0.004, phi);
    EXPECT_NEAR(graph, gls, 0.01 * gls) << "phi " << phi;
  }
  EXPECT_NEAR(GlsVariance(20, 0.04, 0.004, 0.0), 0.044 / 20, 1e-12);
  EXPECT_NEAR(GlsVariance(20, 0.04, 0.004, 1.0), 0.04 + 0.004 / 20, 1e-9);
}

TEST(SubmapGraphTest, GnssBiasNodesAreRecordedAndBadOnesRefused) {
  auto g = SubmapGraph::Create();
  ASSERT_TRUE(g.ok());
  const Eigen::Matrix3d S = 0.04 * Eigen::Matrix3d::Identity();
  EXPECT_EQ(g->AddGnssBiasLink(0, 1, 0.5, S).code(), StatusCode::kNotFound);  // no bias 0 yet
  ASSERT_TRUE(g->AddGnssBias(0, S).ok());
  EXPECT_FALSE(g->AddGnssBiasLink(0, 0, 0.5, S).ok());   // key exists
  EXPECT_FALSE(g->AddGnssBiasLink(0, -1, 0.5, S).ok());  // negative key
  EXPECT_FALSE(g->AddGnssBiasLink(0, 1, 1.5, S).ok());   // transition > 1
  EXPECT_FALSE(g->AddGnssBiasLink(0, 1, 0.5, -S).ok());  // not a covariance
  ASSERT_TRUE(g->AddGnssBiasLink(0, 1, 0.5, 0.75 * S).ok());
  EXPECT_TRUE(g->GnssBias(1).ok());
  const auto& f = g->Factors();
  ASSERT_EQ(f.size(), 2u);
  EXPECT_EQ(f[0].kind, SubmapFactorKind::kGnssBias);
  EXPECT_EQ(f[0].gnss_bias, 0);
  EXPECT_EQ(f[1].kind, SubmapFactorKind::kGnssBiasLink);
  EXPECT_EQ(f[1].gnss_bias, 1);
  EXPECT_EQ(f[1].gnss_bias_from, 0);
  EXPECT_DOUBLE_EQ(f[1].transition(1, 1), 0.5);
  EXPECT_DOUBLE_EQ(f[1].covariance(2, 2), 0.03);
  for (SubmapFactorKind k : {SubmapFactorKind::kGnssBias, SubmapFactorKind::kGnssBiasLink}) {
    SubmapFactorKind back = SubmapFactorKind::kReckon;
    EXPECT_TRUE(SubmapFactorKindFromName(SubmapFactorKindName(k), &back));
    EXPECT_EQ(back, k);
  }
}

// FitFactors: the redundancies sum to the graph's redundancy, a factor alone on its node has none,
// and iterated variance component estimation (each group's covariance scaled by sum chi2 / sum
// redundancy, solved again) recovers how far each group's stated covariance is off: GNSS fixes
// drawn with 3x their stated sigma (9), the reckon chain and the pose priors drawn as stated (1).
// A first fit alone blames the reckon chain too (about 2): the misweighted fixes bend it.
TEST(SubmapGraphTest, FactorFitsRecoverEachGroupsVarianceFactor) {
  const auto truth = CurveTruth(120);
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  std::vector<Eigen::Isometry3d> init, reckon, prior;
  std::vector<Eigen::Vector3d> fixes;
  for (size_t i = 0; i < truth.size(); ++i) {
    init.push_back(Perturb(truth[i], rng, 0.01, 0.5));
    if (i > 0) reckon.push_back(Perturb(truth[i - 1].inverse() * truth[i], rng, 0.002, 0.02));
    prior.push_back(Perturb(truth[i], rng, 0.002, 0.3));
    fixes.push_back(truth[i].translation() + 0.15 * Eigen::Vector3d(n(rng), n(rng), n(rng)));
  }
  const SubmapId lonely = static_cast<SubmapId>(truth.size());
  // scale: the variance factor applied to each kind's stated covariance.
  auto build = [&](std::map<SubmapFactorKind, double> scale) {
    SubmapGraph::Options o;
    o.gnss_loss = RobustLoss::None();
    auto g = SubmapGraph::Create(o);
    EXPECT_TRUE(g.ok());
    for (size_t i = 0; i < truth.size(); ++i) {
      const SubmapId id = static_cast<SubmapId>(i);
      EXPECT_TRUE(g->AddSubmap(id, init[i]).ok());
      if (i > 0) {
        EXPECT_TRUE(
            g->AddReckonFactor(id - 1, id, reckon[i - 1],
                               scale[SubmapFactorKind::kReckon] * DiagonalCovariance(0.002, 0.02))
                .ok());
      }
      EXPECT_TRUE(
          g->AddPosePrior(id, prior[i],
                          scale[SubmapFactorKind::kPosePrior] * DiagonalCovariance(0.002, 0.3))
              .ok());
      EXPECT_TRUE(
          g->AddGnssPrior(id, fixes[i],
                          scale[SubmapFactorKind::kGnss] * 0.0025 * Eigen::Matrix3d::Identity())
              .ok());
    }
    // A node with one prior and nothing else: the estimate takes it exactly.
    EXPECT_TRUE(g->AddSubmap(lonely, Eigen::Isometry3d::Identity()).ok());
    EXPECT_TRUE(g->AddPosePrior(lonely, Eigen::Isometry3d(Eigen::Translation3d(3, 4, 5)),
                                DiagonalCovariance(0.01, 0.1))
                    .ok());
    auto s = g->Solve(SolveTrigger::kFinish);
    EXPECT_TRUE(s.ok() && s->usable());
    return std::move(*g);
  };
  std::map<SubmapFactorKind, double> scale = {{SubmapFactorKind::kReckon, 1.0},
                                              {SubmapFactorKind::kPosePrior, 1.0},
                                              {SubmapFactorKind::kGnss, 1.0}};
  for (int iteration = 0; iteration < 8; ++iteration) {
    const SubmapGraph g = build(scale);
    auto fits = g.FitFactors();
    ASSERT_TRUE(fits.ok()) << fits.status().ToString();
    const auto& factors = g.Factors();
    ASSERT_EQ(fits->size(), factors.size());
    std::map<SubmapFactorKind, std::pair<double, double>> groups;  // chi2, redundancy
    double total_redundancy = 0.0;
    int total_dims = 0;
    for (size_t i = 0; i < factors.size(); ++i) {
      const SubmapGraph::FactorFit& f = (*fits)[i];
      EXPECT_GE(f.redundancy, -1e-9);
      EXPECT_LE(f.redundancy, f.dim + 1e-9);
      total_redundancy += f.redundancy;
      total_dims += f.dim;
      if (factors[i].a == lonely) {
        EXPECT_NEAR(f.redundancy, 0.0, 1e-6);
        EXPECT_NEAR(f.chi2, 0.0, 1e-8);
        continue;
      }
      groups[factors[i].kind].first += f.chi2;
      groups[factors[i].kind].second += f.redundancy;
    }
    EXPECT_NEAR(total_redundancy, total_dims - 6.0 * (truth.size() + 1), 1e-6);
    if (iteration == 0) {  // the fixes' misweighting shows in the chain's residuals as well
      EXPECT_GT(groups[SubmapFactorKind::kReckon].first / groups[SubmapFactorKind::kReckon].second,
                1.5);
    }
    for (auto& [kind, v] : scale) v *= groups[kind].first / groups[kind].second;
  }
  EXPECT_NEAR(scale[SubmapFactorKind::kGnss], 9.0, 1.5);
  EXPECT_NEAR(scale[SubmapFactorKind::kReckon], 1.0, 0.25);
  EXPECT_NEAR(scale[SubmapFactorKind::kPosePrior], 1.0, 0.25);
}

// FitFactors orders the Jacobian's columns by the graph's nodes, not by Ceres's listing of its
// parameter blocks (by address): the same graph built twice with the heap disturbed between gives
// the same bits (before, the redundancies' last digits moved: the fleet's exactness test).
TEST(SubmapGraphTest, FactorFitsDoNotDependOnWhereTheHeapPutsTheNodes) {
  const auto truth = CurveTruth(40);
  std::vector<std::unique_ptr<char[]>> junk;
  std::vector<std::vector<SubmapGraph::FactorFit>> runs;
  for (int run = 0; run < 3; ++run) {
    for (int k = 0; k < 50 * run + 7; ++k) junk.emplace_back(new char[64 + 48 * k]);
    std::mt19937 rng(3);
    std::normal_distribution<double> n(0.0, 1.0);
    auto g = SubmapGraph::Create();
    ASSERT_TRUE(g.ok());
    for (size_t i = 0; i < truth.size(); ++i) {
      const SubmapId id = static_cast<SubmapId>(i);
      ASSERT_TRUE(g->AddSubmap(id, Perturb(truth[i], rng, 0.01, 0.5)).ok());
      if (i > 0) {
        ASSERT_TRUE(g->AddReckonFactor(id - 1, id,
                                       Perturb(truth[i - 1].inverse() * truth[i], rng, 0.002, 0.02),
                                       DiagonalCovariance(0.002, 0.02))
                        .ok());
      }
      const Eigen::Vector3d fix =
          truth[i].translation() + 0.05 * Eigen::Vector3d(n(rng), n(rng), n(rng));
      ASSERT_TRUE(g->AddGnssPrior(id, fix, 0.0025 * Eigen::Matrix3d::Identity()).ok());
      if (i % 4 == 0) {
        ASSERT_TRUE(g->AddPosePrior(id, truth[i], DiagonalCovariance(0.002, 1.0)).ok());
      }
    }
    ASSERT_TRUE(g->Solve(SolveTrigger::kFinish).ok());
    auto fits = g->FitFactors();
    ASSERT_TRUE(fits.ok()) << fits.status().ToString();
    runs.push_back(*fits);
  }
  for (size_t r = 1; r < runs.size(); ++r) {
    ASSERT_EQ(runs[r].size(), runs[0].size());
    for (size_t i = 0; i < runs[0].size(); ++i) {
      EXPECT_EQ(runs[r][i].chi2, runs[0][i].chi2) << "factor " << i;
      EXPECT_EQ(runs[r][i].redundancy, runs[0][i].redundancy) << "factor " << i;
    }
  }
}

// A node no factor observes: no redundancy is defined, and FitFactors says so (the adjustment
// then keeps its solve without variance components).
TEST(SubmapGraphTest, FactorFitsRefuseAnUnobservedNode) {
  auto g = SubmapGraph::Create();
  ASSERT_TRUE(g.ok());
  ASSERT_TRUE(g->AddSubmap(0, Eigen::Isometry3d::Identity()).ok());
  ASSERT_TRUE(g->AddSubmap(1, Eigen::Isometry3d(Eigen::Translation3d(10, 0, 0))).ok());
  ASSERT_TRUE(
      g->AddPosePrior(0, Eigen::Isometry3d::Identity(), DiagonalCovariance(0.01, 0.1)).ok());
  auto fits = g->FitFactors();
  ASSERT_FALSE(fits.ok());
  EXPECT_EQ(fits.status().code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(fits.status().message().find("not observed"), std::string::npos)
      << fits.status().message();
}

TEST(SubmapGraphTest, InvalidInputsReturnStatusWithoutAborting) {
  SubmapGraph::Options bad;
  bad.active_submaps = 0;
  EXPECT_EQ(SubmapGraph::Create(bad).status().code(), StatusCode::kInvalidArgument);
  bad = {};
  bad.loop_loss = RobustLoss::Cauchy(0.0);
  EXPECT_FALSE(SubmapGraph::Create(bad).ok());
  auto g = SubmapGraph::Create();
  ASSERT_TRUE(g.ok());
  auto empty = g->Solve(SolveTrigger::kFinish);
  ASSERT_TRUE(empty.ok());
  EXPECT_EQ(empty->termination, SolveTermination::kNothingToSolve);
  const Eigen::Isometry3d I = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d nan_pose = I;
  nan_pose(0, 3) = std::nan("");
  EXPECT_FALSE(g->AddSubmap(0, nan_pose).ok());
  ASSERT_TRUE(g->AddSubmap(0, I).ok());
  ASSERT_TRUE(g->AddSubmap(1, I).ok());
  EXPECT_FALSE(g->AddSubmap(1, I).ok());
  const Matrix6d cov = DiagonalCovariance(0.01, 0.1);
  EXPECT_EQ(g->AddReckonFactor(0, 5, I, cov).code(), StatusCode::kNotFound);
  EXPECT_FALSE(g->AddLoopFactor(1, 1, I, cov).ok());
  EXPECT_FALSE(g->AddRegistrationFactor(0, 1, I, -cov).ok());
  EXPECT_FALSE(
      g->AddGnssPrior(0, Eigen::Vector3d(std::nan(""), 0, 0), Eigen::Matrix3d::Identity()).ok());
  EXPECT_FALSE(g->AddGnssPrior(0, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero()).ok());
  EXPECT_FALSE(g->AddGnssPrior(9, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Identity()).ok());
  EXPECT_FALSE(g->AddScan(9, 0, Timestamp(), I).ok());
  EXPECT_FALSE(g->SubmapPose(9).ok());
  EXPECT_EQ(g->num_loop_factors(), 0);
  EXPECT_EQ(g->num_gnss_priors(), 0);
  // Only a relative factor and the gauge: solvable; covariance of the gauge node is refused.
  ASSERT_TRUE(g->AddReckonFactor(0, 1, I, cov).ok());
  auto s = g->Solve(SolveTrigger::kFinish);
  ASSERT_TRUE(s.ok() && s->usable());
  EXPECT_FALSE(g->SubmapCovariance(0).ok());
  EXPECT_TRUE(g->SubmapCovariance(1).ok());
}

}  // namespace
}  // namespace slam_mms
