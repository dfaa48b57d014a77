// io benchmarks: reading one real KITTI scan (skipped when ../shared/data is absent) and writing
// maps. The data folder: $SLAM_MMS_SHARED_DATA, else ../shared/data from the working directory or
// from the repository that holds this build.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <random>

#include "slam_mms/io/drive_folder_writer.hpp"
#include "slam_mms/io/folder_drive_reader.hpp"
#include "slam_mms/io/kitti_drive_reader.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "slam_mms/io/map_io.hpp"

namespace {

namespace fs = std::filesystem;

fs::path KittiDriveDir() {
  std::vector<fs::path> roots;
  if (const char* env = std::getenv("SLAM_MMS_SHARED_DATA"); env != nullptr && *env != '\0') {
    roots.emplace_back(env);
  }
  roots.emplace_back(fs::path("..") / "shared" / "data");
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    // <repo>/<build>/benchmarks/slam_mms_benchmarks or <repo>/<build>/slam_mms_benchmarks
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

// Reads scan 0 of the real drive through KittiRawReader (binary read, NaN check, per-point time
// from azimuth when range(0) == 1, 0.205 deg vertical correction when range(1) == 1).
void BM_ReadKittiBin(benchmark::State& state) {
  const fs::path drive = KittiDriveDir();
  if (drive.empty()) {
    state.SkipWithError("real KITTI data not found (set SLAM_MMS_SHARED_DATA)");
    return;
  }
  slam_mms::KittiRawReader::Options options;
  options.per_point_time = state.range(0) != 0;
  options.vertical_angle_correction = state.range(1) != 0;
  auto reader = slam_mms::KittiRawReader::Open(drive, options);
  if (!reader.ok()) {
    state.SkipWithError(reader.status().ToString().c_str());
    return;
  }
  size_t points = 0;
  for (auto _ : state) {
    auto scan = reader->ReadScan(0);
    if (!scan.ok()) {
      state.SkipWithError(scan.status().ToString().c_str());
      return;
    }
    points = scan->cloud.size();
    benchmark::DoNotOptimize(scan->cloud.points().data());
  }
  state.counters["points"] = static_cast<double>(points);
  state.SetItemsProcessed(state.iterations() * static_cast<int64_t>(points));
  state.SetBytesProcessed(state.iterations() * static_cast<int64_t>(points) * 16);
}
BENCHMARK(BM_ReadKittiBin)
    ->ArgNames({"time", "vcorr"})
    ->Args({1, 0})
    ->Args({0, 0})
    ->Args({1, 1})
    ->Unit(benchmark::kMillisecond);

// Reads the real drive's 50 scans, written once as a drive folder of binary PCD files
// (WriteDriveFolder), through FolderDriveReader::ReadScan with per-point time from the azimuth:
// the folder read speed of docs/drive_folder.md (scans/s = items_per_second / points).
void BM_ReadFolderPcdScan(benchmark::State& state) {
  const fs::path drive = KittiDriveDir();
  if (drive.empty()) {
    state.SkipWithError("real KITTI data not found (set SLAM_MMS_SHARED_DATA)");
    return;
  }
  const fs::path dir =
      fs::temp_directory_path() / ("slam_mms_bm_folder_" + std::to_string(getpid()));
  auto kitti = slam_mms::KittiDriveReader::Open(drive, slam_mms::KittiRawReader::Options());
  slam_mms::FolderWriteOptions write;
  write.overwrite = true;
  if (!kitti.ok() || !slam_mms::WriteDriveFolder(**kitti, dir, write).ok()) {
    state.SkipWithError("cannot write the drive folder");
    return;
  }
  auto folder = slam_mms::FolderDriveReader::Open(dir, slam_mms::FolderDriveReader::Options());
  if (!folder.ok()) {
    state.SkipWithError(folder.status().ToString().c_str());
    return;
  }
  size_t i = 0, points = 0;
  for (auto _ : state) {
    auto scan = (*folder)->ReadScan(i++ % (*folder)->NumScans());
    if (!scan.ok()) {
      state.SkipWithError(scan.status().ToString().c_str());
      break;
    }
    points += scan->cloud.size();
    benchmark::DoNotOptimize(scan->cloud.points().data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(points));
  state.counters["scans_per_s"] =
      benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
  std::error_code ec;
  fs::remove_all(dir, ec);
}
BENCHMARK(BM_ReadFolderPcdScan)->Unit(benchmark::kMillisecond)->Iterations(50);

slam_mms::MapCloud BenchMap(size_t n) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<float> u(-500.0f, 500.0f);
  slam_mms::MapCloud map;
  map.cloud.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    map.cloud.Add(Eigen::Vector3f(u(rng), u(rng), 0.01f * u(rng)), 0.5f);
    map.normals.emplace_back(0.0f, 0.0f, 1.0f);
  }
  return map;
}

fs::path BenchFile(const char* name) {
  return fs::temp_directory_path() / ("slam_mms_bm_" + std::to_string(getpid()) + "_" + name);
}

// Writes a binary PLY map of range(0) points with normals.
void BM_WritePly(benchmark::State& state) {
  const slam_mms::MapCloud map = BenchMap(static_cast<size_t>(state.range(0)));
  const fs::path file = BenchFile("map.ply");
  for (auto _ : state) {
    const slam_mms::Status s = slam_mms::WritePly(map, file);
    if (!s.ok()) {
      state.SkipWithError(s.ToString().c_str());
      break;
    }
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
  std::error_code ec;
  fs::remove(file, ec);
}
BENCHMARK(BM_WritePly)->Arg(100000)->Arg(1000000)->Unit(benchmark::kMillisecond);

// Writes a LAS 1.4 map of range(0) points (ENU -> geodetic -> UTM per point).
void BM_WriteLas(benchmark::State& state) {
  const slam_mms::MapCloud map = BenchMap(static_cast<size_t>(state.range(0)));
  const fs::path file = BenchFile("map.las");
  const slam_mms::GeodeticPoint origin{49.013141872681, 8.4378138518088, 114.06644439697};
  for (auto _ : state) {
    const slam_mms::Status s = slam_mms::WriteLas(map, origin, file);
    if (!s.ok()) {
      state.SkipWithError(s.ToString().c_str());
      break;
    }
  }
  state.SetItemsProcessed(state.iterations() * state.range(0));
  std::error_code ec;
  fs::remove(file, ec);
}
BENCHMARK(BM_WriteLas)->Arg(100000)->Unit(benchmark::kMillisecond);

}  // namespace
