// slam_mms_bench_e2e: the end-to-end benchmark (issue 9). Runs MappingSystem on a drive and reports
// throughput (scans/s), the per-stage level-1 milliseconds per scan (median, p90, max; from each
// LocalizationResult's StageTimings), the time spent outside level 1 (level 2, POS), scan reading,
// and memory: peak RSS (VmHWM) and RSS sampled along the drive, to show whether it stays flat.
//
//   slam_mms_bench_e2e [--duration-s S] [--seed N] [--sim-dir DIR]     simulated default drive
//   slam_mms_bench_e2e --kitti-raw DRIVE_DIR [--frames A:B]             a KITTI raw drive
//   slam_mms_bench_e2e --folder DIR | --rosbag FILE.bag [--extrinsics FILE.yaml] [--frames A:B]
//                                                    a plain drive folder or a ROS 1 bag
//   common: [--mode full|gnss_ins|lidar_only] [--out FILE.json] [--rss-samples N]
//           [--threads N] [--renderer auto|cpu|egl]
//   slam_mms_bench_e2e --version | --help        (values: `--flag value` or `--flag=value`)
//
// The simulated drive is written to --sim-dir (kept, and reused when it already holds the same
// seed and duration) or to a temporary folder removed at exit. Prints a table to stdout and, with
// --out, the same numbers as JSON. Exit status: 0 ok, 1 run failed or processed no scan, 2 bad
// command line, 77 the --kitti-raw/--folder/--rosbag input does not exist (lets a smoke test skip).

#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "app_common/huge_page_malloc.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/drive/drive_runner.hpp"
#include "slam_mms/drive/open_drive.hpp"
#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"
#include "slam_mms/sim/drive_simulator.hpp"
#include "slam_mms/version.hpp"

namespace fs = std::filesystem;
using slam_mms::MappingMode;
using slam_mms::MappingSystem;
using slam_mms::Status;
using slam_mms::StatusOr;

namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct Args {
  double duration_s = 30.0;
  uint64_t seed = 1;
  std::string scenario = "default";
  std::string mode = "full";
  fs::path input;  // --kitti-raw, --folder or --rosbag; empty: simulate
  slam_mms::DriveSourceKind kind = slam_mms::DriveSourceKind::kKittiRaw;
  fs::path extrinsics;
  int64_t first_frame = 0;
  int64_t last_frame = -1;
  fs::path out;
  fs::path sim_dir;
  int rss_samples = 40;
  fs::path spill_dir = fs::temp_directory_path();  // empty: submap clouds stay in memory
  int threads = MappingSystem::Options().num_threads;
  slam_mms::SurfelRendererBackend renderer = slam_mms::SurfelRendererBackend::kAuto;
};

constexpr const char* kUsage =
    "usage: slam_mms_bench_e2e [--duration-s S] [--seed N] [--scenario default|long]\n"
    "                          [--sim-dir DIR]\n"
    "       slam_mms_bench_e2e --kitti-raw DRIVE_DIR [--frames A:B]\n"
    "       slam_mms_bench_e2e --folder DIR | --rosbag FILE.bag [--extrinsics FILE.yaml]\n"
    "                          [--frames A:B]\n"
    "  common: [--mode full|gnss_ins|lidar_only] [--out FILE.json] [--rss-samples N]\n"
    "          [--spill-dir DIR|none]   finished submaps' clouds (default: the temp folder)\n"
    "          [--threads N]            MappingSystem::Options::num_threads (default 2)\n"
    "          [--renderer auto|cpu|egl] the surfel renderer (default auto: EGL on a GPU)\n";

// The command line (CLI11: `--flag value` and `--flag=value`); values are checked here so that the
// messages say what was expected. --help prints the usage and exits 0, --version the version.
bool ParseArgs(int argc, char** argv, Args* a, std::string* error) {
  CLI::App app("slam_mms_bench_e2e", "slam_mms_bench_e2e");
  app.set_help_flag();
  bool help = false, version = false;
  std::string duration, seed, mode, kitti_raw, folder, rosbag, frames, spill_dir, rss_samples;
  std::string threads, renderer;
  app.add_flag("-h,--help", help);
  app.add_flag("--version", version);
  app.add_option("--duration-s", duration);
  app.add_option("--scenario", a->scenario);
  app.add_option("--seed", seed);
  app.add_option("--mode", mode);
  app.add_option("--kitti-raw", kitti_raw);
  app.add_option("--folder", folder);
  app.add_option("--rosbag", rosbag);
  app.add_option("--extrinsics", a->extrinsics);
  app.add_option("--frames", frames);
  app.add_option("--out", a->out);
  app.add_option("--spill-dir", spill_dir);
  app.add_option("--sim-dir", a->sim_dir);
  app.add_option("--rss-samples", rss_samples);
  app.add_option("--threads", threads);
  app.add_option("--renderer", renderer);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    *error = e.what();
    return false;
  }
  if (help) {
    std::fputs(kUsage, stdout);
    std::exit(0);
  }
  if (version) {
    std::printf("slam_mms_bench_e2e %s\n", SLAM_MMS_VERSION_STRING);
    std::exit(0);
  }
  const auto given = [&app](const char* flag) { return app.count(flag) > 0; };
  char* end = nullptr;
  if (given("--duration-s")) {
    a->duration_s = std::strtod(duration.c_str(), &end);
    if (duration.empty() || *end != '\0' || !(a->duration_s > 0.0)) {
      *error = "--duration-s " + duration + ": must be a number > 0";
      return false;
    }
  }
  if (a->scenario != "default" && a->scenario != "long") {
    *error = "--scenario " + a->scenario + ": must be default or long";
    return false;
  }
  if (given("--seed")) {
    a->seed = std::strtoull(seed.c_str(), &end, 10);
    if (*end != '\0' || seed.empty() || seed[0] == '-') {
      *error = "--seed " + seed + ": must be a non-negative integer";
      return false;
    }
  }
  if (given("--mode")) {
    MappingMode m;
    if (!slam_mms::ParseMappingMode(mode, &m)) {
      *error = "--mode " + mode + ": must be full, gnss_ins or lidar_only";
      return false;
    }
    a->mode = mode;
  }
  if (given("--kitti-raw") + given("--folder") + given("--rosbag") > 1) {
    *error = "--kitti-raw, --folder and --rosbag exclude each other";
    return false;
  }
  if (given("--kitti-raw")) a->input = kitti_raw;
  if (given("--folder")) {
    a->input = folder;
    a->kind = slam_mms::DriveSourceKind::kFolder;
  }
  if (given("--rosbag")) {
    a->input = rosbag;
    a->kind = slam_mms::DriveSourceKind::kRosbag;
  }
  if (given("--frames")) {
    long long f0 = 0, f1 = 0;
    char tail = 0;
    if (std::sscanf(frames.c_str(), "%lld:%lld%c", &f0, &f1, &tail) != 2 || f0 < 0 || f1 < f0) {
      *error = "--frames " + frames + ": must be A:B with 0 <= A <= B";
      return false;
    }
    a->first_frame = f0;
    a->last_frame = f1;
  }
  if (given("--spill-dir")) a->spill_dir = spill_dir == "none" ? fs::path() : fs::path(spill_dir);
  if (given("--rss-samples")) {
    a->rss_samples = static_cast<int>(std::strtol(rss_samples.c_str(), &end, 10));
    if (rss_samples.empty() || *end != '\0' || a->rss_samples < 2) {
      *error = "--rss-samples " + rss_samples + ": must be an integer >= 2";
      return false;
    }
  }
  if (given("--threads")) {
    a->threads = static_cast<int>(std::strtol(threads.c_str(), &end, 10));
    if (threads.empty() || *end != '\0' || a->threads < 1 || a->threads > 64) {
      *error = "--threads " + threads + ": must be an integer in 1..64";
      return false;
    }
  }
  if (given("--renderer")) {
    if (renderer == "auto") {
      a->renderer = slam_mms::SurfelRendererBackend::kAuto;
    } else if (renderer == "cpu") {
      a->renderer = slam_mms::SurfelRendererBackend::kCpu;
    } else if (renderer == "egl") {
      a->renderer = slam_mms::SurfelRendererBackend::kEgl;
    } else {
      *error = "--renderer " + renderer + ": must be auto, cpu or egl";
      return false;
    }
  }
  return true;
}

// A field of /proc/self/status in MiB (VmRSS, VmHWM); -1 where unavailable.
double ProcStatusMb(const char* field) {
  std::ifstream f("/proc/self/status");
  std::string line;
  const std::string key = std::string(field) + ":";
  while (std::getline(f, line)) {
    if (line.compare(0, key.size(), key) == 0) {
      return std::strtod(line.c_str() + key.size(), nullptr) / 1024.0;  // kB
    }
  }
  return -1.0;
}

// The bytes the program holds from malloc, in MiB (glibc's mallinfo2 over all arenas: in use in
// the heaps plus the blocks mapped on their own); -1 without glibc. Beside the RSS it tells live
// data from memory the allocator keeps after a free.
double HeapInUseMb() {
#if defined(__GLIBC__)
  const struct mallinfo2 mi = mallinfo2();
  return static_cast<double>(mi.uordblks + mi.hblkhd) / (1024.0 * 1024.0);
#else
  return -1.0;
#endif
}

struct Percentiles {
  double median = 0, p90 = 0, max = 0, mean = 0;
};

Percentiles Summarize(std::vector<double> v) {
  Percentiles p;
  if (v.empty()) return p;
  std::sort(v.begin(), v.end());
  auto at = [&](double q) {
    const size_t i = static_cast<size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
    return v[std::min(i, v.size() - 1)];
  };
  p.median = at(0.5);
  p.p90 = at(0.9);
  p.max = v.back();
  double s = 0;
  for (double x : v) s += x;
  p.mean = s / static_cast<double>(v.size());
  return p;
}

// Simulates the default drive into dir (or reuses it when a marker says it holds the same one).
StatusOr<fs::path> SimulatedDrive(const Args& a, const fs::path& dir) {
  std::ostringstream want;
  want << "seed " << a.seed << " duration_s " << a.duration_s << " scenario " << a.scenario << "\n";
  const fs::path marker = dir / "bench_e2e_sim.txt";
  if (std::ifstream in(marker); in) {
    std::string have((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::string drive;
    const size_t nl = have.find('\n');
    if (nl != std::string::npos && have.substr(0, nl + 1) == want.str()) {
      drive = have.substr(nl + 1);
      while (!drive.empty() && drive.back() == '\n') drive.pop_back();
      if (fs::exists(drive)) {
        std::printf("[sim] reusing %s\n", drive.c_str());
        return fs::path(drive);
      }
    }
  }
  slam_mms::sim::DriveSimulator::Options so;
  so.scenario = a.scenario;
  so.duration_s = a.duration_s;
  so.seed = a.seed;
  so.write_scene_cloud = false;
  SLAM_MMS_ASSIGN_OR_RETURN(auto simulator, slam_mms::sim::DriveSimulator::Create(so));
  std::printf("[sim] simulating %.1f s of the %s drive (seed %" PRIu64 ") into %s\n", a.duration_s,
              a.scenario.c_str(), a.seed, dir.c_str());
  std::fflush(stdout);
  const auto t0 = Clock::now();
  SLAM_MMS_ASSIGN_OR_RETURN(auto summary, simulator.Run(dir));
  std::printf("[sim] %d scans, %.0f m, %.1f s wall\n", summary.num_scans, summary.path_length_m,
              MsSince(t0) / 1000.0);
  std::ofstream out(marker);
  out << want.str() << summary.drive_dir.string() << "\n";
  return summary.drive_dir;
}

struct RssSample {
  size_t scans = 0;
  double seconds = 0.0;
  double rss_mb = 0.0;
  double hwm_mb = 0.0;   // VmHWM so far: the peak of a drive cut at this point
  double heap_mb = 0.0;  // HeapInUseMb()
};

struct Report {
  std::string input, mode;
  int threads = 0;
  std::string renderer;  // the renderer the Localizer names in its log line ("cpu", an EGL one)
  size_t scans_total = 0, scans_processed = 0;
  int scans_skipped = 0;
  double drive_s = 0.0;
  double wall_s = 0.0, read_s = 0.0, finish_s = 0.0;
  double scans_per_s = 0.0, scans_per_s_no_io = 0.0;
  std::vector<std::pair<std::string, Percentiles>> stages;  // level-1 stages, then derived rows
  double level1_sum_s = 0.0, outside_level1_s = 0.0;
  slam_mms::Level2Stats level2;
  double peak_rss_mb = -1.0;
  double peak_rss_before_finish_mb = -1.0;  // VmHWM just before Finish()
  bool peak_reset = false;                  // VmHWM was reset after the simulation
  std::vector<RssSample> rss;
  size_t final_surfels = 0;
};

void PrintTable(const Report& r) {
  std::printf("\n== slam_mms_bench_e2e: %s, mode %s ==\n", r.input.c_str(), r.mode.c_str());
  std::printf("threads %d, surfel renderer %s\n", r.threads, r.renderer.c_str());
  std::printf(
      "scans %zu of %zu (%d skipped), drive %.1f s, wall %.2f s (reading scans %.2f s, "
      "Finish %.2f s)\n",
      r.scans_processed, r.scans_total, r.scans_skipped, r.drive_s, r.wall_s, r.read_s, r.finish_s);
  std::printf(
      "throughput: %.2f scans/s end to end (%.2fx real time), %.2f scans/s without "
      "reading scans\n",
      r.scans_per_s, r.wall_s > 0 ? r.drive_s / r.wall_s : 0.0, r.scans_per_s_no_io);
  std::printf("\n| stage [ms/scan] | median | p90 | max | mean |\n|---|---:|---:|---:|---:|\n");
  for (const auto& [name, p] : r.stages) {
    std::printf("| %s | %.2f | %.2f | %.2f | %.2f |\n", name.c_str(), p.median, p.p90, p.max,
                p.mean);
  }
  std::printf(
      "\nlevel 1 total %.2f s; outside level 1 (level 2, POS, queueing) %.2f s; level 2: "
      "%d solves, %d loops accepted of %d tested, last solve %.1f ms\n",
      r.level1_sum_s, r.outside_level1_s, r.level2.solves, r.level2.loops_accepted,
      r.level2.loops_tested, r.level2.last_solve_ms);
  std::printf("memory: peak RSS (VmHWM%s) %.1f MiB, %.1f MiB before Finish(); final surfels %zu\n",
              r.peak_reset ? " since the drive started" : ", including the simulation",
              r.peak_rss_mb, r.peak_rss_before_finish_mb, r.final_surfels);
  std::printf(
      "| scans done | wall [s] | RSS [MiB] | peak so far [MiB] | heap in use [MiB] "
      "|\n|---:|---:|---:|---:|---:|\n");
  // At most ~12 rows here (the JSON has every sample).
  const size_t step = std::max<size_t>(1, (r.rss.size() + 11) / 12);
  for (size_t i = 0; i < r.rss.size(); ++i) {
    if (i % step != 0 && i + 1 != r.rss.size()) continue;
    const RssSample& s = r.rss[i];
    std::printf("| %zu | %.1f | %.1f | %.1f | %.1f |\n", s.scans, s.seconds, s.rss_mb, s.hwm_mb,
                s.heap_mb);
  }
}

bool WriteJson(const Report& r, const fs::path& path) {
  using Json = nlohmann::ordered_json;
  Json j = Json::object();
  j["version"] = SLAM_MMS_VERSION_STRING;
  j["input"] = r.input;
  j["mode"] = r.mode;
  j["threads"] = r.threads;
  j["renderer"] = r.renderer;
  j["scans_total"] = r.scans_total;
  j["scans_processed"] = r.scans_processed;
  j["scans_skipped"] = r.scans_skipped;
  j["drive_s"] = r.drive_s;
  j["wall_s"] = r.wall_s;
  j["read_s"] = r.read_s;
  j["finish_s"] = r.finish_s;
  j["scans_per_s"] = r.scans_per_s;
  j["scans_per_s_without_reading"] = r.scans_per_s_no_io;
  j["level1_total_s"] = r.level1_sum_s;
  j["outside_level1_s"] = r.outside_level1_s;
  j["level2"] = Json{{"solves", r.level2.solves},
                     {"loops_tested", r.level2.loops_tested},
                     {"loops_accepted", r.level2.loops_accepted},
                     {"map_to_map_accepted", r.level2.map_to_map_accepted},
                     {"gnss_factors", r.level2.gnss_factors},
                     {"last_solve_ms", r.level2.last_solve_ms}};
  Json stages = Json::object();
  for (const auto& [name, p] : r.stages) {
    stages[name] = Json{{"median", p.median}, {"p90", p.p90}, {"max", p.max}, {"mean", p.mean}};
  }
  j["stages_ms"] = std::move(stages);
  j["peak_rss_mb"] = r.peak_rss_mb;
  j["peak_rss_before_finish_mb"] = r.peak_rss_before_finish_mb;
  j["peak_rss_reset_after_simulation"] = r.peak_reset;
  j["final_surfels"] = r.final_surfels;
  Json samples = Json::array();
  for (const RssSample& s : r.rss) {
    samples.push_back(Json{{"scans", s.scans},
                           {"wall_s", s.seconds},
                           {"rss_mb", s.rss_mb},
                           {"hwm_mb", s.hwm_mb},
                           {"heap_mb", s.heap_mb}});
  }
  j["rss_samples"] = std::move(samples);
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  if (!f) return false;
  // NaN/inf (an empty stage) are written as null.
  f << j.dump(2, ' ', false, Json::error_handler_t::replace) << "\n";
  return static_cast<bool>(f);
}

// Feeds the drive in time order (a scan once IMU and GNSS reached its end, as a sensor delivers
// it), timing every call.
Status FeedDrive(const slam_mms::DriveReader& reader, MappingMode mode, const Args& a, Report* r) {
  const slam_mms::DriveStreams& in = reader.streams();
  MappingSystem::Options options;
  options.mode = mode;
  options.num_threads = a.threads;
  options.localizer.renderer = a.renderer;
  options.localizer.spill_dir = a.spill_dir;
  options.T_body_lidar = in.T_body_lidar;
  if (in.t_body_antenna_m) options.ins.gnss.t_body_antenna = *in.t_body_antenna_m;
  options = slam_mms::ApplyInputModels(options, in);  // as RunDrive does
  std::vector<slam_mms::InsState> pos;
  if (!in.pos.empty()) {
    options.origin = slam_mms::GeodeticPoint{in.pos.front().latitude_deg,
                                             in.pos.front().longitude_deg, in.pos.front().height_m};
    SLAM_MMS_ASSIGN_OR_RETURN(pos, slam_mms::PosRecordsInWorld(in.pos, *options.origin));
  }
  SLAM_MMS_ASSIGN_OR_RETURN(auto system, MappingSystem::Create(options));

  std::vector<slam_mms::LocalizationResult> results;
  const size_t n_scans = reader.NumScans();
  const size_t every = std::max<size_t>(1, n_scans / static_cast<size_t>(a.rss_samples));
  const auto t_start = Clock::now();
  system->SetResultCallback([&](const slam_mms::LocalizationResult& res) {
    results.push_back(res);
    if (results.size() % every == 0 || results.size() == n_scans) {
      r->rss.push_back({results.size(), MsSince(t_start) / 1000.0, ProcStatusMb("VmRSS"),
                        ProcStatusMb("VmHWM"), HeapInUseMb()});
    }
  });
  r->rss.push_back({0, 0.0, ProcStatusMb("VmRSS"), ProcStatusMb("VmHWM"), HeapInUseMb()});

  // Initial POS attitude and velocity from the reader (as slam_mms_run does).
  if (pos.empty() && in.initial_state) {
    SLAM_MMS_RETURN_IF_ERROR(system->InitializePos(*in.initial_state));
  }
  // With an external POS the IMU/GNSS streams are not fed (MappingSystem::AddInsPose).
  static const std::vector<slam_mms::ImuSample> kNoImu;
  static const std::vector<slam_mms::GnssFix> kNoGnss;
  const std::vector<slam_mms::ImuSample>& imu = pos.empty() ? in.imu : kNoImu;
  const std::vector<slam_mms::GnssFix>& gnss = pos.empty() ? in.gnss : kNoGnss;
  size_t i_pos = 0;
  size_t i_imu = 0, i_gnss = 0;
  double read_ms = 0.0, feed_ms = 0.0;
  for (size_t k = 0; k < n_scans; ++k) {
    const slam_mms::Timestamp deliver = reader.ScanEnd(k);
    auto t0 = Clock::now();
    while (i_imu < imu.size() && imu[i_imu].stamp <= deliver) {
      SLAM_MMS_RETURN_IF_ERROR(system->AddImu(imu[i_imu++]));
    }
    while (i_gnss < gnss.size() && gnss[i_gnss].stamp <= deliver) {
      SLAM_MMS_RETURN_IF_ERROR(system->AddGnss(gnss[i_gnss++]));
    }
    while (i_pos < pos.size() && pos[i_pos].stamp <= deliver) {
      SLAM_MMS_RETURN_IF_ERROR(system->AddInsPose(pos[i_pos++]));
    }
    feed_ms += MsSince(t0);
    t0 = Clock::now();
    StatusOr<slam_mms::Scan> scan = reader.ReadScan(k);
    read_ms += MsSince(t0);
    if (!scan.ok()) {
      std::fprintf(stderr, "[bench] skipping scan %zu: %s\n", k, scan.status().ToString().c_str());
      continue;
    }
    t0 = Clock::now();
    SLAM_MMS_RETURN_IF_ERROR(system->AddScan(*scan));
    feed_ms += MsSince(t0);
  }
  r->peak_rss_before_finish_mb = ProcStatusMb("VmHWM");
  auto t0 = Clock::now();
  while (i_imu < imu.size()) SLAM_MMS_RETURN_IF_ERROR(system->AddImu(imu[i_imu++]));
  while (i_gnss < gnss.size()) SLAM_MMS_RETURN_IF_ERROR(system->AddGnss(gnss[i_gnss++]));
  while (i_pos < pos.size()) SLAM_MMS_RETURN_IF_ERROR(system->AddInsPose(pos[i_pos++]));
  SLAM_MMS_RETURN_IF_ERROR(system->Finish());
  const double finish_ms = MsSince(t0);
  r->wall_s = MsSince(t_start) / 1000.0;
  r->rss.push_back(
      {results.size(), r->wall_s, ProcStatusMb("VmRSS"), ProcStatusMb("VmHWM"), HeapInUseMb()});
  r->peak_rss_mb = ProcStatusMb("VmHWM");

  r->scans_processed = results.size();
  r->scans_skipped = system->num_skipped_scans();
  r->read_s = read_ms / 1000.0;
  r->finish_s = finish_ms / 1000.0;
  r->scans_per_s = r->wall_s > 0 ? static_cast<double>(results.size()) / r->wall_s : 0.0;
  const double no_io_s = r->wall_s - r->read_s;
  r->scans_per_s_no_io = no_io_s > 0 ? static_cast<double>(results.size()) / no_io_s : 0.0;
  r->level2 = system->level2_stats();
  r->final_surfels = system->SurfelMapSnapshot().size();

  const auto& names = slam_mms::StageTimings::Names();
  std::vector<std::vector<double>> per_stage(names.size());
  std::vector<double> total;
  for (const auto& res : results) {
    const auto v = res.timings.Values();
    for (size_t s = 0; s < names.size(); ++s) per_stage[s].push_back(v[s]);
    total.push_back(res.timings.total_ms);
    r->level1_sum_s += res.timings.total_ms / 1000.0;
  }
  for (size_t s = 0; s < names.size(); ++s) {
    r->stages.emplace_back(names[s], Summarize(per_stage[s]));
  }
  r->stages.emplace_back("level-1 total", Summarize(total));
  // Everything the feeding calls spent outside level 1's ProcessScan, spread over the scans.
  r->outside_level1_s = std::max(0.0, (feed_ms + finish_ms) / 1000.0 - r->level1_sum_s);
  return slam_mms::OkStatus();
}

}  // namespace

int main(int argc, char** argv) {
  // As slam_mms_run (SLAM_MMS_HUGE_PAGES=0 measures without).
  slam_mms::app::ReexecWithHugePageMalloc(argv);
  // Warnings and errors go to stderr; of the info lines only the Localizer's, which names the
  // surfel renderer it runs on, is read (for the report).
  Report report;
  slam_mms::SetLogSink([stderr_sink = slam_mms::StderrLogSink(), &report](
                           slam_mms::LogLevel level, const std::string& message) {
    static const std::string kTag = ", renderer ";
    if (level >= slam_mms::LogLevel::kWarning) {
      stderr_sink(level, message);
    } else if (message.rfind("Localizer: ", 0) == 0) {
      const size_t at = message.find(kTag);
      if (at != std::string::npos) {
        const size_t from = at + kTag.size();
        report.renderer = message.substr(from, message.find(", WT ", from) - from);
      }
    }
  });
  slam_mms::SetMinLogLevel(slam_mms::LogLevel::kInfo);
  Args args;
  std::string error;
  if (!ParseArgs(argc, argv, &args, &error)) {
    std::fprintf(stderr, "slam_mms_bench_e2e: %s\n%s", error.c_str(), kUsage);
    return 2;
  }
  MappingMode mode = MappingMode::kFull;
  slam_mms::ParseMappingMode(args.mode, &mode);

  report.mode = args.mode;
  report.threads = args.threads;
  fs::path drive = args.input;
  fs::path temp_dir;
  if (drive.empty()) {
    fs::path dir = args.sim_dir;
    if (dir.empty()) {
      temp_dir = fs::temp_directory_path() / ("slam_mms_bench_e2e_" + std::to_string(::getpid()));
      dir = temp_dir;
    }
    StatusOr<fs::path> simulated = SimulatedDrive(args, dir);
    if (!simulated.ok()) {
      std::fprintf(stderr, "slam_mms_bench_e2e: simulation failed: %s\n",
                   simulated.status().ToString().c_str());
      return 1;
    }
    drive = *simulated;
    char name[96];
    std::snprintf(name, sizeof(name), "simulated %s drive, %.1f s, seed %" PRIu64,
                  args.scenario.c_str(), args.duration_s, args.seed);
    report.input = name;
    // The simulation's own peak is not the library's: reset VmHWM (Linux >= 4.0).
    std::ofstream clear_refs("/proc/self/clear_refs");
    clear_refs << "5";
    clear_refs.close();
    report.peak_reset = static_cast<bool>(clear_refs);
  } else {
    if (!fs::exists(drive)) {
      std::fprintf(stderr, "slam_mms_bench_e2e: %s does not exist\n", drive.c_str());
      return 77;
    }
    report.input = drive.string();
  }
  if (args.last_frame >= 0) {
    report.input +=
        ", frames " + std::to_string(args.first_frame) + ":" + std::to_string(args.last_frame);
  }

  slam_mms::DriveSourceOptions ro;
  ro.kind = args.kind;
  ro.first_frame = args.first_frame;
  ro.last_frame = args.last_frame;
  ro.extrinsics = args.extrinsics;
  StatusOr<std::unique_ptr<slam_mms::DriveReader>> reader = slam_mms::OpenDrive(drive, ro);
  int rc = 0;
  if (!reader.ok()) {
    std::fprintf(stderr, "slam_mms_bench_e2e: %s\n", reader.status().ToString().c_str());
    rc = 1;
  } else {
    const slam_mms::DriveReader& drive_reader = **reader;
    report.scans_total = drive_reader.NumScans();
    if (report.scans_total > 0) {
      report.drive_s =
          drive_reader.ScanEnd(report.scans_total - 1).SecondsSince(drive_reader.ScanStart(0));
    }
    const Status s = FeedDrive(drive_reader, mode, args, &report);
    if (!s.ok()) {
      std::fprintf(stderr, "slam_mms_bench_e2e: run failed: %s\n", s.ToString().c_str());
      rc = 1;
    } else if (report.scans_processed == 0) {
      std::fprintf(stderr, "slam_mms_bench_e2e: no scan was processed\n");
      rc = 1;
    }
    PrintTable(report);
    if (!args.out.empty() && !WriteJson(report, args.out)) {
      std::fprintf(stderr, "slam_mms_bench_e2e: cannot write %s\n", args.out.c_str());
      rc = 1;
    }
  }
  if (!temp_dir.empty()) {
    std::error_code ec;
    fs::remove_all(temp_dir, ec);
  }
  return rc;
}
