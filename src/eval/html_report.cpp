#include "slam_mms/eval/html_report.hpp"

#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <system_error>

namespace slam_mms::eval {
namespace {

// Inline style: readable without any asset; prints well.
constexpr const char* kCss = R"css(
body{font-family:-apple-system,"Segoe UI",Helvetica,Arial,sans-serif;margin:0 auto;max-width:1450px;
padding:0 18px 40px;color:#222;line-height:1.4}
h1{font-size:1.6em;margin:18px 0 2px}h2{font-size:1.25em;margin:28px 0 8px;border-bottom:1px solid #ccc}
p.sub{color:#666;margin:0 0 10px}
table{border-collapse:collapse;margin:6px 0}th,td{border:1px solid #ccc;padding:4px 9px;text-align:left}
th{background:#f0f0f0}table.metrics td{text-align:right;font-variant-numeric:tabular-nums}
table.metrics td:first-child{text-align:left;font-weight:600}
table.kv th{width:16em}
.warn{background:#fff4e0;border-left:5px solid #e69f00;padding:6px 12px}
.ok{background:#eaf6ee;border-left:5px solid #009e73;padding:6px 12px}
figure{margin:14px 0}figure img{max-width:100%;height:auto;border:1px solid #ddd}
figcaption{color:#444;font-size:.95em;margin-top:4px}code{font-size:.95em}
)css";

void KeyValueTable(std::ostringstream& out,
                   const std::vector<std::pair<std::string, std::string>>& rows) {
  out << "<table class=\"kv\">\n";
  for (const auto& [k, v] : rows) {
    out << "<tr><th>" << HtmlEscape(k) << "</th><td>" << HtmlEscape(v) << "</td></tr>\n";
  }
  out << "</table>\n";
}

// The MIME type from the file's first bytes (PNG, JPEG), empty when neither.
std::string ImageMime(const std::string& bytes) {
  static const unsigned char kPng[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (bytes.size() >= 8 && std::memcmp(bytes.data(), kPng, 8) == 0) return "image/png";
  if (bytes.size() >= 3 && static_cast<unsigned char>(bytes[0]) == 0xFF &&
      static_cast<unsigned char>(bytes[1]) == 0xD8 &&
      static_cast<unsigned char>(bytes[2]) == 0xFF) {
    return "image/jpeg";
  }
  return "";
}

}  // namespace

std::string HtmlEscape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default: out += c;
    }
  }
  return out;
}

// No library the project links offers base64 publicly (OpenCV's is internal to its persistence
// code; nlohmann-json, PROJ and GeographicLib have none), and it is a few lines.
std::string Base64Encode(std::string_view bytes) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = (static_cast<uint8_t>(bytes[i]) << 16) |
                       (static_cast<uint8_t>(bytes[i + 1]) << 8) |
                       static_cast<uint8_t>(bytes[i + 2]);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += kAlphabet[(v >> 6) & 63];
    out += kAlphabet[v & 63];
  }
  if (i < bytes.size()) {
    const bool two = i + 1 < bytes.size();
    const uint32_t v = (static_cast<uint8_t>(bytes[i]) << 16) |
                       (two ? static_cast<uint8_t>(bytes[i + 1]) << 8 : 0);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += two ? kAlphabet[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

Status WriteHtmlReport(const HtmlReport& report, const std::filesystem::path& html_file) {
  // The images first: a missing one fails before anything is written.
  std::vector<std::string> data_uris;
  for (const HtmlImage& image : report.images) {
    std::ifstream in(image.file, std::ios::binary);
    if (!in) {
      return InvalidArgumentError("report.html: image " + image.file.string() +
                                  " does not exist or cannot be read");
    }
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const std::string mime = ImageMime(bytes);
    if (mime.empty()) {
      return InvalidArgumentError("report.html: image " + image.file.string() +
                                  " is neither a PNG nor a JPEG (" + std::to_string(bytes.size()) +
                                  " bytes)");
    }
    data_uris.push_back("data:" + mime + ";base64," + Base64Encode(bytes));
  }

  std::ostringstream out;
  out << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      << "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
      << "<title>" << HtmlEscape(report.title) << "</title>\n<style>" << kCss << "</style>\n"
      << "</head>\n<body>\n";
  out << "<h1>" << HtmlEscape(report.title) << "</h1>\n";
  if (!report.subtitle.empty())
    out << "<p class=\"sub\">" << HtmlEscape(report.subtitle) << "</p>\n";

  if (!report.summary.empty()) {
    out << "<h2>Run summary</h2>\n";
    KeyValueTable(out, report.summary);
  }
  out << "<h2>Warnings</h2>\n";
  if (report.warnings.empty()) {
    out << "<p class=\"ok\">No warnings.</p>\n";
  } else {
    out << "<div class=\"warn\"><ul>\n";
    for (const std::string& w : report.warnings) out << "<li>" << HtmlEscape(w) << "</li>\n";
    out << "</ul></div>\n";
  }
  if (!report.metrics.header.empty() || !report.metrics.rows.empty()) {
    out << "<h2>Metrics per method</h2>\n<table class=\"metrics\">\n";
    if (!report.metrics.header.empty()) {
      out << "<tr>";
      for (const std::string& h : report.metrics.header) out << "<th>" << HtmlEscape(h) << "</th>";
      out << "</tr>\n";
    }
    for (const std::vector<std::string>& row : report.metrics.rows) {
      out << "<tr>";
      for (const std::string& cell : row) out << "<td>" << HtmlEscape(cell) << "</td>";
      out << "</tr>\n";
    }
    out << "</table>\n";
    if (!report.metrics.note.empty()) out << "<p>" << HtmlEscape(report.metrics.note) << "</p>\n";
  }
  if (!report.images.empty()) {
    out << "<h2>Plots</h2>\n";
    for (size_t i = 0; i < report.images.size(); ++i) {
      const HtmlImage& image = report.images[i];
      const std::string name = image.file.filename().string();
      out << "<figure>\n<img src=\"" << data_uris[i] << "\" alt=\""
          << HtmlEscape(image.caption.empty() ? name : image.caption) << "\">\n<figcaption><code>"
          << HtmlEscape(name) << "</code>"
          << (image.caption.empty() ? "" : ": " + HtmlEscape(image.caption))
          << "</figcaption>\n</figure>\n";
    }
  }
  if (!report.georeference.empty() || !report.georeference_note.empty()) {
    out << "<h2>Georeference</h2>\n";
    if (!report.georeference.empty()) KeyValueTable(out, report.georeference);
    if (!report.georeference_note.empty()) {
      out << "<p>" << HtmlEscape(report.georeference_note) << "</p>\n";
    }
  }
  if (!report.files.empty()) {
    out << "<h2>Output files</h2>\n<table>\n<tr><th>file</th><th>content</th></tr>\n";
    for (const HtmlOutputFile& f : report.files) {
      out << "<tr><td><code>" << HtmlEscape(f.name) << "</code></td><td>"
          << HtmlEscape(f.description) << "</td></tr>\n";
    }
    out << "</table>\n";
  }
  out << "</body>\n</html>\n";

  // Written whole to a temporary file, then renamed: never a half report.
  std::filesystem::path tmp = html_file;
  tmp += ".tmp";
  {
    std::ofstream file(tmp, std::ios::binary | std::ios::trunc);
    if (!file) return NotFoundError("cannot write " + html_file.string());
    const std::string text = out.str();
    file.write(text.data(), static_cast<std::streamsize>(text.size()));
    if (!file) return NotFoundError("cannot write " + html_file.string() + " (disk full?)");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, html_file, ec);
  if (ec) {
    const std::string why = ec.message();
    std::filesystem::remove(tmp, ec);
    return NotFoundError("cannot write " + html_file.string() + ": " + why);
  }
  return OkStatus();
}

}  // namespace slam_mms::eval
