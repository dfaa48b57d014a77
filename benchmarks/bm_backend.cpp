// Back-end benchmarks: one level-1 sliding-window step, and level-2 submap graph solves.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "backend/sliding_window_graph.hpp"
#include "slam_mms/backend/submap_graph.hpp"
#include "slam_mms/core/lie.hpp"

namespace {

using slam_mms::Matrix6d;
using slam_mms::Vector6d;

Matrix6d DiagCov(double sigma_rot, double sigma_trans) {
  Matrix6d c = Matrix6d::Zero();
  c.diagonal() << Eigen::Vector3d::Constant(sigma_rot * sigma_rot),
      Eigen::Vector3d::Constant(sigma_trans * sigma_trans);
  return c;
}

Eigen::Isometry3d Noisy(const Eigen::Isometry3d& T, std::mt19937& rng, double sr, double st) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vector6d xi;
  xi << sr * n(rng), sr * n(rng), sr * n(rng), st * n(rng), st * n(rng), st * n(rng);
  return T * slam_mms::se3::Exp(xi);
}

Eigen::Isometry3d Step(int i, double length_m) {
  Vector6d xi;
  xi << 0.002 * std::sin(0.3 * i), 0.002 * std::cos(0.2 * i), 0.02 + 0.03 * std::sin(0.05 * i),
      length_m, 0.0, 0.0;
  return slam_mms::se3::Exp(xi);
}

// One level-1 step in steady state: a window of `range(0)` states; per iteration one new scan with
// its odometry factor (eq 12) and a consistency-checked registration factor (eq 16) from the
// previous scan, a solve, and the marginalization of the oldest state.
void BM_SlidingWindowSolve(benchmark::State& state) {
  const int window = static_cast<int>(state.range(0));
  slam_mms::SlidingWindowGraph::Options o;
  o.window_size = window;
  auto g = slam_mms::SlidingWindowGraph::Create(o);
  if (!g.ok()) {
    state.SkipWithError(g.status().ToString().c_str());
    return;
  }
  std::mt19937 rng(1);
  Eigen::Isometry3d truth = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d guess = truth;
  int64_t id = 0;
  auto add_scan = [&]() {
    slam_mms::StateInit init;
    init.T_frame_body = guess;
    (void)g->AddState(id, init);
    if (id == 0) {
      (void)g->AddPosePrior(0, truth, DiagCov(1e-3, 1e-2));
    } else {
      const Eigen::Isometry3d step = Step(static_cast<int>(id), 1.0);
      const Eigen::Isometry3d odom = Noisy(step, rng, 0.002, 0.02);
      (void)g->AddRelativePoseFactor(id - 1, id, odom, DiagCov(0.002, 0.02),
                                     slam_mms::FactorKind::kMotion);
      (void)g->AddRelativePoseFactor(id - 1, id, Noisy(step, rng, 0.001, 0.01),
                                     DiagCov(0.001, 0.01), slam_mms::FactorKind::kRegistration,
                                     slam_mms::RobustLoss::Huber(3.0));
      truth = truth * step;
      guess = guess * odom;
    }
    ++id;
  };
  for (int i = 0; i < window; ++i) {
    add_scan();
    (void)g->Solve();
  }
  int iterations = 0;
  for (auto _ : state) {
    add_scan();
    auto s = g->Solve();
    if (!s.ok() || !s->usable()) {
      state.SkipWithError("solve failed");
      break;
    }
    iterations += s->iterations;
  }
  state.counters["lm_iterations"] =
      benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
}
BENCHMARK(BM_SlidingWindowSolve)->Arg(10)->Arg(20)->Unit(benchmark::kMillisecond);

// A level-2 graph of N submaps (10 m apart) on a closed drive with drifting reckon factors, GNSS
// priors on every 5th submap except during an outage, and loops where the drive passes old
// submaps; solved from the dead-reckoned estimate.
slam_mms::SubmapGraph BuildSubmapGraph(int n, int active_submaps) {
  slam_mms::SubmapGraph::Options o;
  o.active_submaps = active_submaps;
  auto g = slam_mms::SubmapGraph::Create(o);
  std::mt19937 rng(7);
  std::normal_distribution<double> gn(0.0, 0.05);
  std::vector<Eigen::Isometry3d> truth;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity(), guess = T;
  const int lap = 40;  // Submaps per lap: the drive goes round a 400 m loop.
  for (int i = 0; i < n; ++i) {
    truth.push_back(T);
    (void)g->AddSubmap(i, guess);
    for (int k = 0; k < 5; ++k) {
      (void)g->AddScan(i, 5 * i + k, slam_mms::Timestamp(),
                       Eigen::Isometry3d(Eigen::Translation3d(2.0 * k, 0, 0)));
    }
    if (i > 0) {
      const Eigen::Isometry3d rel = truth[static_cast<size_t>(i - 1)].inverse() * T;
      const Eigen::Isometry3d meas =
          Noisy(rel, rng, 0.003, 0.05) * Eigen::AngleAxisd(0.002, Eigen::Vector3d::UnitZ());
      (void)g->AddReckonFactor(i - 1, i, meas, DiagCov(0.005, 0.05));
      guess = guess * meas;
    }
    const bool outage = (i / 100) % 3 == 1;
    if (i % 5 == 0 && !outage) {
      (void)g->AddGnssPrior(i, T.translation() + Eigen::Vector3d(gn(rng), gn(rng), gn(rng)),
                            0.0025 * Eigen::Matrix3d::Identity());
    }
    if (i >= lap && i % 10 == 0) {
      const Eigen::Isometry3d rel = truth[static_cast<size_t>(i - lap)].inverse() * T;
      (void)g->AddLoopFactor(i - lap, i, Noisy(rel, rng, 0.002, 0.03), DiagCov(0.002, 0.03));
    }
    const double yaw = 2.0 * M_PI / lap;
    T = T * Eigen::Translation3d(10.0, 0, 0) * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
  }
  return std::move(*g);
}

void SubmapGraphSolve(benchmark::State& state, slam_mms::SolveTrigger trigger) {
  const int n = static_cast<int>(state.range(0));
  int iterations = 0, free_nodes = 0;
  for (auto _ : state) {
    state.PauseTiming();
    slam_mms::SubmapGraph g = BuildSubmapGraph(n, 50);
    if (trigger != slam_mms::SolveTrigger::kFinish) {
      // During the drive: the graph was solved before; one new submap arrived since.
      (void)g.Solve(slam_mms::SolveTrigger::kFinish);
      const Eigen::Isometry3d last = *g.SubmapPose(n - 1);
      const Eigen::Isometry3d step(Eigen::Translation3d(10.0, 0, 0));
      (void)g.AddSubmap(n, last * step);
      (void)g.AddReckonFactor(n - 1, n, step, DiagCov(0.005, 0.05));
      // Its GNSS fix disagrees with the dead-reckoned guess by 1 m: the window has work to do.
      (void)g.AddGnssPrior(n, (last * step).translation() + Eigen::Vector3d(1.0, 0.5, 0.0),
                           0.0025 * Eigen::Matrix3d::Identity());
    }
    state.ResumeTiming();
    auto s = g.Solve(trigger);
    if (!s.ok() || !s->usable()) {
      state.SkipWithError("solve failed");
      break;
    }
    iterations += s->iterations;
    free_nodes = g.last_num_free_submaps();
  }
  state.counters["lm_iterations"] =
      benchmark::Counter(iterations, benchmark::Counter::kAvgIterations);
  state.counters["free_submaps"] = free_nodes;
}

// The whole graph (Finish()).
void BM_SubmapGraphSolve(benchmark::State& state) {
  SubmapGraphSolve(state, slam_mms::SolveTrigger::kFinish);
}
BENCHMARK(BM_SubmapGraphSolve)->Arg(100)->Arg(1000)->Unit(benchmark::kMillisecond);

// A bounded solve (the newest 50 submaps plus pending loops), as during the drive.
void BM_SubmapGraphBoundedSolve(benchmark::State& state) {
  SubmapGraphSolve(state, slam_mms::SolveTrigger::kRequested);
}
BENCHMARK(BM_SubmapGraphBoundedSolve)->Arg(1000)->Unit(benchmark::kMillisecond);

}  // namespace
