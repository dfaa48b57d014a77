// Surfel rendering and fusion benchmarks (issue 5). Names are parsed by other tools: keep
// BM_RenderEgl/<surfels>, BM_RenderCpu/<surfels>, BM_SurfelIntegrate.
//
// BM_Render*: one full Render() call (upload, draw, readback for EGL) of N surfels of a synthetic
// street (ground, facades, boxes within 60 m; SuMa radii) into the 64 x 2048 HDL-64 model image.
// BM_SurfelIntegrate: SurfelMap::Integrate of one simulated HDL-64 scan (64 x 2048 rays, ~120k
// returns) of a street while driving, on a map warmed up with earlier scans; the active map and its
// association render are included.
#include <benchmark/benchmark.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <vector>

#if SLAM_MMS_HAVE_EGL
#include "render_egl/egl_surfel_renderer.hpp"
#endif
#include "slam_mms/surfel/range_projection.hpp"
#include "slam_mms/surfel/surfel_map.hpp"
#include "surfel/cpu_surfel_renderer.hpp"
#include "surfel/synthetic_surfels.hpp"

namespace {

using slam_mms::Surfel;

const std::vector<Surfel>& StreetSurfels(size_t n) {
  static std::vector<Surfel> s100k = slam_mms::internal::MakeStreetSurfels(100000, 1);
  static std::vector<Surfel> s1m;
  if (n == 100000) return s100k;
  if (s1m.size() != n) s1m = slam_mms::internal::MakeStreetSurfels(n, 1);
  return s1m;
}

Eigen::Isometry3d RenderPose() {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0.5, 0.2, 0.0);
  T.linear() = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return T;
}

void BM_RenderCpu(benchmark::State& state) {
  const auto& surfels = StreetSurfels(static_cast<size_t>(state.range(0)));
  slam_mms::CpuSurfelRenderer renderer;
  slam_mms::VertexNormalMap img;
  for (auto _ : state) {
    const slam_mms::Status s =
        renderer.Render(slam_mms::SurfelRenderInput::All(surfels), RenderPose(), &img);
    if (!s.ok()) state.SkipWithError(s.ToString().c_str());
    benchmark::DoNotOptimize(img.range.data());
  }
  state.counters["valid_px"] = img.CountVertices();
}
BENCHMARK(BM_RenderCpu)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);

void BM_RenderEgl(benchmark::State& state) {
  const auto& surfels = StreetSurfels(static_cast<size_t>(state.range(0)));
#if !SLAM_MMS_HAVE_EGL
  (void)surfels;
  state.SkipWithError("EGL was not built (SLAM_MMS_WITH_EGL=OFF)");
  for (auto _ : state) {
  }
#else
  // range(1): the renderer's host threads (gather and unpack; BM_RenderCpu runs on 2).
  auto renderer = slam_mms::EglSurfelRenderer::Create(slam_mms::SurfelRendererOptions(),
                                                      static_cast<int>(state.range(1)));
  if (!renderer.ok()) {
    state.SkipWithError(renderer.status().ToString().c_str());
    for (auto _ : state) {
    }
    return;
  }
  slam_mms::VertexNormalMap img;
  // First frame compiles/warms the pipeline; not timed.
  (void)(*renderer)->Render(slam_mms::SurfelRenderInput::All(surfels), RenderPose(), &img);
  for (auto _ : state) {
    const slam_mms::Status s =
        (*renderer)->Render(slam_mms::SurfelRenderInput::All(surfels), RenderPose(), &img);
    if (!s.ok()) state.SkipWithError(s.ToString().c_str());
    benchmark::DoNotOptimize(img.range.data());
  }
  state.counters["valid_px"] = img.CountVertices();
  state.SetLabel((*renderer)->gl_renderer());
#endif
}
BENCHMARK(BM_RenderEgl)
    ->ArgsProduct({{100000, 1000000}, {1, 2, 16}})
    ->ArgNames({"surfels", "threads"})
    ->Unit(benchmark::kMillisecond);

// A street: ground, two facades, an end wall and boxes (parked cars, poles).
double CastStreet(const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double best = std::numeric_limits<double>::infinity();
  const struct {
    Eigen::Vector3d n;
    double offset;
  } planes[] = {{{0, 0, 1}, -1.73}, {{0, 1, 0}, 9.0}, {{0, -1, 0}, 9.0}, {{1, 0, 0}, 300.0}};
  for (const auto& p : planes) {
    const double den = p.n.dot(d);
    if (std::abs(den) < 1e-9) continue;
    const double t = (p.offset - p.n.dot(o)) / den;
    if (t > 0 && t < best) best = t;
  }
  for (int b = 0; b < 60; ++b) {
    const double x0 = -40.0 + 7.0 * b;
    const double side = (b % 2 == 0) ? 1.0 : -1.0;
    const Eigen::Vector3d lo(x0, side > 0 ? 4.0 : -6.0, -1.73);
    const Eigen::Vector3d hi(x0 + 4.2, side > 0 ? 6.0 : -4.0, -0.3 + 0.1 * (b % 5));
    double t0 = 0, t1 = best;
    for (int a = 0; a < 3; ++a) {
      const double inv = 1.0 / d[a];
      double ta = (lo[a] - o[a]) * inv, tb = (hi[a] - o[a]) * inv;
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
    }
    if (t0 <= t1 && t0 > 0) best = t0;
  }
  return best;
}

struct ScanSequence {
  std::vector<slam_mms::VertexNormalMap> scans;
  std::vector<Eigen::Isometry3d> poses;
  size_t num_points = 0;
};

const ScanSequence& Sequence() {
  static const ScanSequence seq = [] {
    ScanSequence s;
    slam_mms::RangeProjection proj;
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> jitter(0.05f, 0.95f);
    std::normal_distribution<double> noise(0.0, 0.015);
    for (int f = 0; f < 24; ++f) {
      Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
      T.translation() = Eigen::Vector3d(1.0 * f, 0.5 * std::sin(0.2 * f), 0.0);
      T.linear() =
          Eigen::AngleAxisd(0.02 * std::sin(0.3 * f), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      slam_mms::PointCloud cloud;
      for (int r = 0; r < proj.rows(); ++r) {
        for (int c = 0; c < proj.cols(); ++c) {
          const Eigen::Vector3d d_s =
              proj.Unproject(c + jitter(rng), r + jitter(rng), 1.0f).cast<double>().normalized();
          const double t = CastStreet(T.translation(), T.linear() * d_s);
          if (t < 100.0) cloud.Add(((t + noise(rng)) * d_s).cast<float>());
        }
      }
      s.num_points += cloud.size();
      slam_mms::VertexNormalMap m;
      proj.ComputeVertexNormalMap(cloud, &m);
      s.scans.push_back(std::move(m));
      s.poses.push_back(T);
    }
    s.num_points /= s.scans.size();
    return s;
  }();
  return seq;
}

void BM_SurfelIntegrate(benchmark::State& state) {
  const ScanSequence& seq = Sequence();
  slam_mms::SurfelMap map;
  const size_t warm = 8;
  for (size_t f = 0; f < warm; ++f) {
    (void)map.Integrate(seq.scans[f], seq.poses[f], slam_mms::Timestamp::FromNanoseconds(f));
  }
  size_t f = warm;
  slam_mms::SurfelIntegrationStats last;
  for (auto _ : state) {
    auto s = map.Integrate(seq.scans[f], seq.poses[f], slam_mms::Timestamp::FromNanoseconds(f));
    if (!s.ok()) state.SkipWithError(s.status().ToString().c_str());
    last = *s;
    if (++f == seq.scans.size()) f = warm;  // drive the stretch again (revisits)
  }
  state.counters["points"] = static_cast<double>(seq.num_points);
  state.counters["active"] = last.num_active;
  state.counters["surfels"] = static_cast<double>(last.num_surfels);
  state.counters["created"] = last.num_created;
}
BENCHMARK(BM_SurfelIntegrate)->Unit(benchmark::kMillisecond);

void BM_VertexNormalMap(benchmark::State& state) {
  slam_mms::RangeProjection proj;
  slam_mms::PointCloud cloud;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> jitter(0.05f, 0.95f);
  for (int r = 0; r < proj.rows(); ++r) {
    for (int c = 0; c < proj.cols(); ++c) {
      const Eigen::Vector3d d =
          proj.Unproject(c + jitter(rng), r + jitter(rng), 1.0f).cast<double>().normalized();
      const double t = CastStreet(Eigen::Vector3d::Zero(), d);
      if (t < 100.0) cloud.Add((t * d).cast<float>());
    }
  }
  slam_mms::VertexNormalMap m;
  for (auto _ : state) {
    proj.ComputeVertexNormalMap(cloud, &m);
    benchmark::DoNotOptimize(m.normal.data());
  }
  state.counters["points"] = static_cast<double>(cloud.size());
}
BENCHMARK(BM_VertexNormalMap)->Unit(benchmark::kMillisecond);

}  // namespace
