// PLY and PCD map files (see map_io.hpp).
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "io/binary_util.hpp"
#include "io/file_util.hpp"
#include "slam_mms/io/map_io.hpp"

namespace slam_mms {

namespace fs = std::filesystem;
using io_internal::AppendLe;
using io_internal::ReadScalar;

Status MapCloud::Validate() const {
  if (!normals.empty() && normals.size() != cloud.size()) {
    return InvalidArgumentError("MapCloud::normals has " + std::to_string(normals.size()) +
                                " entries for " + std::to_string(cloud.size()) +
                                " points; must be empty or equal");
  }
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

// A scalar type of PLY or PCD, by byte size and kind.
struct ScalarType {
  char kind = 'F';  // 'F' float, 'I' signed, 'U' unsigned
  int size = 4;
};

double ReadTyped(const char* p, ScalarType t, bool little_endian) {
  switch (t.kind) {
    case 'F':
      return t.size == 8 ? ReadScalar<double>(p, little_endian)
                         : static_cast<double>(ReadScalar<float>(p, little_endian));
    case 'I':
      switch (t.size) {
        case 1: return static_cast<int8_t>(*p);
        case 2: return ReadScalar<int16_t>(p, little_endian);
        case 4: return ReadScalar<int32_t>(p, little_endian);
        default: return static_cast<double>(ReadScalar<int64_t>(p, little_endian));
      }
    default:
      switch (t.size) {
        case 1: return static_cast<uint8_t>(*p);
        case 2: return ReadScalar<uint16_t>(p, little_endian);
        case 4: return ReadScalar<uint32_t>(p, little_endian);
        default: return static_cast<double>(ReadScalar<uint64_t>(p, little_endian));
      }
  }
}

bool PlyType(const std::string& name, ScalarType* t) {
  static const std::pair<const char*, ScalarType> kTypes[] = {
      {"char", {'I', 1}},  {"int8", {'I', 1}},    {"uchar", {'U', 1}},  {"uint8", {'U', 1}},
      {"short", {'I', 2}}, {"int16", {'I', 2}},   {"ushort", {'U', 2}}, {"uint16", {'U', 2}},
      {"int", {'I', 4}},   {"int32", {'I', 4}},   {"uint", {'U', 4}},   {"uint32", {'U', 4}},
      {"float", {'F', 4}}, {"float32", {'F', 4}}, {"double", {'F', 8}}, {"float64", {'F', 8}}};
  for (const auto& [n, type] : kTypes) {
    if (name == n) {
      *t = type;
      return true;
    }
  }
  return false;
}

// Column indices of the fields MapCloud keeps; -1 where absent.
struct Columns {
  int x = -1, y = -1, z = -1, intensity = -1, nx = -1, ny = -1, nz = -1;

  void Assign(const std::string& name, int index) {
    if (name == "x") x = index;
    if (name == "y") y = index;
    if (name == "z") z = index;
    if (name == "intensity" || name == "scalar_intensity" || name == "reflectance") {
      intensity = index;
    }
    if (name == "nx" || name == "normal_x") nx = index;
    if (name == "ny" || name == "normal_y") ny = index;
    if (name == "nz" || name == "normal_z") nz = index;
  }
  bool has_normals() const { return nx >= 0 && ny >= 0 && nz >= 0; }
};

// Fills `map` from per-point column values.
void AddPoint(const std::vector<double>& v, const Columns& c, MapCloud* map) {
  map->cloud.Add(Eigen::Vector3f(static_cast<float>(v[c.x]), static_cast<float>(v[c.y]),
                                 static_cast<float>(v[c.z])),
                 c.intensity >= 0 ? static_cast<float>(v[c.intensity]) : 0.0f);
  if (c.has_normals()) {
    map->normals.emplace_back(static_cast<float>(v[c.nx]), static_cast<float>(v[c.ny]),
                              static_cast<float>(v[c.nz]));
  }
}

// Position just after the header's terminating line (`marker` then '\n'); npos where absent.
size_t HeaderEnd(const std::string& bytes, const std::string& marker, size_t search_from = 0) {
  size_t pos = search_from;
  while (true) {
    pos = bytes.find(marker, pos);
    if (pos == std::string::npos) return pos;
    const bool line_start = pos == 0 || bytes[pos - 1] == '\n';
    const size_t nl = bytes.find('\n', pos);
    if (line_start && nl != std::string::npos) return nl + 1;
    pos += marker.size();
  }
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
  if (bytes.compare(0, 4, "ply\n") != 0 && bytes.compare(0, 5, "ply\r\n") != 0) {
    return DataLossError(f + ": not a PLY file (no 'ply' magic line)");
  }
  const size_t data_start = HeaderEnd(bytes, "end_header");
  if (data_start == std::string::npos) return DataLossError(f + ": PLY header has no end_header");
  std::istringstream header(bytes.substr(0, data_start));
  std::string line;
  enum class Format { kAscii, kBinaryLe, kBinaryBe } format = Format::kAscii;
  bool have_format = false;
  struct Element {
    std::string name;
    size_t count = 0;
    std::vector<std::pair<std::string, ScalarType>> properties;
    bool has_list = false;
  };
  std::vector<Element> elements;
  int line_number = 0;
  while (std::getline(header, line)) {
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto tok = io_internal::SplitWhitespace(line);
    const std::string where = f + ":" + std::to_string(line_number);
    if (tok.empty() || tok[0] == "ply" || tok[0] == "comment" || tok[0] == "obj_info" ||
        tok[0] == "end_header") {
      continue;
    }
    if (tok[0] == "format") {
      if (tok.size() < 2) return DataLossError(where + ": bad format line");
      if (tok[1] == "ascii") {
        format = Format::kAscii;
      } else if (tok[1] == "binary_little_endian") {
        format = Format::kBinaryLe;
      } else if (tok[1] == "binary_big_endian") {
        format = Format::kBinaryBe;
      } else {
        return DataLossError(where + ": unknown PLY format '" + tok[1] + "'");
      }
      have_format = true;
    } else if (tok[0] == "element") {
      char* end = nullptr;
      if (tok.size() != 3) return DataLossError(where + ": bad element line");
      const unsigned long long n = std::strtoull(tok[2].c_str(), &end, 10);
      if (*end != '\0') return DataLossError(where + ": bad element count '" + tok[2] + "'");
      elements.push_back(Element{tok[1], static_cast<size_t>(n), {}, false});
    } else if (tok[0] == "property") {
      if (elements.empty()) return DataLossError(where + ": property before any element");
      if (tok.size() >= 2 && tok[1] == "list") {
        elements.back().has_list = true;
        continue;
      }
      ScalarType t;
      if (tok.size() != 3 || !PlyType(tok[1], &t)) {
        return DataLossError(where + ": bad property line '" + line + "'");
      }
      elements.back().properties.emplace_back(tok[2], t);
    } else {
      return DataLossError(where + ": unknown PLY header keyword '" + tok[0] + "'");
    }
  }
  if (!have_format) return DataLossError(f + ": PLY header has no format line");
  if (elements.empty() || elements.front().name != "vertex") {
    return Status(StatusCode::kUnimplemented, f + ": the first PLY element must be 'vertex'");
  }
  const Element& v = elements.front();
  if (v.has_list)
    return Status(StatusCode::kUnimplemented,
                  f + ": list properties in 'vertex' are not supported");
  Columns cols;
  size_t record_size = 0;
  std::vector<size_t> offsets;
  for (size_t k = 0; k < v.properties.size(); ++k) {
    cols.Assign(v.properties[k].first, static_cast<int>(k));
    offsets.push_back(record_size);
    record_size += v.properties[k].second.size;
  }
  if (cols.x < 0 || cols.y < 0 || cols.z < 0) {
    return DataLossError(f + ": PLY vertex element lacks x, y or z");
  }
  MapCloud map;
  map.cloud.reserve(v.count);
  std::vector<double> values(v.properties.size());
  if (format == Format::kAscii) {
    size_t pos = data_start;
    size_t line_no = static_cast<size_t>(line_number);
    for (size_t i = 0; i < v.count; ++i) {
      size_t nl = bytes.find('\n', pos);
      if (nl == std::string::npos) nl = bytes.size();
      ++line_no;
      if (pos >= bytes.size()) {
        return DataLossError(f + ": PLY ends after " + std::to_string(i) + " of " +
                             std::to_string(v.count) + " vertices");
      }
      const auto tok = io_internal::SplitWhitespace(bytes.substr(pos, nl - pos));
      if (tok.size() != v.properties.size()) {
        return DataLossError(f + ":" + std::to_string(line_no) + ": vertex has " +
                             std::to_string(tok.size()) + " values, expected " +
                             std::to_string(v.properties.size()));
      }
      for (size_t k = 0; k < tok.size(); ++k) {
        if (!io_internal::ParseDouble(tok[k], &values[k])) {
          return DataLossError(f + ":" + std::to_string(line_no) + ": property " +
                               v.properties[k].first + " '" + tok[k] + "' is not a number");
        }
      }
      AddPoint(values, cols, &map);
      pos = nl + 1;
    }
  } else {
    const bool le = format == Format::kBinaryLe;
    const size_t needed = v.count * record_size;
    if (bytes.size() - data_start < needed) {
      return DataLossError(
          f + ": PLY binary data has " + std::to_string(bytes.size() - data_start) +
          " bytes, expected at least " + std::to_string(needed) + " for " +
          std::to_string(v.count) + " vertices of " + std::to_string(record_size) + " bytes");
    }
    for (size_t i = 0; i < v.count; ++i) {
      const char* rec = bytes.data() + data_start + i * record_size;
      for (size_t k = 0; k < values.size(); ++k) {
        values[k] = ReadTyped(rec + offsets[k], v.properties[k].second, le);
      }
      AddPoint(values, cols, &map);
    }
  }
  return map;
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
  size_t pos = 0;
  std::vector<std::string> fields;
  std::vector<ScalarType> types;
  std::vector<int> sizes, counts;
  size_t points = 0;
  bool have_points = false;
  std::string data;
  int line_number = 0;
  while (data.empty()) {
    if (pos >= bytes.size()) return DataLossError(f + ": PCD header has no DATA line");
    size_t nl = bytes.find('\n', pos);
    if (nl == std::string::npos) nl = bytes.size();
    std::string line = bytes.substr(pos, nl - pos);
    pos = nl + 1;
    ++line_number;
    const std::string where = f + ":" + std::to_string(line_number);
    const auto tok = io_internal::SplitWhitespace(line);
    if (tok.empty() || tok[0][0] == '#') continue;
    const std::string& key = tok[0];
    if (key == "FIELDS") {
      fields.assign(tok.begin() + 1, tok.end());
    } else if (key == "SIZE" || key == "COUNT") {
      auto& target = key == "SIZE" ? sizes : counts;
      target.clear();
      for (size_t k = 1; k < tok.size(); ++k) target.push_back(std::atoi(tok[k].c_str()));
    } else if (key == "TYPE") {
      types.clear();
      for (size_t k = 1; k < tok.size(); ++k) types.push_back(ScalarType{tok[k][0], 0});
    } else if (key == "POINTS") {
      if (tok.size() != 2) return DataLossError(where + ": bad POINTS line");
      points = std::strtoull(tok[1].c_str(), nullptr, 10);
      have_points = true;
    } else if (key == "DATA") {
      if (tok.size() != 2) return DataLossError(where + ": bad DATA line");
      data = tok[1];
    } else if (key != "VERSION" && key != "WIDTH" && key != "HEIGHT" && key != "VIEWPOINT") {
      return DataLossError(where + ": unknown PCD header key '" + key + "'");
    }
  }
  if (counts.empty()) counts.assign(fields.size(), 1);
  if (fields.empty() || sizes.size() != fields.size() || types.size() != fields.size() ||
      counts.size() != fields.size() || !have_points) {
    return DataLossError(f +
                         ": PCD header needs FIELDS, SIZE, TYPE (and COUNT) of equal length "
                         "and POINTS");
  }
  Columns cols;
  std::vector<size_t> offsets;
  int num_values = 0;
  size_t record_size = 0;
  for (size_t k = 0; k < fields.size(); ++k) {
    types[k].size = sizes[k];
    if ((types[k].kind != 'F' && types[k].kind != 'I' && types[k].kind != 'U') ||
        (sizes[k] != 1 && sizes[k] != 2 && sizes[k] != 4 && sizes[k] != 8) || counts[k] < 1 ||
        (types[k].kind == 'F' && sizes[k] != 4 && sizes[k] != 8)) {
      return DataLossError(f + ": PCD field '" + fields[k] + "' has an unsupported TYPE/SIZE");
    }
    if (counts[k] == 1) cols.Assign(fields[k], num_values);
    for (int c = 0; c < counts[k]; ++c) offsets.push_back(record_size + c * sizes[k]);
    num_values += counts[k];
    record_size += static_cast<size_t>(sizes[k]) * counts[k];
  }
  if (cols.x < 0 || cols.y < 0 || cols.z < 0) return DataLossError(f + ": PCD lacks x, y or z");
  std::vector<ScalarType> value_types;
  for (size_t k = 0; k < fields.size(); ++k) {
    for (int c = 0; c < counts[k]; ++c) value_types.push_back(types[k]);
  }
  MapCloud map;
  map.cloud.reserve(points);
  std::vector<double> values(num_values);
  if (data == "ascii") {
    for (size_t i = 0; i < points; ++i) {
      if (pos >= bytes.size()) {
        return DataLossError(f + ": PCD ends after " + std::to_string(i) + " of " +
                             std::to_string(points) + " points");
      }
      size_t nl = bytes.find('\n', pos);
      if (nl == std::string::npos) nl = bytes.size();
      ++line_number;
      const auto tok = io_internal::SplitWhitespace(bytes.substr(pos, nl - pos));
      pos = nl + 1;
      if (tok.size() != values.size()) {
        return DataLossError(f + ":" + std::to_string(line_number) + ": point has " +
                             std::to_string(tok.size()) + " values, expected " +
                             std::to_string(values.size()));
      }
      for (size_t k = 0; k < tok.size(); ++k) {
        // PCL writes "nan" for invalid points: parse it as NaN here.
        char* end = nullptr;
        values[k] = std::strtod(tok[k].c_str(), &end);
        if (*end != '\0') {
          return DataLossError(f + ":" + std::to_string(line_number) + ": value '" + tok[k] +
                               "' is not a number");
        }
      }
      AddPoint(values, cols, &map);
    }
  } else if (data == "binary") {
    const size_t needed = points * record_size;
    if (bytes.size() < pos || bytes.size() - pos < needed) {
      return DataLossError(f + ": PCD binary data has " +
                           std::to_string(bytes.size() < pos ? 0 : bytes.size() - pos) +
                           " bytes, expected " + std::to_string(needed));
    }
    for (size_t i = 0; i < points; ++i) {
      const char* rec = bytes.data() + pos + i * record_size;
      for (int k = 0; k < num_values; ++k) {
        values[k] = ReadTyped(rec + offsets[k], value_types[k], true);
      }
      AddPoint(values, cols, &map);
    }
  } else if (data == "binary_compressed") {
    return Status(StatusCode::kUnimplemented, f + ": PCD DATA binary_compressed is not supported");
  } else {
    return DataLossError(f + ": unknown PCD DATA '" + data + "'");
  }
  return map;
}

}  // namespace slam_mms
