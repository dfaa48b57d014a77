// Registration benchmarks (median of repetitions is what the reports quote):
//   BM_ProjectiveIcp       one full 64 x 2048 synthetic street scan (~110k valid pixels) against a
//                          model image rendered at the identity, starting from a typical prediction
//                          error (0.1 m, 0.5 deg) around the true motion.
//   BM_ProjectiveIcpKitti  real KITTI 0013 scan 21 against scan 20's vertex/normal map
//                          (frame-to-frame), constant-velocity start (OXTS motion of 19 -> 20);
//                          skipped without ../shared/data.
//   BM_PointIcp            KD-tree ICP of one scan (0.3 m voxels) against a map of three scans.
//   BM_PointIcpSetTarget   KD-tree build + PCA normals for that map.
// "threads" is Options::num_threads (2 = the default, the budget's 2 cores; 1 shows the work);
// "stride" is Options::pixel_stride (1 = every valid scan pixel, the default).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <memory>

#include "../tests/registration/kitti_frames.hpp"
#include "../tests/registration/synthetic_scene.hpp"
#include "registration/point_icp.hpp"
#include "registration/projective_icp.hpp"
#include "slam_mms/core/lie.hpp"

namespace {

namespace fs = std::filesystem;
using namespace slam_mms;  // NOLINT

fs::path RegKittiDriveDir() {
  std::vector<fs::path> roots;
  if (const char* env = std::getenv("SLAM_MMS_SHARED_DATA"); env != nullptr && *env != '\0') {
    roots.emplace_back(env);
  }
  roots.emplace_back(fs::path("..") / "shared" / "data");
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    for (fs::path p = exe.parent_path(); !p.empty() && p != p.root_path(); p = p.parent_path()) {
      roots.push_back(p.parent_path() / "shared" / "data");
    }
  }
  for (const auto& r : roots) {
    const fs::path d = r / "kitti_raw" / "2011_09_26" / "2011_09_26_drive_0013_sync";
    if (fs::is_directory(d / "velodyne_points", ec)) return d;
  }
  return {};
}

struct SyntheticProblem {
  RangeProjection proj;  // 64 x 2048
  VertexNormalMap model, scan;
  Eigen::Isometry3d T_true, init;
  PointCloud map, scan_cloud;
};

const SyntheticProblem& Synthetic() {
  static const std::unique_ptr<SyntheticProblem> p = [] {
    auto s = std::make_unique<SyntheticProblem>();
    const testing::Scene scene = testing::MakeStreetScene();
    const Eigen::Isometry3d T_world_scan =
        MakeIsometry(FromRollPitchYaw(0.01, -0.02, 0.05), Eigen::Vector3d(1.2, 0.3, 0.05));
    s->model = testing::RenderModel(scene, s->proj, Eigen::Isometry3d::Identity());
    s->scan_cloud = testing::SimulateScan(scene, s->proj, T_world_scan, 0.01, 2);
    s->proj.ComputeVertexNormalMap(s->scan_cloud, &s->scan);
    s->T_true = T_world_scan;
    Vector6d err;
    err << 0.5 * M_PI / 180.0 * Eigen::Vector3d(0.6, -0.48, 0.64),
        0.1 * Eigen::Vector3d(0.8, 0.0, 0.6);
    s->init = T_world_scan * se3::Exp(err);
    // Map: three scans from poses 1.5 m apart, in the frame of the middle one (identity).
    for (int i = -1; i <= 1; ++i) {
      const Eigen::Isometry3d T =
          MakeIsometry(Eigen::Matrix3d::Identity(), Eigen::Vector3d(1.5 * i, 0.0, 0.0));
      const PointCloud c = testing::SimulateScan(scene, s->proj, T, 0.01, 10 + i);
      for (const auto& p : c.points()) s->map.Add((T * p.cast<double>()).cast<float>());
    }
    return s;
  }();
  return *p;
}

void BM_ProjectiveIcp(benchmark::State& state) {
  const SyntheticProblem& s = Synthetic();
  ProjectiveIcp::Options o;
  o.num_threads = static_cast<int>(state.range(0));
  o.pixel_stride = static_cast<int>(state.range(1));
  auto icp = ProjectiveIcp::Create(s.proj, o).value();
  RegistrationResult r;
  for (auto _ : state) {
    r = icp.Align(s.scan, s.model, s.init).value();
    benchmark::DoNotOptimize(r);
  }
  state.counters["valid_pixels"] = s.scan.CountNormals();
  state.counters["iterations"] = r.iterations;
  state.counters["inliers"] = static_cast<double>(r.num_inliers);
  state.counters["err_mm"] = 1e3 * (s.T_true.inverse() * r.T_target_source).translation().norm();
}
BENCHMARK(BM_ProjectiveIcp)
    ->ArgNames({"threads", "stride"})
    ->Args({2, 1})
    ->Args({1, 1})
    ->Args({2, 2})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_ProjectiveIcpKitti(benchmark::State& state) {
  const fs::path dir = RegKittiDriveDir();
  testing::KittiDrive drive;
  if (dir.empty() || !drive.Load(dir, 50)) {
    state.SkipWithError("real KITTI data not found (set SLAM_MMS_SHARED_DATA)");
    return;
  }
  const RangeProjection proj;
  VertexNormalMap model, scan;
  proj.ComputeVertexNormalMap(drive.Scan(20, true), &model);
  proj.ComputeVertexNormalMap(drive.Scan(21, true), &scan);
  const Eigen::Isometry3d init = drive.RelativeLidar(19, 20);  // constant velocity
  const Eigen::Isometry3d T_ref = drive.RelativeLidar(20, 21);
  ProjectiveIcp::Options o;
  o.num_threads = static_cast<int>(state.range(0));
  auto icp = ProjectiveIcp::Create(proj, o).value();
  RegistrationResult r;
  for (auto _ : state) {
    r = icp.Align(scan, model, init).value();
    benchmark::DoNotOptimize(r);
  }
  state.counters["valid_pixels"] = scan.CountNormals();
  state.counters["iterations"] = r.iterations;
  state.counters["inliers"] = static_cast<double>(r.num_inliers);
  state.counters["err_vs_oxts_mm"] =
      1e3 * (T_ref.inverse() * r.T_target_source).translation().norm();
}
BENCHMARK(BM_ProjectiveIcpKitti)
    ->ArgName("threads")
    ->Arg(2)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_PointIcp(benchmark::State& state) {
  const SyntheticProblem& s = Synthetic();
  PointIcp::Options o;
  o.source_voxel_size = 0.3;
  auto icp = PointIcp::Create(o).value();
  if (!icp.SetTarget(s.map.View()).ok()) {
    state.SkipWithError("SetTarget failed");
    return;
  }
  RegistrationResult r;
  for (auto _ : state) {
    r = icp.Align(s.scan_cloud.View(), s.init).value();
    benchmark::DoNotOptimize(r);
  }
  state.counters["map_points"] = static_cast<double>(s.map.size());
  state.counters["iterations"] = r.iterations;
  state.counters["inliers"] = static_cast<double>(r.num_inliers);
  state.counters["err_mm"] = 1e3 * (s.T_true.inverse() * r.T_target_source).translation().norm();
}
BENCHMARK(BM_PointIcp)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_PointIcpSetTarget(benchmark::State& state) {
  const SyntheticProblem& s = Synthetic();
  PointIcp icp;
  for (auto _ : state) {
    benchmark::DoNotOptimize(icp.SetTarget(s.map.View()));
  }
  state.counters["map_points"] = static_cast<double>(s.map.size());
}
BENCHMARK(BM_PointIcpSetTarget)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
