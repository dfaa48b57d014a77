// LAS 1.4 geo-referenced through a GeoReference (see map_io.hpp). Layout references: ASPRS LAS 1.4
// R15 (public header block 375 bytes, VLR header 54 bytes, point data record format 6 of 30 bytes,
// OGC WKT in a LASF_Projection VLR with record ID 2112, global encoding bit 4 = WKT).
#include <proj.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <ctime>
#include <exception>
#include <fstream>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <utility>

#include "io/binary_util.hpp"
#include "io/file_util.hpp"
#include "slam_mms/io/map_io.hpp"

namespace slam_mms {

namespace fs = std::filesystem;
using io_internal::PutLe;
using io_internal::ReadScalar;

namespace {

constexpr size_t kHeaderSize14 = 375;
constexpr size_t kVlrHeaderSize = 54;
constexpr size_t kEvlrHeaderSize = 60;
constexpr uint16_t kGlobalEncodingGpsStandardTime = 1;
constexpr uint16_t kGlobalEncodingWkt = 1 << 4;
constexpr size_t kFormat6Size = 30;

void PutString(char* p, const std::string& s, size_t n) {
  std::memset(p, 0, n);
  std::memcpy(p, s.data(), std::min(n, s.size()));
}

std::string GetString(const char* p, size_t n) {
  size_t len = 0;
  while (len < n && p[len] != '\0') ++len;
  return std::string(p, len);
}

template <typename T>
T Le(const std::string& b, size_t offset) {
  return ReadScalar<T>(b.data() + offset, true);
}

}  // namespace

Status LasWriteOptions::Validate() const {
  if (!(scale_m > 0.0) || !std::isfinite(scale_m)) {
    return InvalidArgumentError("LasWriteOptions::scale_m = " + std::to_string(scale_m) +
                                "; must be > 0");
  }
  if (utm_zone < 0 || utm_zone > 60) {
    return InvalidArgumentError("LasWriteOptions::utm_zone = " + std::to_string(utm_zone) +
                                "; must be 0 (from the origin) or 1..60");
  }
  return OkStatus();
}

std::string UtmZoneWkt(int zone, bool north) {
  if (zone < 1 || zone > 60) return "";
  PJ_CONTEXT* ctx = proj_context_create();
  if (ctx == nullptr) return "";
  proj_log_func(ctx, nullptr, [](void*, int, const char*) {});
  const std::string code = "EPSG:" + std::to_string((north ? 32600 : 32700) + zone);
  std::string wkt;
  if (PJ* crs = proj_create(ctx, code.c_str())) {
    const char* const options[] = {"MULTILINE=NO", nullptr};
    const char* w = proj_as_wkt(ctx, crs, PJ_WKT1_GDAL, options);
    if (w != nullptr) wkt = w;
    proj_destroy(crs);
  }
  proj_context_destroy(ctx);
  return wkt;
}

namespace {

// Edge of the cells of GeoReference::EnuToProjectedInterpolated for the LAS coordinates.
constexpr double kProjectionCellM = 8.0;

// The projected coordinates and adjusted GPS times (empty without times) of every point.
Status ProjectMap(const MapCloud& map, const GeoReference& geo, std::vector<Eigen::Vector3d>* enh,
                  std::vector<double>* gps_time) {
  SLAM_MMS_RETURN_IF_ERROR(map.Validate());
  const size_t n = map.cloud.size();
  std::vector<Eigen::Vector3d> p_world(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3f& p = map.cloud.points()[i];
    if (!p.allFinite()) {
      return InvalidArgumentError("WriteLas: point " + std::to_string(i) + " is not finite");
    }
    p_world[i] = p.cast<double>();
  }
  // Exact at the corners of 8 m cells, trilinear inside (a few micrometres against the exact
  // projection per point, at a tenth of its cost; the file keeps millimetres).
  SLAM_MMS_RETURN_IF_ERROR(
      geo.EnuToProjectedInterpolated(p_world, enh, kProjectionCellM).WithContext("WriteLas"));
  gps_time->clear();
  if (!map.time_ns.empty()) {
    gps_time->resize(n);
    for (size_t i = 0; i < n; ++i) {
      StatusOr<double> t = AdjustedGpsTimeFromUtc(Timestamp::FromNanoseconds(map.time_ns[i]));
      if (!t.ok()) return t.status().WithContext("WriteLas: point " + std::to_string(i));
      (*gps_time)[i] = *t;
    }
  }
  return OkStatus();
}

// The indices of `subset` (all points when null) in file order: by GPS time (stable) if wanted.
std::vector<size_t> FileOrder(const MapCloud& map, const std::vector<size_t>* subset,
                              const LasWriteOptions& options) {
  std::vector<size_t> order;
  if (subset != nullptr) {
    order = *subset;
  } else {
    order.resize(map.cloud.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  }
  if (options.sort_by_time && !map.time_ns.empty()) {
    // A stable sort by time, of contiguous (time, index) pairs: a comparison that looks the
    // times up costs a cache miss each.
    std::vector<std::pair<int64_t, size_t>> keyed(order.size());
    for (size_t k = 0; k < order.size(); ++k) keyed[k] = {map.time_ns[order[k]], order[k]};
    std::stable_sort(keyed.begin(), keyed.end(),
                     [](const auto& a, const auto& b) { return a.first < b.first; });
    for (size_t k = 0; k < order.size(); ++k) order[k] = keyed[k].second;
  }
  return order;
}

// One LAS 1.4 format-6 file of the points `order` (indices into map / enh / gps_time).
Status WriteLasPoints(const MapCloud& map, const std::vector<Eigen::Vector3d>& enh,
                      const std::vector<double>& gps_time, const std::vector<size_t>& order,
                      const std::string& wkt, const fs::path& file,
                      const LasWriteOptions& options) {
  const size_t n = order.size();
  // Offsets: whole kilometres below the minimum, so int32 * scale covers +-2000 km at 1 mm.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  // The bounds do not depend on the order: over the whole map in memory order where the file
  // holds every point (the order is by time, a gather with a cache miss per point).
  if (n == enh.size()) {
    for (const Eigen::Vector3d& p : enh) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  } else {
    for (const size_t i : order) {
      lo = lo.cwiseMin(enh[i]);
      hi = hi.cwiseMax(enh[i]);
    }
  }
  if (n == 0) lo = hi = Eigen::Vector3d::Zero();
  Eigen::Vector3d offset;
  for (int a = 0; a < 3; ++a) offset[a] = std::floor(lo[a] / 1000.0) * 1000.0;
  const double s = options.scale_m;
  const double max_range = 2147483647.0 * s;
  if ((hi - offset).maxCoeff() > max_range) {
    return InvalidArgumentError("WriteLas: the map spans more than " + std::to_string(max_range) +
                                " m at scale " + std::to_string(s) + " m");
  }
  std::string points(n * kFormat6Size, '\0');
  Eigen::Vector3d qlo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d qhi = -qlo;
  // The points are read in file order (by time), scattered over memory: each one's fields are
  // fetched a few records ahead.
  constexpr size_t kAhead = 16;
  const float* const intensities = map.cloud.intensities().data();
  for (size_t k = 0; k < n; ++k) {
    if (k + kAhead < n) {
      const size_t ahead = order[k + kAhead];
      __builtin_prefetch(&enh[ahead]);
      __builtin_prefetch(intensities + ahead);
      if (!gps_time.empty()) __builtin_prefetch(&gps_time[ahead]);
      if (!map.source_id.empty()) __builtin_prefetch(&map.source_id[ahead]);
    }
    const size_t i = order[k];
    char* rec = points.data() + k * kFormat6Size;
    Eigen::Vector3d q;
    for (int a = 0; a < 3; ++a) {
      const auto v = static_cast<int32_t>(std::llround((enh[i][a] - offset[a]) / s));
      PutLe<int32_t>(rec + 4 * a, v);
      q[a] = offset[a] + v * s;
    }
    qlo = qlo.cwiseMin(q);
    qhi = qhi.cwiseMax(q);
    const double in = std::clamp(static_cast<double>(map.cloud.intensities()[i]), 0.0, 1.0);
    PutLe<uint16_t>(rec + 12, static_cast<uint16_t>(std::lround(in * 65535.0)));
    rec[14] = static_cast<char>(1 | (1 << 4));  // return 1 of 1
    // 15: classification flags, scanner channel, scan direction, edge of flight line: 0.
    rec[16] = static_cast<char>(map.classification.empty() ? 0 : map.classification[i]);
    // 17 user data, 18 scan angle: 0.
    PutLe<uint16_t>(rec + 20, map.source_id.empty() ? options.point_source_id : map.source_id[i]);
    PutLe<double>(rec + 22, gps_time.empty() ? 0.0 : gps_time[i]);
  }
  if (n == 0) qlo = qhi = Eigen::Vector3d::Zero();

  const size_t wkt_size = wkt.size() + 1;  // null-terminated
  if (wkt_size > 65535) return InternalError("WriteLas: WKT too long");
  const size_t vlr_size = kVlrHeaderSize + wkt_size;
  const size_t point_offset = kHeaderSize14 + vlr_size;

  std::string header(kHeaderSize14, '\0');
  char* h = header.data();
  std::memcpy(h, "LASF", 4);
  PutLe<uint16_t>(h + 4, 0);
  PutLe<uint16_t>(h + 6, kGlobalEncodingGpsStandardTime | kGlobalEncodingWkt);
  h[24] = 1;
  h[25] = 4;
  PutString(h + 26, "OTHER", 32);
  PutString(h + 58, options.generating_software, 32);
  const std::time_t now = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&now, &tm);
  PutLe<uint16_t>(h + 90, static_cast<uint16_t>(tm.tm_yday + 1));
  PutLe<uint16_t>(h + 92, static_cast<uint16_t>(tm.tm_year + 1900));
  PutLe<uint16_t>(h + 94, static_cast<uint16_t>(kHeaderSize14));
  PutLe<uint32_t>(h + 96, static_cast<uint32_t>(point_offset));
  PutLe<uint32_t>(h + 100, 1);  // one VLR
  h[104] = 6;
  PutLe<uint16_t>(h + 105, static_cast<uint16_t>(kFormat6Size));
  // 107..130: legacy counts, zero for point formats >= 6.
  for (int a = 0; a < 3; ++a) PutLe<double>(h + 131 + 8 * a, s);
  for (int a = 0; a < 3; ++a) PutLe<double>(h + 155 + 8 * a, offset[a]);
  for (int a = 0; a < 3; ++a) {
    PutLe<double>(h + 179 + 16 * a, qhi[a]);
    PutLe<double>(h + 187 + 16 * a, qlo[a]);
  }
  // 227 waveform start, 235 first EVLR start, 243 number of EVLRs: 0.
  PutLe<uint64_t>(h + 247, n);
  PutLe<uint64_t>(h + 255, n);  // all points are first returns

  std::string vlr(vlr_size, '\0');
  char* v = vlr.data();
  PutString(v + 2, "LASF_Projection", 16);
  PutLe<uint16_t>(v + 18, 2112);
  PutLe<uint16_t>(v + 20, static_cast<uint16_t>(wkt_size));
  PutString(v + 22, "OGC coordinate system WKT", 32);
  std::memcpy(v + kVlrHeaderSize, wkt.c_str(), wkt_size);

  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) return UnavailableError("cannot create " + file.string());
  out.write(header.data(), static_cast<std::streamsize>(header.size()));
  out.write(vlr.data(), static_cast<std::streamsize>(vlr.size()));
  out.write(points.data(), static_cast<std::streamsize>(points.size()));
  out.close();
  if (!out) return DataLossError("cannot write " + file.string());
  return OkStatus();
}

std::string CornerText(double v, double tile_size_m) {
  char buf[64];
  const bool whole = std::floor(tile_size_m) == tile_size_m;
  std::snprintf(buf, sizeof(buf), whole ? "%.0f" : "%.3f", v);
  return buf;
}

}  // namespace

Status WriteLas(const MapCloud& map, const GeoReference& geo, const fs::path& file,
                const LasWriteOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  std::vector<Eigen::Vector3d> enh;
  std::vector<double> gps_time;
  SLAM_MMS_RETURN_IF_ERROR(ProjectMap(map, geo, &enh, &gps_time));
  return WriteLasPoints(map, enh, gps_time, FileOrder(map, nullptr, options), geo.wkt1(), file,
                        options);
}

Status WriteLas(const MapCloud& map, const GeodeticPoint& origin, const fs::path& file) {
  return WriteLas(map, origin, file, LasWriteOptions());
}

Status WriteLas(const MapCloud& map, const GeodeticPoint& origin, const fs::path& file,
                const LasWriteOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  std::string crs = options.crs;
  if (crs.empty() && options.utm_zone != 0) {
    crs = "EPSG:" + std::to_string((options.north ? 32600 : 32700) + options.utm_zone);
  }
  StatusOr<GeoReference> geo = GeoReference::Create(origin, crs);
  if (!geo.ok()) return geo.status().WithContext("WriteLas");
  return WriteLas(map, *geo, file, options);
}

StatusOr<std::vector<LasTile>> WriteLasTiles(const MapCloud& map, const GeoReference& geo,
                                             const fs::path& folder, double tile_size_m,
                                             const LasWriteOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (!(tile_size_m > 0.0) || !std::isfinite(tile_size_m)) {
    return InvalidArgumentError("WriteLasTiles: tile_size_m = " + std::to_string(tile_size_m) +
                                "; must be > 0");
  }
  std::vector<Eigen::Vector3d> enh;
  std::vector<double> gps_time;
  SLAM_MMS_RETURN_IF_ERROR(ProjectMap(map, geo, &enh, &gps_time));
  std::error_code ec;
  fs::create_directories(folder, ec);
  if (ec)
    return UnavailableError("WriteLasTiles: cannot create " + folder.string() + ": " +
                            ec.message());
  // Cell of each point; cells ordered row-major from the south-west.
  std::map<std::pair<int64_t, int64_t>, std::vector<size_t>> cells;
  for (size_t i = 0; i < enh.size(); ++i) {
    const auto column = static_cast<int64_t>(std::floor(enh[i].x() / tile_size_m));
    const auto row = static_cast<int64_t>(std::floor(enh[i].y() / tile_size_m));
    cells[{row, column}].push_back(i);
  }
  std::vector<LasTile> tiles;
  nlohmann::json index;
  index["crs"] = {{"epsg", geo.epsg()}, {"name", geo.crs_name()}};
  index["tile_size_m"] = tile_size_m;
  index["cell"] = "column = floor(easting / tile_size_m), row = floor(northing / tile_size_m)";
  index["tiles"] = nlohmann::json::array();
  for (const auto& [cell, members] : cells) {
    LasTile t;
    t.row = cell.first;
    t.column = cell.second;
    t.min_easting_m = static_cast<double>(t.column) * tile_size_m;
    t.min_northing_m = static_cast<double>(t.row) * tile_size_m;
    t.file = "tile_" + CornerText(t.min_easting_m, tile_size_m) + "_" +
             CornerText(t.min_northing_m, tile_size_m) + ".las";
    t.num_points = members.size();
    SLAM_MMS_RETURN_IF_ERROR(WriteLasPoints(map, enh, gps_time, FileOrder(map, &members, options),
                                            geo.wkt1(), folder / t.file, options)
                                 .WithContext("WriteLasTiles: tile " + t.file));
    index["tiles"].push_back({{"file", t.file},
                              {"column", t.column},
                              {"row", t.row},
                              {"min_easting_m", t.min_easting_m},
                              {"min_northing_m", t.min_northing_m},
                              {"max_easting_m", t.min_easting_m + tile_size_m},
                              {"max_northing_m", t.min_northing_m + tile_size_m},
                              {"points", t.num_points}});
    tiles.push_back(std::move(t));
  }
  index["points"] = enh.size();
  std::ofstream out(folder / "index.json", std::ios::trunc);
  out << index.dump(2) << "\n";
  out.close();
  if (!out)
    return UnavailableError("WriteLasTiles: cannot write " + (folder / "index.json").string());
  return tiles;
}

StatusOr<LasCloud> ReadLas(const fs::path& file) {
  SLAM_MMS_ASSIGN_OR_RETURN(const std::string b, io_internal::ReadFileBytes(file));
  const std::string f = file.string();
  if (b.size() < 227 || b.compare(0, 4, "LASF") != 0) {
    return DataLossError(f + ": not a LAS file (no LASF signature or too short)");
  }
  LasCloud las;
  las.global_encoding = Le<uint16_t>(b, 6);
  las.version_major = static_cast<uint8_t>(b[24]);
  las.version_minor = static_cast<uint8_t>(b[25]);
  const size_t header_size = Le<uint16_t>(b, 94);
  const size_t point_offset = Le<uint32_t>(b, 96);
  const uint32_t num_vlrs = Le<uint32_t>(b, 100);
  las.point_format = static_cast<uint8_t>(b[104]) & 0x3f;  // bits 6-7: compression flags
  const size_t record_length = Le<uint16_t>(b, 105);
  uint64_t count = Le<uint32_t>(b, 107);
  for (int a = 0; a < 3; ++a) {
    las.scale[a] = Le<double>(b, 131 + 8 * a);
    las.offset[a] = Le<double>(b, 155 + 8 * a);
    las.max[a] = Le<double>(b, 179 + 16 * a);
    las.min[a] = Le<double>(b, 187 + 16 * a);
  }
  uint64_t evlr_start = 0;
  uint32_t num_evlrs = 0;
  if (las.version_major == 1 && las.version_minor >= 4) {
    if (header_size < kHeaderSize14 || b.size() < kHeaderSize14) {
      return DataLossError(f + ": LAS 1.4 header shorter than 375 bytes");
    }
    evlr_start = Le<uint64_t>(b, 235);
    num_evlrs = Le<uint32_t>(b, 243);
    const uint64_t count14 = Le<uint64_t>(b, 247);
    if (count14 != 0) count = count14;
  }
  // VLRs, then EVLRs: the first LASF_Projection/2112 gives the WKT.
  size_t pos = header_size;
  for (uint32_t i = 0; i < num_vlrs; ++i) {
    if (pos + kVlrHeaderSize > b.size())
      return DataLossError(f + ": truncated VLR " + std::to_string(i));
    const std::string user = GetString(b.data() + pos + 2, 16);
    const uint16_t id = Le<uint16_t>(b, pos + 18);
    const size_t len = Le<uint16_t>(b, pos + 20);
    if (pos + kVlrHeaderSize + len > b.size()) {
      return DataLossError(f + ": VLR " + std::to_string(i) + " runs past the end of the file");
    }
    if (user == "LASF_Projection" && id == 2112 && las.wkt.empty()) {
      las.wkt = GetString(b.data() + pos + kVlrHeaderSize, len);
    }
    pos += kVlrHeaderSize + len;
  }
  pos = evlr_start;
  for (uint32_t i = 0; i < num_evlrs; ++i) {
    if (pos + kEvlrHeaderSize > b.size()) {
      return DataLossError(f + ": truncated EVLR " + std::to_string(i));
    }
    const std::string user = GetString(b.data() + pos + 2, 16);
    const uint16_t id = Le<uint16_t>(b, pos + 18);
    const uint64_t len = Le<uint64_t>(b, pos + 20);
    if (pos + kEvlrHeaderSize + len > b.size()) {
      return DataLossError(f + ": EVLR " + std::to_string(i) + " runs past the end of the file");
    }
    if (user == "LASF_Projection" && id == 2112 && las.wkt.empty()) {
      las.wkt = GetString(b.data() + pos + kEvlrHeaderSize, static_cast<size_t>(len));
    }
    pos += kEvlrHeaderSize + static_cast<size_t>(len);
  }
  size_t intensity_offset = 12;
  size_t min_length = 0;
  const bool extended = las.point_format >= 6;
  const size_t class_offset = extended ? 16 : 15;
  const size_t source_offset = extended ? 20 : 18;
  const size_t user_offset = 17;
  const bool has_time = las.point_format == 1 || las.point_format == 3 || extended;
  const size_t time_offset = extended ? 22 : 20;
  switch (las.point_format) {
    case 0: min_length = 20; break;
    case 1: min_length = 28; break;
    case 2: min_length = 26; break;
    case 3: min_length = 34; break;
    case 6: min_length = 30; break;
    case 7: min_length = 36; break;
    case 8: min_length = 38; break;
    default:
      return Status(StatusCode::kUnimplemented, f + ": LAS point data record format " +
                                                    std::to_string(las.point_format) +
                                                    " not supported (0-3, 6-8)");
  }
  if (record_length < min_length) {
    return DataLossError(f + ": point record length " + std::to_string(record_length) +
                         " shorter than format " + std::to_string(las.point_format) + " needs (" +
                         std::to_string(min_length) + ")");
  }
  if (point_offset > b.size() || (b.size() - point_offset) / record_length < count) {
    return DataLossError(f + ": header says " + std::to_string(count) + " points of " +
                         std::to_string(record_length) + " bytes from offset " +
                         std::to_string(point_offset) + " but the file has " +
                         std::to_string(b.size()) + " bytes");
  }
  las.points_utm.resize(count);
  las.intensities.resize(count);
  las.point_source_id.resize(count);
  las.classification.resize(count);
  las.user_data.resize(count);
  if (has_time) las.gps_time.resize(count);
  for (uint64_t i = 0; i < count; ++i) {
    const size_t r = point_offset + i * record_length;
    for (int a = 0; a < 3; ++a) {
      las.points_utm[i][a] = las.offset[a] + las.scale[a] * Le<int32_t>(b, r + 4 * a);
    }
    las.intensities[i] = Le<uint16_t>(b, r + intensity_offset);
    const auto cls = static_cast<uint8_t>(b[r + class_offset]);
    las.classification[i] = extended ? cls : static_cast<uint8_t>(cls & 0x1f);
    las.user_data[i] = static_cast<uint8_t>(b[r + user_offset]);
    las.point_source_id[i] = Le<uint16_t>(b, r + source_offset);
    if (has_time) las.gps_time[i] = Le<double>(b, r + time_offset);
  }
  return las;
}

}  // namespace slam_mms
