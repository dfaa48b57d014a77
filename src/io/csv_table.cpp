#include "io/csv_table.hpp"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "io/file_util.hpp"

namespace slam_mms::io_internal {
namespace {

std::string Trim(std::string_view s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return std::string(s.substr(a, b - a));
}

std::vector<std::string> SplitFields(std::string_view line) {
  std::vector<std::string> fields;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      fields.push_back(Trim(line.substr(start)));
      return fields;
    }
    fields.push_back(Trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
}

std::string Joined(const std::vector<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : ",") + n;
  return s;
}

// Quoted for messages, shortened (a fuzzed field may be megabytes).
std::string Quoted(const std::string& text) {
  return "'" + (text.size() > 40 ? text.substr(0, 40) + "..." : text) + "'";
}

}  // namespace

StatusOr<CsvTable> CsvTable::Parse(std::string_view bytes, const std::string& file,
                                   const CsvSchema& schema) {
  CsvTable t;
  t.file_ = file;
  const std::vector<std::string> lines = SplitLines(bytes);
  bool have_header = false;
  int header_line = 0;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int line_number = static_cast<int>(i) + 1;
    const std::string trimmed = Trim(lines[i]);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    const std::string where = file + ":" + std::to_string(line_number);
    std::vector<std::string> fields = SplitFields(lines[i]);
    if (!have_header) {
      // Header: required columns in order, then optional ones in their order.
      size_t opt = 0;
      for (size_t k = 0; k < fields.size(); ++k) {
        const std::string& name = fields[k];
        if (k < schema.required.size()) {
          if (name != schema.required[k]) {
            return DataLossError(where + ": header column " + std::to_string(k + 1) + " is " +
                                 Quoted(name) + ", expected '" + schema.required[k] +
                                 "' (header must be " + Joined(schema.required) + ")");
          }
          continue;
        }
        while (opt < schema.optional.size() && schema.optional[opt] != name) ++opt;
        if (opt == schema.optional.size()) {
          return DataLossError(
              where + ": header column " + std::to_string(k + 1) + " " + Quoted(name) +
              " is unknown or out of order (after " + Joined(schema.required) +
              (schema.optional.empty()
                   ? std::string(" no column is allowed")
                   : " only " + Joined(schema.optional) + " may follow, in this order") +
              ")");
        }
        ++opt;
      }
      if (fields.size() < schema.required.size()) {
        return DataLossError(where + ": header has " + std::to_string(fields.size()) +
                             " columns; column " + std::to_string(fields.size() + 1) + " '" +
                             schema.required[fields.size()] + "' is missing (header must be " +
                             Joined(schema.required) + ")");
      }
      t.header_ = std::move(fields);
      have_header = true;
      header_line = line_number;
      continue;
    }
    if (fields.size() != t.header_.size()) {
      const std::string which = fields.size() < t.header_.size()
                                    ? "; field '" + t.header_[fields.size()] + "' is missing"
                                    : "; extra field " + Quoted(fields[t.header_.size()]) +
                                          " after '" + t.header_.back() + "'";
      return DataLossError(where + ": " + std::to_string(fields.size()) + " fields, expected " +
                           std::to_string(t.header_.size()) + " (header on line " +
                           std::to_string(header_line) + ")" + which);
    }
    t.rows_.push_back(std::move(fields));
    t.lines_.push_back(line_number);
  }
  if (!have_header) {
    return DataLossError(file + ": no header line (expected " + Joined(schema.required) + ")");
  }
  return t;
}

std::string CsvTable::Source(size_t row) const { return file_ + ":" + std::to_string(lines_[row]); }

int CsvTable::Column(std::string_view name) const {
  for (size_t k = 0; k < header_.size(); ++k) {
    if (header_[k] == name) return static_cast<int>(k);
  }
  return -1;
}

const std::string& CsvTable::Text(size_t row, std::string_view column) const {
  return rows_[row][static_cast<size_t>(Column(column))];
}

std::string CsvTable::Where(size_t row, std::string_view column) const {
  return Source(row) + ": field '" + std::string(column) + "'";
}

Status CsvTable::Double(size_t row, std::string_view column, double* value) const {
  const std::string& text = Text(row, column);
  if (text.empty()) return DataLossError(Where(row, column) + ": empty");
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) {
    return DataLossError(Where(row, column) + ": " + Quoted(text) + " is not a number");
  }
  if (!std::isfinite(v)) {
    return DataLossError(Where(row, column) + ": " + Quoted(text) + " is not finite");
  }
  *value = v;
  return OkStatus();
}

Status CsvTable::Int64(size_t row, std::string_view column, int64_t* value) const {
  const std::string& text = Text(row, column);
  if (text.empty()) return DataLossError(Where(row, column) + ": empty");
  size_t k = (text[0] == '-' || text[0] == '+') ? 1 : 0;
  if (k == text.size()) {
    return DataLossError(Where(row, column) + ": " + Quoted(text) + " is not an integer");
  }
  for (size_t j = k; j < text.size(); ++j) {
    if (text[j] < '0' || text[j] > '9') {
      return DataLossError(Where(row, column) + ": " + Quoted(text) +
                           " is not an integer (digits only)");
    }
  }
  errno = 0;
  const long long v = std::strtoll(text.c_str(), nullptr, 10);
  if (errno == ERANGE) {
    return DataLossError(Where(row, column) + ": " + Quoted(text) + " is out of the int64 range");
  }
  *value = v;
  return OkStatus();
}

Status CsvTable::Stamp(size_t row, std::string_view column, Timestamp* stamp) const {
  int64_t ns = 0;
  SLAM_MMS_RETURN_IF_ERROR(Int64(row, column, &ns));
  *stamp = Timestamp::FromNanoseconds(ns);
  return OkStatus();
}

Status CsvTable::IncreasingStamps(std::string_view column, std::vector<Timestamp>* stamps) const {
  stamps->clear();
  stamps->reserve(rows_.size());
  for (size_t r = 0; r < rows_.size(); ++r) {
    Timestamp t;
    SLAM_MMS_RETURN_IF_ERROR(Stamp(r, column, &t));
    if (r > 0 && t <= stamps->back()) {
      return DataLossError(Where(r, column) + ": " + std::to_string(t.nanoseconds()) +
                           (t == stamps->back() ? " duplicated" : " goes backwards") + " (line " +
                           std::to_string(lines_[r - 1]) + " has " +
                           std::to_string(stamps->back().nanoseconds()) +
                           "); stamps must strictly increase");
    }
    stamps->push_back(t);
  }
  return OkStatus();
}

std::string CsvLine(const std::vector<std::string>& fields) {
  std::string s;
  for (size_t k = 0; k < fields.size(); ++k) {
    if (k > 0) s += ',';
    s += fields[k];
  }
  s += '\n';
  return s;
}

}  // namespace slam_mms::io_internal
