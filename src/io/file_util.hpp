#pragma once
// Private helpers of the io module: whole-file reads, KITTI timestamp files, number tokens.

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "slam_mms/core/status.hpp"
#include "slam_mms/core/timestamp.hpp"

namespace slam_mms::io_internal {

/// The lines of a text file ('\n' separated, a trailing '\r' removed, no final empty line).
StatusOr<std::vector<std::string>> ReadLines(const std::filesystem::path& file);

/// ReadLines on bytes already in memory (the parsers' entry for fuzzing and tests).
std::vector<std::string> SplitLines(std::string_view bytes);

/// Whole file contents as bytes.
StatusOr<std::string> ReadFileBytes(const std::filesystem::path& file);

/// Writes `bytes` as the whole file (created or truncated); kUnavailable naming the file when it
/// cannot be created or written.
[[nodiscard]] Status WriteFileBytes(const std::filesystem::path& file, std::string_view bytes);

/// True when the line has only whitespace.
bool IsBlank(const std::string& line);

/// A KITTI timestamps file: one stamp per line. Blank lines are std::nullopt where
/// `allow_blank_lines` (extract layout: lost records), else kDataLoss. The non-blank stamps must be
/// strictly increasing (kDataLoss naming the file, both lines and stamps: "goes backwards" or
/// "duplicated").
StatusOr<std::vector<std::optional<Timestamp>>> ReadTimestampFile(const std::filesystem::path& file,
                                                                  bool allow_blank_lines);

/// ReadTimestampFile on the lines of a file already in memory; `file` only names it in errors.
StatusOr<std::vector<std::optional<Timestamp>>> ParseTimestampLines(
    const std::vector<std::string>& lines, const std::string& file, bool allow_blank_lines);

/// `dir` unchanged when it ends in a name; "a/drive/", "a/drive/." or "." made absolute and
/// normalised without a trailing separator, so that parent_path() is the enclosing folder.
std::filesystem::path DirPathWithName(const std::filesystem::path& dir);

/// Splits on whitespace.
std::vector<std::string> SplitWhitespace(const std::string& line);

/// Parses a whole token as a finite double; false otherwise.
bool ParseDouble(const std::string& token, double* value);

/// "%.17g".
std::string FormatDouble(double v);

}  // namespace slam_mms::io_internal
