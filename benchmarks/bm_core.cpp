#include <benchmark/benchmark.h>

#include <random>

#include "slam_mms/core/lie.hpp"

namespace {

void BM_Se3ExpLog(benchmark::State& state) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  slam_mms::Vector6d xi;
  for (int i = 0; i < 6; ++i) xi[i] = u(rng);
  for (auto _ : state) {
    benchmark::DoNotOptimize(slam_mms::se3::Log(slam_mms::se3::Exp(xi)));
  }
}
BENCHMARK(BM_Se3ExpLog);

}  // namespace
