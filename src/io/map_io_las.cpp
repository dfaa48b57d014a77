// LAS 1.4 geo-referenced in UTM (see map_io.hpp). Layout references: ASPRS LAS 1.4 R15
// (public header block 375 bytes, VLR header 54 bytes, point data record format 6 of 30 bytes,
// OGC WKT in a LASF_Projection VLR with record ID 2112, global encoding bit 4 = WKT).
#include <GeographicLib/LocalCartesian.hpp>
#include <GeographicLib/UTMUPS.hpp>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <ctime>
#include <exception>
#include <fstream>
#include <limits>

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
  const std::string name = "WGS 84 / UTM zone " + std::to_string(zone) + (north ? "N" : "S");
  const int epsg = (north ? 32600 : 32700) + zone;
  const int central_meridian = 6 * zone - 183;
  return "PROJCS[\"" + name +
         "\",GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,298.257223563,"
         "AUTHORITY[\"EPSG\",\"7030\"]],AUTHORITY[\"EPSG\",\"6326\"]],PRIMEM[\"Greenwich\",0,"
         "AUTHORITY[\"EPSG\",\"8901\"]],UNIT[\"degree\",0.0174532925199433,AUTHORITY[\"EPSG\","
         "\"9122\"]],AUTHORITY[\"EPSG\",\"4326\"]],PROJECTION[\"Transverse_Mercator\"],"
         "PARAMETER[\"latitude_of_origin\",0],PARAMETER[\"central_meridian\"," +
         std::to_string(central_meridian) +
         "],PARAMETER[\"scale_factor\",0.9996],PARAMETER[\"false_easting\",500000],"
         "PARAMETER[\"false_northing\"," +
         std::string(north ? "0" : "10000000") +
         "],UNIT[\"metre\",1,AUTHORITY[\"EPSG\",\"9001\"]],AXIS[\"Easting\",EAST],"
         "AXIS[\"Northing\",NORTH],AUTHORITY[\"EPSG\",\"" +
         std::to_string(epsg) + "\"]]";
}

Status WriteLas(const MapCloud& map, const GeoOrigin& origin, const fs::path& file) {
  return WriteLas(map, origin, file, LasWriteOptions());
}

Status WriteLas(const MapCloud& map, const GeoOrigin& origin, const fs::path& file,
                const LasWriteOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  SLAM_MMS_RETURN_IF_ERROR(map.Validate());
  if (!std::isfinite(origin.latitude_deg) || !std::isfinite(origin.longitude_deg) ||
      !std::isfinite(origin.height_m) || origin.latitude_deg < -80.0 ||
      origin.latitude_deg > 84.0 || std::abs(origin.longitude_deg) > 180.0) {
    return InvalidArgumentError("WriteLas: origin (" + std::to_string(origin.latitude_deg) + ", " +
                                std::to_string(origin.longitude_deg) +
                                ") outside the UTM latitude band [-80, 84] deg or invalid");
  }
  const size_t n = map.cloud.size();
  int zone = options.utm_zone;
  bool north = options.north;
  std::vector<Eigen::Vector3d> utm(n);
  try {
    if (zone == 0) {
      zone = GeographicLib::UTMUPS::StandardZone(origin.latitude_deg, origin.longitude_deg);
      north = origin.latitude_deg >= 0.0;
    }
    const GeographicLib::LocalCartesian enu(origin.latitude_deg, origin.longitude_deg,
                                            origin.height_m);
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3f& p = map.cloud.points()[i];
      if (!p.allFinite()) {
        return InvalidArgumentError("WriteLas: point " + std::to_string(i) + " is not finite");
      }
      double lat, lon, h, gamma, k;
      enu.Reverse(p.x(), p.y(), p.z(), lat, lon, h);
      bool northp = north;
      int z = zone;
      GeographicLib::UTMUPS::Forward(lat, lon, z, northp, utm[i].x(), utm[i].y(), gamma, k, zone);
      if (northp != north) {  // a point across the equator: keep the file's hemisphere
        utm[i].y() +=
            north ? -GeographicLib::UTMUPS::UTMShift() : GeographicLib::UTMUPS::UTMShift();
      }
      utm[i].z() = h;
    }
  } catch (const std::exception& e) {
    return InvalidArgumentError(std::string("WriteLas: UTM conversion failed: ") + e.what());
  }

  // Offsets: whole kilometres below the minimum, so int32 * scale covers +-2000 km at 1 mm.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& u : utm) {
    lo = lo.cwiseMin(u);
    hi = hi.cwiseMax(u);
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
  for (size_t i = 0; i < n; ++i) {
    char* rec = points.data() + i * kFormat6Size;
    Eigen::Vector3d q;
    for (int a = 0; a < 3; ++a) {
      const auto v = static_cast<int32_t>(std::llround((utm[i][a] - offset[a]) / s));
      PutLe<int32_t>(rec + 4 * a, v);
      q[a] = offset[a] + v * s;
    }
    qlo = qlo.cwiseMin(q);
    qhi = qhi.cwiseMax(q);
    const double in = std::clamp(static_cast<double>(map.cloud.intensities()[i]), 0.0, 1.0);
    PutLe<uint16_t>(rec + 12, static_cast<uint16_t>(std::lround(in * 65535.0)));
    rec[14] = static_cast<char>(1 | (1 << 4));  // return 1 of 1
    // 15 flags, 16 classification (0: created, never classified), 17 user data, 18 scan angle,
    // 20 point source id, 22 GPS time: all 0.
  }
  if (n == 0) qlo = qhi = Eigen::Vector3d::Zero();

  const std::string wkt = UtmZoneWkt(zone, north);
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
  for (uint64_t i = 0; i < count; ++i) {
    const size_t r = point_offset + i * record_length;
    for (int a = 0; a < 3; ++a) {
      las.points_utm[i][a] = las.offset[a] + las.scale[a] * Le<int32_t>(b, r + 4 * a);
    }
    las.intensities[i] = Le<uint16_t>(b, r + intensity_offset);
  }
  return las;
}

}  // namespace slam_mms
