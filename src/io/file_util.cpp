#include "io/file_util.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "slam_mms/io/kitti_timestamp.hpp"

namespace slam_mms::io_internal {

Status WriteFileBytes(const std::filesystem::path& file, std::string_view bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) return UnavailableError("cannot create " + file.string());
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) return UnavailableError("cannot write " + file.string());
  return OkStatus();
}

StatusOr<std::string> ReadFileBytes(const std::filesystem::path& file) {
  // An ifstream opens a folder on Linux and reports an absurd size: say what it is instead.
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    return InvalidArgumentError(file.string() + " is a folder, not a file");
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) return NotFoundError("cannot open " + file.string());
  std::string bytes;
  in.seekg(0, std::ios::end);
  const auto size = in.tellg();
  if (size < 0) return DataLossError("cannot determine the size of " + file.string());
  bytes.resize(static_cast<size_t>(size));
  in.seekg(0, std::ios::beg);
  if (size > 0 && !in.read(bytes.data(), size)) {
    return DataLossError("cannot read " + std::to_string(size) + " bytes from " + file.string());
  }
  return bytes;
}

std::vector<std::string> SplitLines(std::string_view bytes) {
  std::vector<std::string> lines;
  size_t start = 0;
  while (start < bytes.size()) {
    size_t end = bytes.find('\n', start);
    if (end == std::string_view::npos) end = bytes.size();
    std::string line(bytes.substr(start, end - start));
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
    start = end + 1;
  }
  return lines;
}

StatusOr<std::vector<std::string>> ReadLines(const std::filesystem::path& file) {
  SLAM_MMS_ASSIGN_OR_RETURN(const std::string bytes, ReadFileBytes(file));
  return SplitLines(bytes);
}

bool IsBlank(const std::string& line) {
  for (const char c : line) {
    if (!std::isspace(static_cast<unsigned char>(c))) return false;
  }
  return true;
}

StatusOr<std::vector<std::optional<Timestamp>>> ReadTimestampFile(const std::filesystem::path& file,
                                                                  bool allow_blank_lines) {
  SLAM_MMS_ASSIGN_OR_RETURN(const std::vector<std::string> lines, ReadLines(file));
  return ParseTimestampLines(lines, file.string(), allow_blank_lines);
}

StatusOr<std::vector<std::optional<Timestamp>>> ParseTimestampLines(
    const std::vector<std::string>& lines, const std::string& file, bool allow_blank_lines) {
  std::vector<std::optional<Timestamp>> stamps;
  stamps.reserve(lines.size());
  int previous_line = 0;
  Timestamp previous;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line_number = static_cast<int>(i) + 1;
    if (IsBlank(lines[i])) {
      if (!allow_blank_lines) {
        return DataLossError(file + ":" + std::to_string(line_number) + ": empty timestamp line");
      }
      stamps.emplace_back(std::nullopt);
      continue;
    }
    auto stamp = ParseKittiTimestamp(lines[i]);
    if (!stamp.ok()) {
      return DataLossError(file + ":" + std::to_string(line_number) + ": " +
                           stamp.status().message());
    }
    if (previous_line > 0 && *stamp <= previous) {
      return DataLossError(
          file + ":" + std::to_string(line_number) + ": timestamp " + stamp->ToKittiString() +
          (*stamp == previous ? " duplicated" : " goes backwards") + " (line " +
          std::to_string(previous_line) + " has " + previous.ToKittiString() + ")");
    }
    previous = *stamp;
    previous_line = line_number;
    stamps.emplace_back(*stamp);
  }
  return stamps;
}

std::filesystem::path DirPathWithName(const std::filesystem::path& dir) {
  if (dir.empty()) return dir;
  const std::string name = dir.filename().string();
  if (!name.empty() && name != "." && name != "..") return dir;
  std::error_code ec;
  std::filesystem::path p = std::filesystem::absolute(dir, ec).lexically_normal();
  if (ec) return dir;
  if (!p.has_filename() && p.has_parent_path() && p != p.root_path()) p = p.parent_path();
  return p;
}

std::vector<std::string> SplitWhitespace(const std::string& line) {
  std::vector<std::string> tokens;
  std::istringstream is(line);
  std::string t;
  while (is >> t) tokens.push_back(t);
  return tokens;
}

bool ParseDouble(const std::string& token, double* value) {
  if (token.empty()) return false;
  char* end = nullptr;
  const double v = std::strtod(token.c_str(), &end);
  if (end != token.c_str() + token.size() || !std::isfinite(v)) return false;
  *value = v;
  return true;
}

std::string FormatDouble(double v) {
  char buf[40];
  std::snprintf(buf, sizeof(buf), "%.17g", v);
  return buf;
}

}  // namespace slam_mms::io_internal
