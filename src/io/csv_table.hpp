#pragma once
// Private: the one CSV helper behind every CSV file of a drive folder (scans.csv, imu.csv,
// gnss.csv, initial_state.csv, pos.csv).
//
// Rules: comma-separated, no quoting (fields may not contain commas); spaces around a field are
// trimmed; blank lines and lines whose first non-space character is '#' are skipped; the first
// other line is the header, checked by name against a schema: the required columns in order, then
// any of the optional columns in their order (a column out of place or unknown is an error naming
// it). Every error names "<file>:<line>: field '<name>'".
//
// Thread safety: value type; const methods safe from any thread.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms::io_internal {

/// The columns a CSV file must (and may) have.
struct CsvSchema {
  std::vector<std::string> required;
  std::vector<std::string> optional;  ///< May follow the required ones, in this order.
};

class CsvTable {
 public:
  /// Parses `bytes`; `file` names the source in messages. kDataLoss for an empty file, a bad
  /// header or a row with the wrong number of fields.
  static StatusOr<CsvTable> Parse(std::string_view bytes, const std::string& file,
                                  const CsvSchema& schema);

  const std::string& file() const { return file_; }
  size_t num_rows() const { return rows_.size(); }
  /// 1-based line of row `row` in the file.
  int line(size_t row) const { return lines_[row]; }
  /// "file:line".
  std::string Source(size_t row) const;
  /// Index of column `name` in the header; -1 when absent (an optional column not given).
  int Column(std::string_view name) const;
  bool Has(std::string_view name) const { return Column(name) >= 0; }
  const std::vector<std::string>& header() const { return header_; }

  /// The trimmed text of a field (column must exist).
  const std::string& Text(size_t row, std::string_view column) const;
  /// "<file>:<line>: field '<column>'", for messages.
  std::string Where(size_t row, std::string_view column) const;

  /// The field as a finite double (strtod syntax); kDataLoss naming file, line, field otherwise.
  [[nodiscard]] Status Double(size_t row, std::string_view column, double* value) const;
  /// The field as a decimal int64 (optional sign, digits only).
  [[nodiscard]] Status Int64(size_t row, std::string_view column, int64_t* value) const;
  /// The field as a Timestamp in integer nanoseconds since the Unix epoch.
  [[nodiscard]] Status Stamp(size_t row, std::string_view column, Timestamp* stamp) const;

  /// Reads column `column` of every row as stamps and checks they strictly increase: an error
  /// names the row's line and the previous one ("goes backwards" / "duplicated").
  [[nodiscard]] Status IncreasingStamps(std::string_view column,
                                        std::vector<Timestamp>* stamps) const;

 private:
  std::string file_;
  std::vector<std::string> header_;
  std::vector<std::vector<std::string>> rows_;
  std::vector<int> lines_;
};

/// One CSV line of `fields` joined by commas, with '\n'.
std::string CsvLine(const std::vector<std::string>& fields);

}  // namespace slam_mms::io_internal
