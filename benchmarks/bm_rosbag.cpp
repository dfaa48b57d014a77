// rosbag benchmarks: the 50 real KITTI scans of drive 0013 written once as a ROS 1 bag (with the
// per-point `time` field when range(0) == 1, as kitti2bag without it when 0), then read back scan
// by scan through RosbagDriveReader::ReadScan (one message per call: a [t, t] View on the bag
// index, deserialisation, decoding). items/s = scans/s; `x_realtime` = scans/s over the 10 Hz of
// the sensor (wall-clock time). BM_RosbagOpen is Open's cost (topic choice, IMU/GNSS pass, one read
// of each cloud for its stamps). Skipped when ../shared/data is absent (see bm_io.cpp for where it
// is looked for).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <map>

#include "slam_mms/io/kitti_drive_reader.hpp"
#include "slam_mms/rosbag/rosbag_drive_reader.hpp"
#include "slam_mms/rosbag/rosbag_writer.hpp"

namespace {

namespace fs = std::filesystem;

fs::path KittiDrive() {
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

// The bag of the real drive (written once per process and variant), or "" with `error` set.
fs::path KittiBag(bool with_time, std::string* error) {
  static std::map<bool, fs::path> bags;
  if (auto it = bags.find(with_time); it != bags.end()) return it->second;
  const fs::path drive = KittiDrive();
  if (drive.empty()) {
    *error = "real KITTI data not found (set SLAM_MMS_SHARED_DATA)";
    return {};
  }
  auto kitti = slam_mms::KittiDriveReader::Open(drive, slam_mms::KittiRawReader::Options());
  if (!kitti.ok()) {
    *error = kitti.status().ToString();
    return {};
  }
  const fs::path bag =
      fs::temp_directory_path() / ("slam_mms_bm_rosbag_" + std::to_string(::getpid()) +
                                   (with_time ? "_time" : "_notime") + ".bag");
  slam_mms::RosbagWriteOptions w;
  w.write_point_time = with_time;
  if (const slam_mms::Status s = slam_mms::WriteRosbag(**kitti, bag, w); !s.ok()) {
    *error = s.ToString();
    return {};
  }
  std::atexit([] {
    std::error_code ec;
    for (const auto& [k, p] : bags) fs::remove(p, ec);
  });
  return bags[with_time] = bag;
}

slam_mms::RosbagDriveReader::Options ReaderOptions() {
  slam_mms::RosbagDriveReader::Options o;
  o.lidar_topic = "/velodyne_points";
  return o;
}

void BM_RosbagReadScans(benchmark::State& state) {
  std::string error;
  const fs::path bag = KittiBag(state.range(0) != 0, &error);
  if (bag.empty()) {
    state.SkipWithError(error.c_str());
    return;
  }
  auto reader = slam_mms::RosbagDriveReader::Open(bag, ReaderOptions());
  if (!reader.ok()) {
    state.SkipWithError(reader.status().ToString().c_str());
    return;
  }
  const size_t n = (*reader)->NumScans();
  size_t points = 0;
  for (auto _ : state) {
    for (size_t i = 0; i < n; ++i) {
      auto scan = (*reader)->ReadScan(i);
      if (!scan.ok()) {
        state.SkipWithError(scan.status().ToString().c_str());
        return;
      }
      points += scan->cloud.size();
      benchmark::DoNotOptimize(scan->cloud.points().data());
    }
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * n));
  state.counters["points"] =
      benchmark::Counter(static_cast<double>(points), benchmark::Counter::kIsRate);
  state.counters["x_realtime"] = benchmark::Counter(
      static_cast<double>(state.iterations() * n) / 10.0, benchmark::Counter::kIsRate);
  state.counters["scans"] = static_cast<double>(n);
}
BENCHMARK(BM_RosbagReadScans)
    ->ArgName("time_field")
    ->Arg(1)
    ->Arg(0)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_RosbagOpen(benchmark::State& state) {
  std::string error;
  const fs::path bag = KittiBag(state.range(0) != 0, &error);
  if (bag.empty()) {
    state.SkipWithError(error.c_str());
    return;
  }
  for (auto _ : state) {
    auto reader = slam_mms::RosbagDriveReader::Open(bag, ReaderOptions());
    if (!reader.ok()) {
      state.SkipWithError(reader.status().ToString().c_str());
      return;
    }
    benchmark::DoNotOptimize(reader->get());
  }
}
BENCHMARK(BM_RosbagOpen)->ArgName("time_field")->Arg(1)->Arg(0)->Unit(benchmark::kMillisecond);

}  // namespace
