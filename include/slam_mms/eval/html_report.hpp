#pragma once
// report.html: one self-contained HTML page that a surveyor opens first. Inline CSS, no script, no
// network: the plots are embedded as base64 data URIs, so the file can be mailed or archived
// alone. Sections, each left out when empty: run summary, warnings, metrics table, plots,
// georeference, output files.
//
// The caller fills HtmlReport with plain text (every string is HTML-escaped here) and the paths of
// PNG/JPEG images; WriteHtmlReport reads each image and fails, naming the file, when one is
// missing or is not a PNG or JPEG.
//
// Thread safety: free functions; safe to call concurrently for distinct output files.

#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "slam_mms/core/status.hpp"

namespace slam_mms::eval {

struct HtmlTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;  ///< Each as many cells as the header (or fewer).
  std::string note;                            ///< A paragraph under the table (may be empty).
};

struct HtmlImage {
  std::string caption;
  std::filesystem::path file;  ///< A PNG or JPEG, embedded as a data URI.
};

struct HtmlOutputFile {
  std::string name;         ///< As listed (relative to the report's folder).
  std::string description;  ///< One line.
};

struct HtmlReport {
  std::string title = "slam_mms run report";
  std::string subtitle;  ///< E.g. the version and when the run ended.
  /// Run summary as key/value rows (input, duration, scans, ground truth, outages, complete...).
  std::vector<std::pair<std::string, std::string>> summary;
  std::vector<std::string> warnings;  ///< Shown prominently; none: "no warnings".
  HtmlTable metrics;
  std::vector<HtmlImage> images;
  /// Georeference as key/value rows (origin, CRS, vertical datum...); `georeference_note` under it.
  std::vector<std::pair<std::string, std::string>> georeference;
  std::string georeference_note;
  std::vector<HtmlOutputFile> files;
};

/// Writes `report` to `html_file`. InvalidArgument naming the image when one is missing,
/// unreadable or neither PNG nor JPEG; NotFound when the HTML file cannot be written. Nothing is
/// written on failure.
[[nodiscard]] Status WriteHtmlReport(const HtmlReport& report,
                                     const std::filesystem::path& html_file);

/// `text` with &, <, >, " and ' replaced by character references.
std::string HtmlEscape(std::string_view text);

/// Standard base64 (RFC 4648, with padding) of `bytes`.
std::string Base64Encode(std::string_view bytes);

}  // namespace slam_mms::eval
