#include "io/point_file_format.hpp"

#include <cctype>
#include <cstdlib>
#include <cstring>
#include <limits>

#include "io/binary_util.hpp"
#include "io/file_util.hpp"

namespace slam_mms::io_internal {
namespace {

// More values per point than any real file has: a corrupt COUNT would otherwise allocate GBs.
constexpr size_t kMaxColumns = 4096;

std::string Where(const std::string& file, int line) { return file + ":" + std::to_string(line); }

// A whole token as a non-negative integer; false on anything else or overflow.
bool ParseCount(const std::string& token, unsigned long long* value) {
  if (token.empty() || token.size() > 19) return false;
  unsigned long long v = 0;
  for (const char c : token) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + static_cast<unsigned long long>(c - '0');
  }
  *value = v;
  return true;
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

// The next line of `bytes` from `*pos` (without '\n' and a trailing '\r'); advances `*pos`.
std::string_view NextLine(std::string_view bytes, size_t* pos) {
  size_t nl = bytes.find('\n', *pos);
  if (nl == std::string_view::npos) nl = bytes.size();
  std::string_view line = bytes.substr(*pos, nl - *pos);
  *pos = nl + 1;
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return line;
}

}  // namespace

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

int PointFileLayout::ColumnIndex(std::string_view name) const {
  for (size_t k = 0; k < columns.size(); ++k) {
    if (columns[k].count == 1 && columns[k].name == name) return static_cast<int>(k);
  }
  return -1;
}

// ------------------------------------------------------------------------------------------------
StatusOr<PointFileLayout> ParsePcdHeader(std::string_view bytes, const std::string& f) {
  PointFileLayout layout;
  layout.format = "PCD";
  std::vector<std::string> fields, types;
  std::vector<unsigned long long> sizes, counts;
  int fields_line = 0, sizes_line = 0, types_line = 0, counts_line = 0, points_line = 0;
  int width_line = 0, height_line = 0;
  unsigned long long points = 0, width = 0, height = 0;
  std::string data;
  size_t pos = 0;
  int line_number = 0;
  while (data.empty()) {
    if (pos >= bytes.size()) return DataLossError(f + ": PCD header has no DATA line");
    const std::string line(NextLine(bytes, &pos));
    ++line_number;
    const std::string where = Where(f, line_number);
    const auto tok = SplitWhitespace(line);
    if (tok.empty() || tok[0][0] == '#') continue;
    const std::string& key = tok[0];
    if (key == "FIELDS") {
      fields.assign(tok.begin() + 1, tok.end());
      fields_line = line_number;
      if (fields.empty()) return DataLossError(where + ": FIELDS lists no field");
    } else if (key == "SIZE" || key == "COUNT" || key == "POINTS" || key == "WIDTH" ||
               key == "HEIGHT") {
      std::vector<unsigned long long> numbers;
      for (size_t k = 1; k < tok.size(); ++k) {
        unsigned long long v = 0;
        if (!ParseCount(tok[k], &v)) {
          return DataLossError(where + ": " + key + " entry " + std::to_string(k) + " '" + tok[k] +
                               "' is not a non-negative integer");
        }
        numbers.push_back(v);
      }
      if (key == "SIZE") {
        sizes = numbers;
        sizes_line = line_number;
      } else if (key == "COUNT") {
        counts = numbers;
        counts_line = line_number;
      } else {
        if (numbers.size() != 1) {
          return DataLossError(where + ": " + key + " needs one number, has " +
                               std::to_string(numbers.size()));
        }
        (key == "POINTS" ? points : key == "WIDTH" ? width : height) = numbers[0];
        (key == "POINTS" ? points_line : key == "WIDTH" ? width_line : height_line) = line_number;
      }
    } else if (key == "TYPE") {
      types.assign(tok.begin() + 1, tok.end());
      types_line = line_number;
    } else if (key == "DATA") {
      if (tok.size() != 2) return DataLossError(where + ": DATA needs one word (ascii or binary)");
      data = tok[1];
      if (data == "ascii") {
        layout.encoding = PointEncoding::kAscii;
      } else if (data == "binary") {
        layout.encoding = PointEncoding::kBinaryLittleEndian;
      } else if (data == "binary_compressed") {
        return Status(StatusCode::kUnimplemented,
                      where +
                          ": PCD DATA binary_compressed is not supported (convert the file to "
                          "DATA binary, e.g. with PCL's pcl_convert_pcd_ascii_binary)");
      } else {
        return DataLossError(where + ": unknown PCD DATA '" + data +
                             "' (expected ascii or binary)");
      }
    } else if (key != "VERSION" && key != "VIEWPOINT") {
      return DataLossError(where + ": unknown PCD header key '" + key + "'");
    }
  }
  layout.header_lines = line_number;
  layout.data_offset = std::min(pos, bytes.size());
  if (fields.empty()) return DataLossError(f + ": PCD header has no FIELDS line");
  const auto check_length = [&](const char* key, size_t n, int line) -> Status {
    if (line == 0) return DataLossError(f + ": PCD header has no " + key + " line");
    if (n != fields.size()) {
      return DataLossError(Where(f, line) + ": " + key + " has " + std::to_string(n) +
                           " entries but FIELDS (line " + std::to_string(fields_line) + ") has " +
                           std::to_string(fields.size()));
    }
    return OkStatus();
  };
  SLAM_MMS_RETURN_IF_ERROR(check_length("SIZE", sizes.size(), sizes_line));
  SLAM_MMS_RETURN_IF_ERROR(check_length("TYPE", types.size(), types_line));
  if (counts_line == 0) counts.assign(fields.size(), 1);
  SLAM_MMS_RETURN_IF_ERROR(
      check_length("COUNT", counts.size(), counts_line == 0 ? -1 : counts_line));
  if (points_line == 0) {
    if (width_line == 0 || height_line == 0) {
      return DataLossError(f + ": PCD header has no POINTS line (nor WIDTH and HEIGHT)");
    }
    if (height != 0 && width > std::numeric_limits<unsigned long long>::max() / height) {
      return DataLossError(Where(f, width_line) + ": WIDTH x HEIGHT overflows");
    }
    points = width * height;
  } else if (width_line > 0 && height_line > 0 &&
             ((height != 0 && width > std::numeric_limits<unsigned long long>::max() / height) ||
              width * height != points)) {
    return DataLossError(Where(f, points_line) + ": POINTS " + std::to_string(points) +
                         " but WIDTH x HEIGHT = " + std::to_string(width) + " x " +
                         std::to_string(height) + " (lines " + std::to_string(width_line) + ", " +
                         std::to_string(height_line) + ")");
  }
  layout.num_points = static_cast<size_t>(points);
  for (size_t k = 0; k < fields.size(); ++k) {
    const std::string& t = types[k];
    const unsigned long long size = sizes[k];
    const bool ok_type = t.size() == 1 && (t[0] == 'F' || t[0] == 'I' || t[0] == 'U');
    const bool ok_size = size == 1 || size == 2 || size == 4 || size == 8;
    if (!ok_type || !ok_size || (t[0] == 'F' && size != 4 && size != 8)) {
      return DataLossError(Where(f, types_line) + ": field '" + fields[k] + "' has TYPE " + t +
                           " SIZE " + std::to_string(size) + " (supported: F 4/8, I or U 1/2/4/8)");
    }
    if (counts[k] < 1 || layout.columns.size() + counts[k] > kMaxColumns) {
      return DataLossError(Where(f, counts_line) + ": field '" + fields[k] + "' has COUNT " +
                           std::to_string(counts[k]) + " (must be 1.." +
                           std::to_string(kMaxColumns) + " values per point in all)");
    }
    for (unsigned long long c = 0; c < counts[k]; ++c) {
      PointColumn col;
      col.name = fields[k];
      col.element = static_cast<int>(c);
      col.count = static_cast<int>(counts[k]);
      col.type = ScalarType{t[0], static_cast<int>(size)};
      col.offset = layout.record_size;
      layout.columns.push_back(col);
      layout.record_size += size;
    }
  }
  return layout;
}

// ------------------------------------------------------------------------------------------------
StatusOr<PointFileLayout> ParsePlyHeader(std::string_view bytes, const std::string& f) {
  PointFileLayout layout;
  layout.format = "PLY";
  layout.noun = "vertex";
  layout.nouns = "vertices";
  if (bytes.substr(0, 4) != "ply\n" && bytes.substr(0, 5) != "ply\r\n") {
    return DataLossError(f + ": not a PLY file (no 'ply' magic line)");
  }
  bool have_format = false, have_end = false;
  bool any_element = false, vertex_seen = false, in_vertex = false, vertex_first = true;
  size_t pos = 0;
  int line_number = 0;
  while (!have_end) {
    if (pos >= bytes.size()) return DataLossError(f + ": PLY header has no end_header");
    const std::string line(NextLine(bytes, &pos));
    ++line_number;
    const std::string where = Where(f, line_number);
    const auto tok = SplitWhitespace(line);
    if (tok.empty() || tok[0] == "comment" || tok[0] == "obj_info") continue;
    if (tok[0] == "ply" && line_number == 1) continue;
    if (tok[0] == "end_header") {
      have_end = true;
    } else if (tok[0] == "format") {
      if (tok.size() < 2) return DataLossError(where + ": bad format line");
      if (tok[1] == "ascii") {
        layout.encoding = PointEncoding::kAscii;
      } else if (tok[1] == "binary_little_endian") {
        layout.encoding = PointEncoding::kBinaryLittleEndian;
      } else if (tok[1] == "binary_big_endian") {
        layout.encoding = PointEncoding::kBinaryBigEndian;
      } else {
        return DataLossError(where + ": unknown PLY format '" + tok[1] + "'");
      }
      have_format = true;
    } else if (tok[0] == "element") {
      unsigned long long n = 0;
      if (tok.size() != 3) return DataLossError(where + ": bad element line '" + line + "'");
      if (!ParseCount(tok[2], &n)) {
        return DataLossError(where + ": bad element count '" + tok[2] + "'");
      }
      in_vertex = tok[1] == "vertex" && !vertex_seen;
      if (in_vertex) {
        vertex_first = !any_element;
        vertex_seen = true;
        layout.num_points = static_cast<size_t>(n);
      }
      any_element = true;
    } else if (tok[0] == "property") {
      if (!any_element) return DataLossError(where + ": property before any element");
      if (!in_vertex) continue;  // a property of a later element (faces): ignored
      if (tok.size() >= 2 && tok[1] == "list") {
        return Status(StatusCode::kUnimplemented,
                      where + ": list properties in 'vertex' are not supported");
      }
      ScalarType t;
      if (tok.size() != 3 || !PlyType(tok[1], &t)) {
        return DataLossError(where + ": bad property line '" + line + "'");
      }
      if (layout.columns.size() >= kMaxColumns) {
        return DataLossError(where + ": more than " + std::to_string(kMaxColumns) +
                             " vertex properties");
      }
      PointColumn col;
      col.name = tok[2];
      col.type = t;
      col.offset = layout.record_size;
      layout.columns.push_back(col);
      layout.record_size += static_cast<size_t>(t.size);
    } else {
      return DataLossError(where + ": unknown PLY header keyword '" + tok[0] + "'");
    }
  }
  layout.header_lines = line_number;
  layout.data_offset = std::min(pos, bytes.size());
  if (!have_format) return DataLossError(f + ": PLY header has no format line");
  if (!vertex_seen) return DataLossError(f + ": PLY header has no 'vertex' element");
  if (!vertex_first) {
    return Status(StatusCode::kUnimplemented, f + ": the first PLY element must be 'vertex'");
  }
  return layout;
}

// ------------------------------------------------------------------------------------------------
Status DecodePointColumns(std::string_view bytes, const PointFileLayout& layout,
                          const std::string& f, const std::vector<int>& wanted,
                          std::vector<float>* values) {
  values->clear();
  const size_t n = layout.num_points;
  const size_t m = wanted.size();
  const size_t start = std::min(layout.data_offset, bytes.size());
  const size_t available = bytes.size() - start;
  if (layout.encoding != PointEncoding::kAscii) {
    const size_t rec = layout.record_size;
    const size_t complete = rec == 0 ? n : available / rec;
    if (complete < n) {
      return DataLossError(f + ": " + layout.format + " binary data has " +
                           std::to_string(available) + " bytes, expected at least " +
                           std::to_string(n) + " x " + std::to_string(rec) + " for " +
                           std::to_string(n) + " " + layout.nouns + " of " + std::to_string(rec) +
                           " bytes: only " + std::to_string(complete) + " of " + std::to_string(n) +
                           " " + layout.nouns + " (truncated file?)");
    }
    const bool le = layout.encoding == PointEncoding::kBinaryLittleEndian;
    values->resize(n * m);
    float* out = values->data();
    const char* data = bytes.data() + start;
    // Fast path: the records are exactly the wanted float32 columns in order (x y z intensity [t]
    // as PCL and WriteDriveFolder write them): one copy.
    bool packed = le == kHostIsLittleEndian && rec == 4 * m;
    for (size_t k = 0; k < m && packed; ++k) {
      const int c = wanted[k];
      packed = c >= 0 && layout.columns[static_cast<size_t>(c)].type.kind == 'F' &&
               layout.columns[static_cast<size_t>(c)].type.size == 4 &&
               layout.columns[static_cast<size_t>(c)].offset == 4 * k;
    }
    if (packed) {
      if (n > 0) std::memcpy(out, data, n * rec);
      return OkStatus();
    }
    for (size_t i = 0; i < n; ++i) {
      const char* record = data + i * rec;
      for (size_t k = 0; k < m; ++k) {
        const int c = wanted[k];
        if (c < 0) {
          out[i * m + k] = 0.0f;
          continue;
        }
        const PointColumn& col = layout.columns[static_cast<size_t>(c)];
        if (col.type.kind == 'F' && col.type.size == 4) {
          out[i * m + k] = ReadScalar<float>(record + col.offset, le);
        } else {
          out[i * m + k] = static_cast<float>(ReadTyped(record + col.offset, col.type, le));
        }
      }
    }
    return OkStatus();
  }
  // Ascii: one point per non-blank line.
  values->reserve(std::min(n, available / 2 + 1) * m);
  const size_t num_columns = layout.columns.size();
  std::vector<double> row(num_columns);
  size_t pos = start;
  int line_number = layout.header_lines;
  for (size_t i = 0; i < n; ++i) {
    std::string line;
    do {
      if (pos >= bytes.size()) {
        return DataLossError(f + ": " + layout.format + " ends after " + std::to_string(i) +
                             " of " + std::to_string(n) + " " + layout.nouns +
                             " (header declares " + std::to_string(n) + ")");
      }
      line = std::string(NextLine(bytes, &pos));
      ++line_number;
    } while (IsBlank(line));
    const char* p = line.c_str();
    size_t count = 0;
    while (true) {
      while (*p != '\0' && std::isspace(static_cast<unsigned char>(*p))) ++p;
      if (*p == '\0') break;
      const char* token = p;
      while (*p != '\0' && !std::isspace(static_cast<unsigned char>(*p))) ++p;
      if (count < num_columns) {
        char* end = nullptr;
        const std::string text(token, p);
        row[count] = std::strtod(text.c_str(), &end);
        if (end != text.c_str() + text.size()) {
          return DataLossError(Where(f, line_number) + ": " + layout.noun + " " +
                               std::to_string(i) + " field '" + layout.columns[count].name +
                               "': '" + text + "' is not a number");
        }
      }
      ++count;
    }
    if (count != num_columns) {
      return DataLossError(Where(f, line_number) + ": " + layout.noun + " has " +
                           std::to_string(count) + " values, expected " +
                           std::to_string(num_columns));
    }
    for (size_t k = 0; k < m; ++k) {
      values->push_back(wanted[k] < 0 ? 0.0f
                                      : static_cast<float>(row[static_cast<size_t>(wanted[k])]));
    }
  }
  return OkStatus();
}

}  // namespace slam_mms::io_internal
