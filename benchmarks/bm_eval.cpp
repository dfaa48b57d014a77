// eval benchmarks: mean map entropy (paper eqs 26-27) with the paper's settings (0.1 m voxels,
// r = 0.5 m) on street-like maps of 100k and 1M points, voxel downsampling, ATE.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/voxel_downsample.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/eval/trajectory_error.hpp"

namespace {

// A street of length L: ground (20 m wide) and two 8 m facades, random points with 2 cm noise;
// L grows with n so that the density (about 28 points/m^2) stays the same.
slam_mms::PointCloud StreetMap(size_t n) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::normal_distribution<float> g(0.0f, 0.02f);
  const float length = static_cast<float>(n) / (36.0f * 28.0f);
  slam_mms::PointCloud cloud;
  cloud.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const float pick = u(rng) * 36.0f;
    const float x = length * u(rng);
    if (pick < 20.0f) {
      cloud.Add({x, pick - 10.0f, g(rng)}, u(rng));
    } else {
      const float side = pick < 28.0f ? -10.0f : 10.0f;
      cloud.Add({x, side + g(rng), 8.0f * u(rng)}, u(rng));
    }
  }
  return cloud;
}

void BM_MapEntropy(benchmark::State& state) {
  const slam_mms::PointCloud map = StreetMap(static_cast<size_t>(state.range(0)));
  slam_mms::eval::MapEntropyOptions options;  // r = 0.5 m, voxel 0.1 m, 2 threads
  options.num_threads = static_cast<int>(state.range(1));
  slam_mms::eval::MapEntropyResult last;
  for (auto _ : state) {
    auto r = slam_mms::eval::ComputeMapEntropy(map, options);
    if (!r.ok()) {
      state.SkipWithError(r.status().ToString().c_str());
      return;
    }
    last = *r;
    benchmark::ClobberMemory();  // DoNotOptimize(double&) corrupts the value with GCC 12
  }
  state.counters["evaluated_pts"] = static_cast<double>(last.num_evaluated_points);
  state.counters["valid_pts"] = static_cast<double>(last.num_valid_points);
  state.counters["mean_neighbors"] = last.mean_neighbors;
  state.counters["mme"] = last.mean_map_entropy;
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_MapEntropy)
    ->Args({100000, 2})
    ->Args({1000000, 2})
    ->Args({1000000, 1})
    ->ArgNames({"points", "threads"})
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()  // CPU of all worker threads
    ->UseRealTime();

void BM_VoxelDownsample(benchmark::State& state) {
  const slam_mms::PointCloud map = StreetMap(static_cast<size_t>(state.range(0)));
  size_t out = 0;
  for (auto _ : state) {
    auto r = slam_mms::VoxelDownsample(map, 0.1);
    out = r.ok() ? r->size() : 0;
    benchmark::DoNotOptimize(out);
  }
  state.counters["voxels"] = static_cast<double>(out);
  state.SetItemsProcessed(state.iterations() * state.range(0));
}
BENCHMARK(BM_VoxelDownsample)->Arg(1000000)->Unit(benchmark::kMillisecond);

void BM_AteInterpolated(benchmark::State& state) {
  // 10 Hz estimate against a 100 Hz ground truth, n estimated poses.
  const int n = static_cast<int>(state.range(0));
  const slam_mms::Timestamp t0 = slam_mms::Timestamp::FromNanoseconds(1000000000000LL);
  slam_mms::Trajectory gt, est;
  for (int i = 0; i <= 10 * n; ++i) {
    const double t = 0.01 * i;
    (void)gt.Add(t0.PlusSeconds(t),
                 slam_mms::MakeIsometry(slam_mms::FromRollPitchYaw(0, 0, 0.01 * t),
                                        Eigen::Vector3d(10 * t, std::sin(t), 0)));
  }
  for (int i = 0; i < n; ++i) {
    const double t = 0.1 * i + 0.003;
    (void)est.Add(t0.PlusSeconds(t),
                  slam_mms::MakeIsometry(slam_mms::FromRollPitchYaw(0, 0, 0.01 * t),
                                         Eigen::Vector3d(10 * t + 0.1, std::sin(t), 0)));
  }
  for (auto _ : state) {
    auto r = slam_mms::eval::ComputeAte(est, gt);
    benchmark::DoNotOptimize(r.ok());
  }
  state.SetItemsProcessed(state.iterations() * n);
}
BENCHMARK(BM_AteInterpolated)->Arg(10000)->Unit(benchmark::kMillisecond);

}  // namespace
