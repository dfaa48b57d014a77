// ins micro-benchmarks: EKF predict (one IMU sample) and predict + GNSS update, preintegration of
// 10 samples, evaluation of the preintegration factor (with and without Jacobians) and of the
// GNSS position factor.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "backend/gnss_position_factor.hpp"
#include "backend/imu_preintegration_factor.hpp"
#include "backend/pose_block.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/ins/imu_preintegration.hpp"
#include "slam_mms/ins/ins_filter.hpp"

namespace {

using namespace slam_mms;

const Timestamp kT0 = Timestamp::FromSeconds(1317000000.0);

ImuSample Sample(int k) {
  ImuSample s;
  s.stamp = kT0.PlusSeconds(0.01 * k);
  s.accel_mps2 = Eigen::Vector3d(0.3 * std::sin(0.01 * k), 0.2, 9.81);
  s.gyro_radps = Eigen::Vector3d(0.01, -0.02, 0.1 * std::cos(0.005 * k));
  return s;
}

InsFilter MakeFilter() {
  InsFilter f;
  InsState init;
  init.stamp = kT0;
  (void)f.Initialize(init);
  (void)f.mutable_gnss_prior().SetOrigin({49.0, 8.4, 100.0});
  return f;
}

// One EKF prediction per iteration (100 Hz IMU sample).
void BM_InsFilterPredict(benchmark::State& state) {
  InsFilter f = MakeFilter();
  int k = 1;
  for (auto _ : state) {
    benchmark::DoNotOptimize(f.AddImu(Sample(k++)));
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_InsFilterPredict);

// One second of data per iteration: 100 predictions + 10 GNSS updates (decision + EKF update).
void BM_InsFilterPredictUpdate1s(benchmark::State& state) {
  InsFilter f = MakeFilter();
  int k = 1;
  for (auto _ : state) {
    for (int i = 0; i < 100; ++i, ++k) {
      benchmark::DoNotOptimize(f.AddImu(Sample(k)));
      if (k % 10 == 0) {
        const Eigen::Vector3d p = f.CurrentState().value().T_world_body.translation();
        const GeodeticPoint g = f.gnss_prior().ToGeodetic(p).value();
        GnssFix fix;
        fix.stamp = kT0.PlusSeconds(0.01 * k);
        fix.latitude_deg = g.latitude_deg;
        fix.longitude_deg = g.longitude_deg;
        fix.height_m = g.height_m;
        fix.type = GnssFixType::kRtkFixed;
        benchmark::DoNotOptimize(f.AddGnss(fix));
      }
    }
  }
  state.SetItemsProcessed(state.iterations() * 100);
}
BENCHMARK(BM_InsFilterPredictUpdate1s)->Unit(benchmark::kMicrosecond);

void BM_ImuPreintegration10Samples(benchmark::State& state) {
  for (auto _ : state) {
    ImuPreintegration pre(ImuPreintegration::Options(), Eigen::Vector3d::Zero(),
                          Eigen::Vector3d::Zero());
    for (int k = 0; k < 10; ++k) {
      const ImuSample s = Sample(k);
      benchmark::DoNotOptimize(pre.Integrate(s.accel_mps2, s.gyro_radps, 0.01));
    }
    benchmark::DoNotOptimize(pre.delta_p());
  }
}
BENCHMARK(BM_ImuPreintegration10Samples);

struct FactorFixture {
  std::unique_ptr<ImuPreintegrationFactor> factor;
  std::array<double, 7> pi{}, pj{};
  std::array<double, 3> vi{}, vj{};
  std::array<double, 6> bi{}, bj{};
  FactorFixture() {
    ImuPreintegration pre(ImuPreintegration::Options(), Eigen::Vector3d::Zero(),
                          Eigen::Vector3d::Zero());
    for (int k = 0; k < 10; ++k)
      (void)pre.Integrate(Sample(k).accel_mps2, Sample(k).gyro_radps, 0.01);
    factor = std::move(ImuPreintegrationFactor::Create(pre, Eigen::Vector3d(0, 0, -9.81)).value());
    PoseToBlock(MakeIsometry(so3::Exp(Eigen::Vector3d(0.1, 0.2, 0.3)), Eigen::Vector3d(1, 2, 3)),
                pi.data());
    PoseToBlock(MakeIsometry(so3::Exp(Eigen::Vector3d(0.1, 0.2, 0.35)), Eigen::Vector3d(2, 2, 3)),
                pj.data());
    vi = {10, 0, 0};
    vj = {10, 0.1, 0};
  }
};

void BM_ImuPreintegrationFactorEvaluate(benchmark::State& state) {
  FactorFixture fx;
  const double* params[6] = {fx.pi.data(), fx.vi.data(), fx.bi.data(),
                             fx.pj.data(), fx.vj.data(), fx.bj.data()};
  double r[15];
  double j0[15 * 7], j1[15 * 3], j2[15 * 6], j3[15 * 7], j4[15 * 3], j5[15 * 6];
  double* jac[6] = {j0, j1, j2, j3, j4, j5};
  const bool with_jacobians = state.range(0) != 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(fx.factor->Evaluate(params, r, with_jacobians ? jac : nullptr));
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_ImuPreintegrationFactorEvaluate)->Arg(0)->Arg(1)->ArgNames({"jacobians"});

void BM_GnssPositionFactorEvaluate(benchmark::State& state) {
  auto f = GnssPositionFactor::Create(Eigen::Vector3d(1, 2, 3), 0.01 * Eigen::Matrix3d::Identity(),
                                      Eigen::Vector3d(0.5, 0.2, 1.2))
               .value();
  std::array<double, 7> pose{};
  PoseToBlock(MakeIsometry(so3::Exp(Eigen::Vector3d(0.1, 0.2, 0.3)), Eigen::Vector3d(1, 2, 3)),
              pose.data());
  const double* params[1] = {pose.data()};
  double r[3], j[21];
  double* jac[1] = {j};
  for (auto _ : state) {
    benchmark::DoNotOptimize(f->Evaluate(params, r, jac));
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_GnssPositionFactorEvaluate);

}  // namespace
