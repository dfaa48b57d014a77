#include "pipeline/cloud_file.hpp"

#include <unistd.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <system_error>
#include <utility>
#include <vector>

namespace slam_mms::internal {
namespace {

constexpr char kMagic[8] = {'S', 'M', 'M', 'S', 'C', 'L', 'D', '1'};
constexpr char kMagic2[8] = {'S', 'M', 'M', 'S', 'C', 'L', 'D', '2'};  // + MapPointStamps
constexpr size_t kStampBytes = 2 * sizeof(int64_t);
constexpr size_t kHeaderBytes = sizeof(kMagic) + sizeof(uint64_t);
constexpr size_t kPointBytes = 4 * sizeof(float);
// Points per write/read batch.
constexpr size_t kBatch = 4096;

}  // namespace

Status WriteCloudFile(const std::filesystem::path& path, const PointCloud& cloud,
                      const MapPointStamps* stamps) {
  static_assert(sizeof(float) == 4, "IEEE floats expected");
  const auto fail = [&path](const char* what) {
    std::error_code ec;
    std::filesystem::remove(path, ec);
    return UnavailableError(path.string() + ": " + what);
  };
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return UnavailableError(path.string() + ": cannot be created");
  const uint64_t n = cloud.size();
  const bool with_stamps = stamps != nullptr && !stamps->empty() && stamps->size() == n &&
                           stamps->scan_index.size() == n;
  out.write(with_stamps ? kMagic2 : kMagic, sizeof(kMagic));
  out.write(reinterpret_cast<const char*>(&n), sizeof(n));
  std::vector<float> buf;
  buf.reserve(4 * kBatch);
  const auto& p = cloud.points();
  const auto& in = cloud.intensities();
  for (size_t i0 = 0; i0 < n && out; i0 += kBatch) {
    const size_t i1 = std::min<size_t>(n, i0 + kBatch);
    buf.clear();
    for (size_t i = i0; i < i1; ++i) {
      buf.insert(buf.end(), {p[i].x(), p[i].y(), p[i].z(), i < in.size() ? in[i] : 0.0f});
    }
    out.write(reinterpret_cast<const char*>(buf.data()),
              static_cast<std::streamsize>(buf.size() * sizeof(float)));
  }
  if (with_stamps && out) {
    out.write(reinterpret_cast<const char*>(stamps->time_ns.data()),
              static_cast<std::streamsize>(n * sizeof(int64_t)));
    out.write(reinterpret_cast<const char*>(stamps->scan_index.data()),
              static_cast<std::streamsize>(n * sizeof(int64_t)));
  }
  out.flush();
  if (!out) return fail("write failed (disk full?)");
  out.close();
  if (!out) return fail("close failed");
  return OkStatus();
}

StatusOr<PointCloud> ReadCloudFile(const std::filesystem::path& path, MapPointStamps* stamps) {
  if (stamps != nullptr) stamps->clear();
  std::ifstream in(path, std::ios::binary);
  if (!in) return NotFoundError(path.string() + ": cannot be opened");
  std::error_code ec;
  const uintmax_t bytes = std::filesystem::file_size(path, ec);
  if (ec) return NotFoundError(path.string() + ": cannot read its size: " + ec.message());
  std::array<char, sizeof(kMagic)> magic{};
  uint64_t n = 0;
  in.read(magic.data(), magic.size());
  in.read(reinterpret_cast<char*>(&n), sizeof(n));
  if (!in || bytes < kHeaderBytes) {
    return DataLossError(path.string() + ": truncated header (" + std::to_string(bytes) +
                         " bytes)");
  }
  const bool v2 = std::memcmp(magic.data(), kMagic2, sizeof(kMagic2)) == 0;
  if (!v2 && std::memcmp(magic.data(), kMagic, sizeof(kMagic)) != 0) {
    return DataLossError(path.string() + ": not a slam_mms cloud file (bad magic)");
  }
  const size_t per_point = kPointBytes + (v2 ? kStampBytes : 0);
  if (n > (bytes - kHeaderBytes) / per_point || bytes != kHeaderBytes + n * per_point) {
    return DataLossError(path.string() + ": header says " + std::to_string(n) +
                         " points, the file has " + std::to_string(bytes) + " bytes (expected " +
                         std::to_string(kHeaderBytes + n * per_point) + ")");
  }
  PointCloud cloud;
  cloud.reserve(static_cast<size_t>(n));
  std::vector<float> buf(4 * kBatch);
  for (uint64_t i0 = 0; i0 < n; i0 += kBatch) {
    const size_t m = static_cast<size_t>(std::min<uint64_t>(kBatch, n - i0));
    in.read(reinterpret_cast<char*>(buf.data()), static_cast<std::streamsize>(m * kPointBytes));
    if (!in) {
      return DataLossError(path.string() + ": read failed at point " + std::to_string(i0));
    }
    for (size_t k = 0; k < m; ++k) {
      cloud.Add(Eigen::Vector3f(buf[4 * k], buf[4 * k + 1], buf[4 * k + 2]), buf[4 * k + 3]);
    }
  }
  if (v2) {
    MapPointStamps read;
    read.time_ns.resize(static_cast<size_t>(n));
    read.scan_index.resize(static_cast<size_t>(n));
    in.read(reinterpret_cast<char*>(read.time_ns.data()),
            static_cast<std::streamsize>(n * sizeof(int64_t)));
    in.read(reinterpret_cast<char*>(read.scan_index.data()),
            static_cast<std::streamsize>(n * sizeof(int64_t)));
    if (!in) return DataLossError(path.string() + ": read failed in the point stamps");
    if (stamps != nullptr) *stamps = std::move(read);
  }
  return cloud;
}

StatusOr<SpillFolder> SpillFolder::Create(const std::filesystem::path& parent) {
  static std::atomic<uint64_t> counter{0};
  const auto now = std::chrono::steady_clock::now().time_since_epoch().count();
  SpillFolder folder;
  const std::filesystem::path path =
      parent / ("slam_mms_spill_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) +
                "_" + std::to_string(now % 1000000007));
  std::error_code ec;
  std::filesystem::create_directories(path, ec);
  if (ec) return UnavailableError("cannot create " + path.string() + ": " + ec.message());
  folder.path_ = path;
  return folder;
}

SpillFolder::SpillFolder(SpillFolder&& other) noexcept : path_(std::move(other.path_)) {
  other.path_.clear();
}

SpillFolder& SpillFolder::operator=(SpillFolder&& other) noexcept {
  if (this != &other) {
    Remove();
    path_ = std::move(other.path_);
    other.path_.clear();
  }
  return *this;
}

SpillFolder::~SpillFolder() { Remove(); }

void SpillFolder::Remove() {
  if (path_.empty()) return;
  std::error_code ec;
  std::filesystem::remove_all(path_, ec);
  path_.clear();
}

Status SpillFolder::Spill(const std::string& name, PointCloud* cloud, std::filesystem::path* file,
                          MapPointStamps* stamps) const {
  if (!enabled() || !file->empty()) return OkStatus();
  const std::filesystem::path target = path_ / name;
  SLAM_MMS_RETURN_IF_ERROR(WriteCloudFile(target, *cloud, stamps));
  *file = target;
  *cloud = PointCloud();
  if (stamps != nullptr) *stamps = MapPointStamps();
  return OkStatus();
}

StatusOr<PointCloud> CloudFromMemoryOrFile(const PointCloud& cloud,
                                           const std::filesystem::path& file,
                                           const MapPointStamps* stamps,
                                           MapPointStamps* stamps_out) {
  if (file.empty()) {
    if (stamps_out != nullptr) *stamps_out = stamps != nullptr ? *stamps : MapPointStamps();
    return cloud;
  }
  return ReadCloudFile(file, stamps_out);
}

}  // namespace slam_mms::internal
