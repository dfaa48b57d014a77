// SurfelMap::Save / Load: a versioned binary file with a checksum; every record is validated before
// the map is replaced, so a corrupt file never leaves a half-loaded map.
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "slam_mms/surfel/surfel_map.hpp"
#include "surfel/surfel_map_impl.hpp"

namespace slam_mms {
namespace {

constexpr char kMagic[8] = {'S', 'L', 'M', 'M', 'S', 'U', 'R', 'F'};
constexpr uint32_t kVersion = 1;
constexpr uint32_t kRecordBytes = 64;
constexpr size_t kHeaderBytes = 8 + 4 + 4 + 8 + 4 + 4;

uint64_t Fnv1a(const uint8_t* data, size_t n) {
  uint64_t h = 1469598103934665603ull;
  for (size_t i = 0; i < n; ++i) {
    h ^= data[i];
    h *= 1099511628211ull;
  }
  return h;
}

// Little-endian encoding (the host is checked to be little-endian by the memcpy round trip below
// being the identity on x86-64/aarch64; a big-endian host would need byte swaps here).
template <typename T>
void Put(std::vector<uint8_t>* buf, const T& v) {
  const size_t at = buf->size();
  buf->resize(at + sizeof(T));
  std::memcpy(buf->data() + at, &v, sizeof(T));
}
template <typename T>
T Get(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

void PutSurfel(std::vector<uint8_t>* buf, const Surfel& s) {
  for (int a = 0; a < 3; ++a) Put(buf, s.position[a]);
  Put(buf, s.radius);
  for (int a = 0; a < 3; ++a) Put(buf, s.normal[a]);
  Put(buf, s.confidence);
  Put(buf, s.created_ns);
  Put(buf, s.updated_ns);
  Put(buf, s.created_frame);
  Put(buf, s.updated_frame);
  Put(buf, s.submap_id);
  Put(buf, s.num_updates);
}

Surfel GetSurfel(const uint8_t* p) {
  Surfel s;
  for (int a = 0; a < 3; ++a) s.position[a] = Get<float>(p + 4 * a);
  s.radius = Get<float>(p + 12);
  for (int a = 0; a < 3; ++a) s.normal[a] = Get<float>(p + 16 + 4 * a);
  s.confidence = Get<float>(p + 28);
  s.created_ns = Get<int64_t>(p + 32);
  s.updated_ns = Get<int64_t>(p + 40);
  s.created_frame = Get<int32_t>(p + 48);
  s.updated_frame = Get<int32_t>(p + 52);
  s.submap_id = Get<int32_t>(p + 56);
  s.num_updates = Get<int32_t>(p + 60);
  return s;
}

}  // namespace

Status SurfelMap::Save(const std::string& path) const {
  const Impl& m = *impl_;
  std::vector<uint8_t> buf;
  buf.reserve(kHeaderBytes + m.num_alive * kRecordBytes + 8);
  buf.insert(buf.end(), kMagic, kMagic + 8);
  Put(&buf, kVersion);
  Put(&buf, kRecordBytes);
  Put(&buf, static_cast<uint64_t>(m.num_alive));
  Put(&buf, m.submap_id);
  Put(&buf, m.frame_count);
  for (size_t i = 0; i < m.surfels.size(); ++i) {
    if (m.alive[i]) PutSurfel(&buf, m.surfels[i]);
  }
  Put(&buf, Fnv1a(buf.data(), buf.size()));
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) return NotFoundError("SurfelMap::Save: cannot open '" + path + "' for writing");
  out.write(reinterpret_cast<const char*>(buf.data()), static_cast<std::streamsize>(buf.size()));
  out.close();
  if (!out) return InternalError("SurfelMap::Save: writing '" + path + "' failed");
  return OkStatus();
}

Status SurfelMap::Load(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return NotFoundError("SurfelMap::Load: cannot open '" + path + "'");
  std::vector<uint8_t> buf((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string where = "SurfelMap::Load: '" + path + "': ";
  if (buf.size() < kHeaderBytes + 8) {
    return DataLossError(where + "truncated (" + std::to_string(buf.size()) + " bytes)");
  }
  if (std::memcmp(buf.data(), kMagic, 8) != 0) {
    return DataLossError(where + "not a slam_mms surfel map (bad magic)");
  }
  const uint32_t version = Get<uint32_t>(buf.data() + 8);
  const uint32_t record = Get<uint32_t>(buf.data() + 12);
  const uint64_t count = Get<uint64_t>(buf.data() + 16);
  if (version != kVersion) {
    return DataLossError(where + "unsupported version " + std::to_string(version) + " (expected " +
                         std::to_string(kVersion) + ")");
  }
  if (record != kRecordBytes) {
    return DataLossError(where + "record size " + std::to_string(record) + ", expected 64");
  }
  if (count > (buf.size() - kHeaderBytes - 8) / kRecordBytes ||
      buf.size() != kHeaderBytes + count * kRecordBytes + 8) {
    std::ostringstream os;
    os << where << "size " << buf.size() << " bytes does not match " << count
       << " surfels (truncated or trailing data)";
    return DataLossError(os.str());
  }
  const uint64_t stored = Get<uint64_t>(buf.data() + buf.size() - 8);
  if (stored != Fnv1a(buf.data(), buf.size() - 8)) {
    return DataLossError(where + "checksum mismatch (corrupt file)");
  }
  std::vector<Surfel> surfels;
  surfels.reserve(count);
  for (uint64_t i = 0; i < count; ++i) {
    const Surfel s = GetSurfel(buf.data() + kHeaderBytes + i * kRecordBytes);
    if (!s.position.allFinite() || !s.normal.allFinite() || !std::isfinite(s.confidence) ||
        !(s.radius > 0.0f) || !std::isfinite(s.radius) ||
        std::abs(s.normal.norm() - 1.0f) > 1e-3f) {
      return DataLossError(where + "surfel " + std::to_string(i) + " has invalid values");
    }
    surfels.push_back(s);
  }
  Impl& m = *impl_;
  Clear();
  m.submap_id = Get<int32_t>(buf.data() + 24);
  m.frame_count = Get<int32_t>(buf.data() + 28);
  m.surfels.reserve(surfels.size());
  for (const Surfel& s : surfels) m.AddSlot(s);
  return OkStatus();
}

}  // namespace slam_mms
