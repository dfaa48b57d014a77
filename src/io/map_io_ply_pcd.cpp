// PLY and PCD map files (see map_io.hpp).
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "io/binary_util.hpp"
#include "io/file_util.hpp"
#include "io/point_file_format.hpp"
#include "slam_mms/io/map_io.hpp"

namespace slam_mms {

namespace fs = std::filesystem;
using io_internal::AppendLe;

Status MapCloud::Validate() const {
  if (!normals.empty() && normals.size() != cloud.size()) {
    return InvalidArgumentError("MapCloud::normals has " + std::to_string(normals.size()) +
                                " entries for " + std::to_string(cloud.size()) +
                                " points; must be empty or equal");
  }
  const auto check = [&](size_t size, const char* field) {
    return size == 0 || size == cloud.size()
               ? OkStatus()
               : InvalidArgumentError(std::string("MapCloud::") + field + " has " +
                                      std::to_string(size) + " entries for " +
                                      std::to_string(cloud.size()) +
                                      " points; must be empty or equal");
  };
  SLAM_MMS_RETURN_IF_ERROR(check(time_ns.size(), "time_ns"));
  SLAM_MMS_RETURN_IF_ERROR(check(source_id.size(), "source_id"));
  SLAM_MMS_RETURN_IF_ERROR(check(classification.size(), "classification"));
  if (cloud.intensities().size() != cloud.size()) {
    return InvalidArgumentError("MapCloud::cloud has " +
                                std::to_string(cloud.intensities().size()) + " intensities for " +
                                std::to_string(cloud.size()) + " points");
  }
  return OkStatus();
}

namespace {

Status WriteAll(const fs::path& file, const std::string& header, const std::string& body) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) return UnavailableError("cannot create " + file.string());
  out.write(header.data(), static_cast<std::streamsize>(header.size()));
  out.write(body.data(), static_cast<std::streamsize>(body.size()));
  out.close();
  if (!out) return DataLossError("cannot write " + file.string());
  return OkStatus();
}

// Point records x y z intensity [nx ny nz] as little-endian float32.
std::string PackFloatRecords(const MapCloud& map) {
  const size_t fields = map.has_normals() ? 7 : 4;
  std::string body;
  body.reserve(map.cloud.size() * fields * 4);
  for (size_t i = 0; i < map.cloud.size(); ++i) {
    const Eigen::Vector3f& p = map.cloud.points()[i];
    AppendLe<float>(&body, p.x());
    AppendLe<float>(&body, p.y());
    AppendLe<float>(&body, p.z());
    AppendLe<float>(&body, map.cloud.intensities()[i]);
    if (map.has_normals()) {
      const Eigen::Vector3f& n = map.normals[i];
      AppendLe<float>(&body, n.x());
      AppendLe<float>(&body, n.y());
      AppendLe<float>(&body, n.z());
    }
  }
  return body;
}

// Index of the first of `names` among the layout's COUNT-1 columns; -1 when none.
int FindColumn(const io_internal::PointFileLayout& layout,
               std::initializer_list<std::string_view> names) {
  for (const std::string_view n : names) {
    const int c = layout.ColumnIndex(n);
    if (c >= 0) return c;
  }
  return -1;
}

// The map of a PLY/PCD file whose header is `layout`: x y z, intensity (also scalar_intensity,
// reflectance; 0 where absent), normals where nx/normal_x, ... are all present.
StatusOr<MapCloud> MapFromLayout(const std::string& bytes,
                                 const io_internal::PointFileLayout& layout, const std::string& f) {
  const int nx = FindColumn(layout, {"nx", "normal_x"});
  const int ny = FindColumn(layout, {"ny", "normal_y"});
  const int nz = FindColumn(layout, {"nz", "normal_z"});
  const bool normals = nx >= 0 && ny >= 0 && nz >= 0;
  std::vector<int> wanted = {FindColumn(layout, {"x"}), FindColumn(layout, {"y"}),
                             FindColumn(layout, {"z"}),
                             FindColumn(layout, {"intensity", "scalar_intensity", "reflectance"})};
  if (wanted[0] < 0 || wanted[1] < 0 || wanted[2] < 0) {
    return DataLossError(f + ": " + layout.format + " " + layout.noun + " lacks x, y or z");
  }
  if (normals) wanted.insert(wanted.end(), {nx, ny, nz});
  std::vector<float> v;
  SLAM_MMS_RETURN_IF_ERROR(io_internal::DecodePointColumns(bytes, layout, f, wanted, &v));
  const size_t m = wanted.size();
  const size_t n = v.size() / m;
  MapCloud map;
  map.cloud.reserve(n);
  if (normals) map.normals.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    const float* r = &v[i * m];
    map.cloud.Add(Eigen::Vector3f(r[0], r[1], r[2]), r[3]);
    if (normals) map.normals.emplace_back(r[4], r[5], r[6]);
  }
  return map;
}

}  // namespace

// ------------------------------------------------------------------------------------------------
Status WritePly(const MapCloud& map, const fs::path& file) {
  SLAM_MMS_RETURN_IF_ERROR(map.Validate());
  std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment slam_mms map\nelement vertex " +
      std::to_string(map.cloud.size()) +
      "\nproperty float x\nproperty float y\nproperty float z\nproperty float intensity\n";
  if (map.has_normals()) header += "property float nx\nproperty float ny\nproperty float nz\n";
  header += "end_header\n";
  return WriteAll(file, header, PackFloatRecords(map));
}

StatusOr<MapCloud> ReadPly(const fs::path& file) {
  SLAM_MMS_ASSIGN_OR_RETURN(const std::string bytes, io_internal::ReadFileBytes(file));
  const std::string f = file.string();
  SLAM_MMS_ASSIGN_OR_RETURN(const io_internal::PointFileLayout layout,
                            io_internal::ParsePlyHeader(bytes, f));
  return MapFromLayout(bytes, layout, f);
}

// ------------------------------------------------------------------------------------------------
Status WritePcd(const MapCloud& map, const fs::path& file) {
  SLAM_MMS_RETURN_IF_ERROR(map.Validate());
  const bool n = map.has_normals();
  const std::string count = std::to_string(map.cloud.size());
  std::string header = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n";
  header += n ? "FIELDS x y z intensity normal_x normal_y normal_z\nSIZE 4 4 4 4 4 4 4\n"
                "TYPE F F F F F F F\nCOUNT 1 1 1 1 1 1 1\n"
              : "FIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n";
  header +=
      "WIDTH " + count + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + count + "\nDATA binary\n";
  return WriteAll(file, header, PackFloatRecords(map));
}

StatusOr<MapCloud> ReadPcd(const fs::path& file) {
  SLAM_MMS_ASSIGN_OR_RETURN(const std::string bytes, io_internal::ReadFileBytes(file));
  const std::string f = file.string();
  SLAM_MMS_ASSIGN_OR_RETURN(const io_internal::PointFileLayout layout,
                            io_internal::ParsePcdHeader(bytes, f));
  return MapFromLayout(bytes, layout, f);
}

}  // namespace slam_mms
