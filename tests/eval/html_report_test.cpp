#include "slam_mms/eval/html_report.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <regex>

#include "testing/test_data.hpp"

namespace slam_mms::eval {
namespace {

std::string ReadAll(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// A plain decoder written independently of the encoder; empty on a bad character or length.
std::string Base64Decode(const std::string& s) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  if (s.size() % 4 != 0) return "";
  std::string out;
  for (size_t i = 0; i < s.size(); i += 4) {
    int v[4];
    int pad = 0;
    for (int k = 0; k < 4; ++k) {
      if (s[i + k] == '=' && i + 4 == s.size() && k >= 2) {
        v[k] = 0;
        ++pad;
      } else if ((v[k] = value(s[i + k])) < 0) {
        return "";
      }
    }
    const uint32_t x = (v[0] << 18) | (v[1] << 12) | (v[2] << 6) | v[3];
    out += static_cast<char>((x >> 16) & 0xFF);
    if (pad < 2) out += static_cast<char>((x >> 8) & 0xFF);
    if (pad < 1) out += static_cast<char>(x & 0xFF);
  }
  return out;
}

size_t Count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

TEST(HtmlReportTest, Base64MatchesRfc4648) {
  EXPECT_EQ(Base64Encode(""), "");
  EXPECT_EQ(Base64Encode("f"), "Zg==");
  EXPECT_EQ(Base64Encode("fo"), "Zm8=");
  EXPECT_EQ(Base64Encode("foo"), "Zm9v");
  EXPECT_EQ(Base64Encode("foob"), "Zm9vYg==");
  EXPECT_EQ(Base64Encode("fooba"), "Zm9vYmE=");
  EXPECT_EQ(Base64Encode("foobar"), "Zm9vYmFy");
  std::string all;
  for (int i = 0; i < 256; ++i) all += static_cast<char>(i);
  EXPECT_EQ(Base64Decode(Base64Encode(all)), all);
}

TEST(HtmlReportTest, EscapesText) {
  EXPECT_EQ(HtmlEscape("a<b>&\"c'"), "a&lt;b&gt;&amp;&quot;c&#39;");
  EXPECT_EQ(HtmlEscape("plain 1.5 m"), "plain 1.5 m");
}

TEST(HtmlReportTest, SelfContainedPageEmbedsTheImagesAndEscapesAllText) {
  const std::filesystem::path dir = slam_mms::testing::MakeTempDir("html_report");
  cv::Mat a(40, 60, CV_8UC3, cv::Scalar(10, 200, 30)), b(20, 30, CV_8UC3, cv::Scalar(0, 0, 255));
  ASSERT_TRUE(cv::imwrite((dir / "a.png").string(), a));
  ASSERT_TRUE(cv::imwrite((dir / "b.png").string(), b));

  HtmlReport r;
  r.title = "run <demo> & co";
  r.subtitle = "slam_mms 1.0";
  r.summary = {{"input", "/data/drive_<1>"}, {"complete", "yes"}};
  r.warnings = {"scan 7 skipped: \"truncated\" <bad>"};
  r.metrics.header = {"method", "ATE [m]"};
  r.metrics.rows = {{"full", "0.123"}, {"lidar_only<script>", "4.5"}};
  r.metrics.note = "ATE without alignment";
  r.images = {{"trajectories", dir / "a.png"}, {"errors & more", dir / "b.png"}};
  r.georeference = {{"origin", "48.1 N, 11.5 E, 520 m"}, {"CRS", "EPSG:25832"}};
  r.files = {{"full.tum", "trajectory, TUM"}, {"report.json", "all metrics"}};
  const std::filesystem::path html = dir / "report.html";
  ASSERT_TRUE(WriteHtmlReport(r, html).ok());
  const std::string text = ReadAll(html);

  // Escaped: none of the caller's markup survives.
  EXPECT_EQ(text.find("<demo>"), std::string::npos);
  EXPECT_EQ(text.find("<bad>"), std::string::npos);
  EXPECT_EQ(text.find("<script"), std::string::npos);
  EXPECT_NE(text.find("run &lt;demo&gt; &amp; co"), std::string::npos);
  EXPECT_NE(text.find("lidar_only&lt;script&gt;"), std::string::npos);
  EXPECT_NE(text.find("&quot;truncated&quot;"), std::string::npos);
  EXPECT_NE(text.find("EPSG:25832"), std::string::npos);
  EXPECT_NE(text.find("report.json"), std::string::npos);
  // No network: nothing is fetched.
  EXPECT_EQ(text.find("http:"), std::string::npos);
  EXPECT_EQ(text.find("https:"), std::string::npos);
  EXPECT_EQ(text.find("<link"), std::string::npos);

  // Balanced tags for every element the page uses.
  for (const char* tag : {"html", "head", "body", "title", "style", "h1", "h2", "p", "table", "tr",
                          "th", "td", "ul", "li", "div", "figure", "figcaption", "code"}) {
    const std::string open = std::string("<") + tag;
    size_t opens = 0;
    for (size_t at = text.find(open); at != std::string::npos; at = text.find(open, at + 1)) {
      const char next = text[at + open.size()];
      if (next == '>' || next == ' ') ++opens;
    }
    EXPECT_EQ(opens, Count(text, std::string("</") + tag + ">")) << tag;
    EXPECT_GT(opens, 0u) << tag;
  }

  // Every <img> is a data URI of one of the PNGs, byte for byte, in the given order.
  const std::regex img_re("<img src=\"data:image/png;base64,([A-Za-z0-9+/=]+)\"");
  std::vector<std::string> decoded;
  for (auto it = std::sregex_iterator(text.begin(), text.end(), img_re);
       it != std::sregex_iterator(); ++it) {
    decoded.push_back(Base64Decode((*it)[1].str()));
  }
  EXPECT_EQ(Count(text, "<img "), 2u);
  ASSERT_EQ(decoded.size(), 2u);
  const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  for (const std::string& d : decoded) {
    ASSERT_GE(d.size(), 8u);
    EXPECT_EQ(std::memcmp(d.data(), sig, 8), 0);
  }
  EXPECT_EQ(decoded[0], ReadAll(dir / "a.png"));
  EXPECT_EQ(decoded[1], ReadAll(dir / "b.png"));
  std::filesystem::remove_all(dir);
}

TEST(HtmlReportTest, MissingOrNonImageFilesFailNamingTheFile) {
  const std::filesystem::path dir = slam_mms::testing::MakeTempDir("html_report_bad");
  HtmlReport r;
  r.images = {{"gone", dir / "missing_plot.png"}};
  const std::filesystem::path html = dir / "report.html";
  Status s = WriteHtmlReport(r, html);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("missing_plot.png"), std::string::npos) << s.ToString();
  EXPECT_FALSE(std::filesystem::exists(html));
  std::ofstream(dir / "notes.png") << "not an image";
  r.images = {{"text", dir / "notes.png"}};
  s = WriteHtmlReport(r, html);
  EXPECT_NE(s.message().find("notes.png"), std::string::npos) << s.ToString();
  EXPECT_FALSE(std::filesystem::exists(html));
  // An unwritable destination.
  r.images.clear();
  EXPECT_EQ(WriteHtmlReport(r, dir / "no_such_folder" / "report.html").code(),
            StatusCode::kNotFound);
  // Without images or tables the page is still valid and says there is no warning.
  ASSERT_TRUE(WriteHtmlReport(HtmlReport(), html).ok());
  const std::string text = ReadAll(html);
  EXPECT_NE(text.find("No warnings."), std::string::npos);
  EXPECT_EQ(text.find("<img"), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace slam_mms::eval
