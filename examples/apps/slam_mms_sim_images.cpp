// slam_mms_sim_images: the pictures of docs/simulator.md.
//
//   slam_mms_sim_images --out docs/images [--seed N] [--at S] [--real SCAN.bin] [--version]
//
// Writes sim_vs_kitti_scan.png (a simulated scan beside a real KITTI scan: top view, range image,
// perspective) and sim_scene.png (the procedural city along the default drive, top view).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

#include "slam_mms/core/logging.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"
#include "slam_mms/sim/drive_simulator.hpp"
#include "slam_mms/sim/hdl64_lidar.hpp"
#include "slam_mms/sim/scan_renderer.hpp"
#include "slam_mms/version.hpp"

namespace fs = std::filesystem;
using namespace slam_mms;

int main(int argc, char** argv) {
  SetLogSink(StderrLogSink());
  fs::path out = "docs/images";
  fs::path real =
      "../shared/data/kitti_raw/2011_09_26/2011_09_26_drive_0013_sync/velodyne_points/data/"
      "0000000020.bin";
  uint64_t seed = 1;
  double at_s = 14.0;
  bool version = false;
  CLI::App app("slam_mms_sim_images: the pictures of docs/simulator.md", "slam_mms_sim_images");
  app.add_option("--out", out, "output folder (default docs/images)");
  app.add_option("--real", real, "a real KITTI scan (.bin) shown beside the simulated one");
  app.add_option("--seed", seed, "simulator seed (default 1)");
  app.add_option("--at", at_s, "seconds into the drive of the simulated scan (default 14)");
  app.add_flag("--version", version, "print the version and exit");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp&) {
    std::fputs(app.help().c_str(), stdout);
    return 0;
  } catch (const CLI::ParseError& e) {
    std::cerr << "slam_mms_sim_images: " << e.what() << "\n" << app.help();
    return 2;
  }
  if (version) {
    std::printf("slam_mms_sim_images %s\n", SLAM_MMS_VERSION_STRING);
    return 0;
  }
  // The whole default drive (for the scene picture) and one scan at `at_s`.
  sim::DriveSimulator::Options o;
  o.seed = seed;
  auto simulator = sim::DriveSimulator::Create(o);
  if (!simulator.ok()) {
    std::cerr << simulator.status().ToString() << "\n";
    return 1;
  }
  const auto& traj = simulator->trajectory();
  const sim::Hdl64Lidar lidar(o.lidar);
  const auto scan = lidar.Simulate(simulator->world(), traj, o.T_lidar_body.inverse(),
                                   traj.start_s() + at_s, 0, seed, 2);
  std::printf("simulated scan at %.1f s: %zu points\n", at_s, scan.scan.cloud.size());
  std::vector<sim::ScanRenderer::LabeledScan> scans = {
      {"simulated (slam_mms_sim)", &scan.scan.cloud}};
  PointCloud real_cloud;
  if (fs::exists(real)) {
    auto r = ReadKittiScanFile(real);
    if (!r.ok()) {
      std::cerr << r.status().ToString() << "\n";
      return 1;
    }
    real_cloud = std::move(*r);
    real_cloud.RemoveNonFinite();
    std::printf("real KITTI scan %s: %zu points\n", real.c_str(), real_cloud.size());
    scans.push_back({"real KITTI 2011_09_26_drive_0013", &real_cloud});
  } else {
    std::fprintf(stderr, "no real scan at %s: simulated only\n", real.c_str());
  }
  Status s = sim::ScanRenderer::WriteScanComparison(scans, out / "sim_vs_kitti_scan.png");
  if (!s.ok()) {
    std::cerr << s.ToString() << "\n";
    return 1;
  }
  s = sim::ScanRenderer::WriteSceneMap(simulator->world(), traj, traj.start_s(), traj.end_s(), 0.25,
                                       out / "sim_scene.png");
  if (!s.ok()) {
    std::cerr << s.ToString() << "\n";
    return 1;
  }
  std::printf("wrote %s and %s\n", (out / "sim_vs_kitti_scan.png").c_str(),
              (out / "sim_scene.png").c_str());
  return 0;
}
