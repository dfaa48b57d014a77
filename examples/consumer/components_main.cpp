// A consumer of two package components besides the SDK: find_package(slam_mms COMPONENTS io eval).
// Writes a small planar map as PLY (slam_mms::io), reads it back and computes its mean map entropy
// (slam_mms::eval); exits 0 when the round trip keeps every point and a plane with 2 cm noise
// scores higher (less sharp) than one with 2 mm (an exact plane has no entropy: its covariances are
// singular).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

#include "slam_mms/core/voxel_downsample.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/io/map_io.hpp"
#include "slam_mms/version.hpp"

namespace {

slam_mms::PointCloud Plane(double noise_m) {
  std::mt19937 rng(3);
  std::normal_distribution<float> n(0.0f, static_cast<float>(noise_m));
  slam_mms::PointCloud cloud;
  for (int i = 0; i < 60; ++i) {
    for (int j = 0; j < 60; ++j) {
      cloud.Add(Eigen::Vector3f(0.05f * i, 0.05f * j, n(rng)), 0.5f);
    }
  }
  return cloud;
}

}  // namespace

int main() {
  namespace fs = std::filesystem;
  const fs::path file = fs::temp_directory_path() / "slam_mms_consumer_components.ply";
  slam_mms::MapCloud map;
  map.cloud = Plane(0.002);
  const slam_mms::Status written = slam_mms::WritePly(map, file);
  if (!written.ok()) {
    std::printf("WritePly: %s\n", written.ToString().c_str());
    return 1;
  }
  const slam_mms::StatusOr<slam_mms::MapCloud> back = slam_mms::ReadPly(file);
  fs::remove(file);
  if (!back.ok() || back->cloud.size() != map.cloud.size()) {
    std::printf("ReadPly: %s\n",
                back.ok() ? "point count differs" : back.status().ToString().c_str());
    return 1;
  }
  slam_mms::eval::MapEntropyOptions options;
  options.voxel_size_m = 0.0;
  const auto sharp = slam_mms::eval::ComputeMapEntropy(back->cloud, options);
  const auto blurred = slam_mms::eval::ComputeMapEntropy(Plane(0.02), options);
  if (!sharp.ok() || !blurred.ok()) {
    std::printf("ComputeMapEntropy failed\n");
    return 1;
  }
  const auto down = slam_mms::VoxelDownsample(back->cloud, 0.1);
  std::printf(
      "slam_mms %s components io+eval: %zu points round-tripped, entropy %.3f (2 mm noise) < "
      "%.3f (2 cm noise), %zu voxels\n",
      SLAM_MMS_VERSION_STRING, back->cloud.size(), sharp->mean_map_entropy,
      blurred->mean_map_entropy, down.ok() ? down->size() : 0);
  return sharp->mean_map_entropy < blurred->mean_map_entropy && down.ok() ? 0 : 1;
}
