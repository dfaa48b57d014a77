#include "slam_mms/eval/report.hpp"

#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>

#include "slam_mms/eval/json_writer.hpp"
#include "testing/test_data.hpp"

namespace slam_mms::eval {
namespace {

// A minimal strict JSON parser for checking the written documents (test oracle, not the writer).
struct Json {
  enum class Type { kNull, kBool, kNumber, kString, kArray, kObject } type = Type::kNull;
  bool b = false;
  double num = 0.0;
  std::string str;
  std::vector<Json> arr;
  std::vector<std::pair<std::string, Json>> obj;  // keeps order

  const Json* Get(const std::string& key) const {
    for (const auto& [k, v] : obj) {
      if (k == key) return &v;
    }
    return nullptr;
  }
  std::vector<std::string> Keys() const {
    std::vector<std::string> k;
    for (const auto& kv : obj) k.push_back(kv.first);
    return k;
  }
};

class Parser {
 public:
  explicit Parser(const std::string& s) : s_(s) {}
  bool Parse(Json* out) {
    if (!Value(out)) return false;
    Ws();
    return i_ == s_.size();
  }

 private:
  void Ws() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_]))) ++i_;
  }
  bool Lit(const char* lit) {
    const size_t n = std::strlen(lit);
    if (s_.compare(i_, n, lit) != 0) return false;
    i_ += n;
    return true;
  }
  bool String(std::string* out) {
    if (s_[i_] != '"') return false;
    ++i_;
    while (i_ < s_.size() && s_[i_] != '"') {
      if (s_[i_] == '\\') {
        ++i_;
        if (i_ >= s_.size()) return false;
        const char c = s_[i_];
        if (c == 'n')
          *out += '\n';
        else if (c == 't')
          *out += '\t';
        else if (c == 'u') {
          *out += static_cast<char>(std::stoi(s_.substr(i_ + 1, 4), nullptr, 16));
          i_ += 4;
        } else
          *out += c;
        ++i_;
      } else {
        if (static_cast<unsigned char>(s_[i_]) < 0x20) return false;
        *out += s_[i_++];
      }
    }
    if (i_ >= s_.size()) return false;
    ++i_;
    return true;
  }
  bool Value(Json* v) {
    Ws();
    if (i_ >= s_.size()) return false;
    const char c = s_[i_];
    if (c == '{') {
      v->type = Json::Type::kObject;
      ++i_;
      Ws();
      if (s_[i_] == '}') return ++i_, true;
      while (true) {
        Ws();
        std::string key;
        if (!String(&key)) return false;
        Ws();
        if (s_[i_++] != ':') return false;
        Json child;
        if (!Value(&child)) return false;
        v->obj.emplace_back(key, std::move(child));
        Ws();
        if (s_[i_] == ',') {
          ++i_;
          continue;
        }
        if (s_[i_] == '}') return ++i_, true;
        return false;
      }
    }
    if (c == '[') {
      v->type = Json::Type::kArray;
      ++i_;
      Ws();
      if (s_[i_] == ']') return ++i_, true;
      while (true) {
        Json child;
        if (!Value(&child)) return false;
        v->arr.push_back(std::move(child));
        Ws();
        if (s_[i_] == ',') {
          ++i_;
          continue;
        }
        if (s_[i_] == ']') return ++i_, true;
        return false;
      }
    }
    if (c == '"') {
      v->type = Json::Type::kString;
      return String(&v->str);
    }
    if (Lit("null")) return v->type = Json::Type::kNull, true;
    if (Lit("true")) return v->type = Json::Type::kBool, v->b = true, true;
    if (Lit("false")) return v->type = Json::Type::kBool, v->b = false, true;
    size_t used = 0;
    try {
      v->num = std::stod(s_.substr(i_), &used);
    } catch (...) {
      return false;
    }
    if (used == 0 || s_[i_] == '+' || s_[i_] == '.') return false;
    v->type = Json::Type::kNumber;
    i_ += used;
    return true;
  }
  const std::string& s_;
  size_t i_ = 0;
};

Json ParseOrFail(const std::string& text) {
  Json j;
  Parser p(text);
  EXPECT_TRUE(p.Parse(&j)) << "not valid JSON:\n" << text;
  return j;
}

EvalReport SampleReport() {
  EvalReport r;
  r.input.drive = "2011_09_26_drive_0013_sync";
  r.input.scans = 144;
  r.input.duration_s = 14.3;
  r.input.ground_truth = "oxts";
  r.gnss_outages = {{10.0, 5.0}, {30.0, 20.0}};
  MethodReport full;
  full.ate_rmse_m = 0.42;
  full.ate_rmse_xyz_m = Eigen::Vector3d(0.2, 0.3, 0.1);
  full.rot_rmse_deg = 0.5;
  full.rot_rmse_rpy_deg = Eigen::Vector3d(0.1, 0.2, 0.4);
  full.t_rel_pct = 1.25;
  full.r_rel_deg_per_100m = 0.3;
  full.max_pos_err_in_outage_m = 1.1;
  full.max_rot_err_in_outage_deg = 0.9;
  full.mme = -1.2;
  full.scans_per_s = 17.5;
  full.peak_rss_mb = 812.0;
  r.methods.emplace_back("full", full);
  MethodReport lidar;  // everything null except a few
  lidar.ate_rmse_m = 3.0;
  lidar.mme = std::nan("");  // NaN -> null
  r.methods.emplace_back("lidar_only", lidar);
  return r;
}

TEST(ReportTest, JsonHasExactlyTheSchemaKeys) {
  const StatusOr<std::string> text = ReportToJson(SampleReport());
  ASSERT_TRUE(text.ok()) << text.status().ToString();
  const Json j = ParseOrFail(*text);
  ASSERT_EQ(j.type, Json::Type::kObject);
  EXPECT_EQ(j.Keys(),
            (std::vector<std::string>{"input", "gnss_outages", "methods", "ground_truth_map"}));
  const Json* input = j.Get("input");
  ASSERT_NE(input, nullptr);
  EXPECT_EQ(input->Keys(),
            (std::vector<std::string>{"drive", "scans", "duration_s", "ground_truth"}));
  EXPECT_EQ(input->Get("drive")->str, "2011_09_26_drive_0013_sync");
  EXPECT_EQ(input->Get("scans")->num, 144.0);
  EXPECT_EQ(input->Get("ground_truth")->str, "oxts");

  const Json* outages = j.Get("gnss_outages");
  ASSERT_EQ(outages->arr.size(), 2u);
  EXPECT_EQ(outages->arr[1].arr.size(), 2u);
  EXPECT_EQ(outages->arr[1].arr[0].num, 30.0);
  EXPECT_EQ(outages->arr[1].arr[1].num, 20.0);

  const std::vector<std::string> method_keys = {"ate_rmse_m",
                                                "ate_rmse_xyz_m",
                                                "rot_rmse_deg",
                                                "rot_rmse_rpy_deg",
                                                "t_rel_pct",
                                                "r_rel_deg_per_100m",
                                                "max_pos_err_in_outage_m",
                                                "max_rot_err_in_outage_deg",
                                                "mme",
                                                "scans_per_s",
                                                "peak_rss_mb"};
  const Json* methods = j.Get("methods");
  EXPECT_EQ(methods->Keys(), (std::vector<std::string>{"full", "lidar_only"}));
  const Json* full = methods->Get("full");
  EXPECT_EQ(full->Keys(), method_keys);
  EXPECT_EQ(full->Get("ate_rmse_m")->num, 0.42);
  ASSERT_EQ(full->Get("rot_rmse_rpy_deg")->arr.size(), 3u);
  EXPECT_EQ(full->Get("rot_rmse_rpy_deg")->arr[2].num, 0.4);
  EXPECT_EQ(full->Get("peak_rss_mb")->num, 812.0);
  const Json* lidar = methods->Get("lidar_only");
  EXPECT_EQ(lidar->Keys(), method_keys);
  EXPECT_EQ(lidar->Get("ate_rmse_m")->num, 3.0);
  EXPECT_EQ(lidar->Get("ate_rmse_xyz_m")->type, Json::Type::kNull);
  EXPECT_EQ(lidar->Get("t_rel_pct")->type, Json::Type::kNull);
  EXPECT_EQ(lidar->Get("mme")->type, Json::Type::kNull);

  const Json* gt_map = j.Get("ground_truth_map");
  EXPECT_EQ(gt_map->Keys(), (std::vector<std::string>{"mme"}));
  EXPECT_EQ(gt_map->Get("mme")->type, Json::Type::kNull);
}

TEST(ReportTest, WritesFileAndValidatesNames) {
  const std::filesystem::path dir = slam_mms::testing::MakeTempDir("eval_report");
  const std::filesystem::path file = dir / "report.json";
  ASSERT_TRUE(WriteReportJson(SampleReport(), file).ok());
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  const Json j = ParseOrFail(ss.str());
  EXPECT_NE(j.Get("methods"), nullptr);

  EvalReport bad = SampleReport();
  bad.input.ground_truth = "gps";
  EXPECT_EQ(ReportToJson(bad).status().code(), StatusCode::kInvalidArgument);
  bad = SampleReport();
  bad.methods.emplace_back("suma", MethodReport());
  EXPECT_NE(ReportToJson(bad).status().message().find("suma"), std::string::npos);
  bad = SampleReport();
  bad.methods.emplace_back("full", MethodReport());
  EXPECT_FALSE(ReportToJson(bad).ok());
  EXPECT_FALSE(WriteReportJson(SampleReport(), dir / "no_such_dir" / "r.json").ok());
  std::filesystem::remove_all(dir);
}

TEST(ReportTest, MakeMethodReportFromResults) {
  AteResult ate;
  ate.ate_rmse_m = 1.5;
  ate.ate_rmse_xyz_m = Eigen::Vector3d(1, 1, 0.5);
  ate.rot_rmse_deg = 0.2;
  RelativeErrorResult rel;  // no segment: stays null
  rel.num_segments = 0;
  rel.t_rel_pct = std::nan("");
  OutageErrorResult out;
  out.num_poses = 3;
  out.max_pos_err_m = 2.5;
  out.max_rot_err_deg = 0.7;
  MapEntropyResult mme;
  mme.mean_map_entropy = -1.1;
  const MethodReport m = MakeMethodReport(&ate, &rel, &out, &mme);
  EXPECT_EQ(*m.ate_rmse_m, 1.5);
  EXPECT_EQ(m.ate_rmse_xyz_m->z(), 0.5);
  EXPECT_FALSE(m.t_rel_pct.has_value());
  EXPECT_EQ(*m.max_pos_err_in_outage_m, 2.5);
  EXPECT_EQ(*m.mme, -1.1);
  EXPECT_FALSE(m.scans_per_s.has_value());
  const MethodReport empty = MakeMethodReport(nullptr, nullptr, nullptr, nullptr);
  EXPECT_FALSE(empty.ate_rmse_m.has_value());
  EXPECT_TRUE(PeakRssMb().has_value());
  EXPECT_GT(*PeakRssMb(), 0.0);
}

TEST(JsonWriterTest, EscapesNestsAndRejectsMisuse) {
  JsonWriter w;
  w.BeginObject()
      .Key("s")
      .String("a\"b\\c\n\x01")
      .Key("n")
      .Number(0.1)
      .Key("inf")
      .Number(std::numeric_limits<double>::infinity())
      .Key("i")
      .Int(-7)
      .Key("b")
      .Bool(true)
      .Key("nested")
      .BeginArray()
      .BeginObject()
      .Key("x")
      .Number(1e-300)
      .EndObject()
      .BeginArray()
      .EndArray()
      .EndArray()
      .Key("empty")
      .BeginObject()
      .EndObject()
      .EndObject();
  const StatusOr<std::string> text = w.Finish();
  ASSERT_TRUE(text.ok()) << text.status().ToString();
  const Json j = ParseOrFail(*text);
  EXPECT_EQ(j.Get("s")->str, std::string("a\"b\\c\n\x01"));
  EXPECT_EQ(j.Get("n")->num, 0.1);  // shortest round-trip text
  EXPECT_EQ(j.Get("inf")->type, Json::Type::kNull);
  EXPECT_EQ(j.Get("i")->num, -7.0);
  EXPECT_EQ(j.Get("nested")->arr[0].Get("x")->num, 1e-300);
  EXPECT_EQ(j.Get("empty")->type, Json::Type::kObject);

  JsonWriter bad1;
  bad1.BeginObject().Number(1.0).EndObject();  // value without key
  EXPECT_EQ(bad1.Finish().status().code(), StatusCode::kFailedPrecondition);
  JsonWriter bad2;
  bad2.BeginArray();
  EXPECT_FALSE(bad2.Finish().ok());
  JsonWriter bad3;
  bad3.BeginArray().Key("k");
  EXPECT_FALSE(bad3.Finish().ok());
  JsonWriter bad4;
  EXPECT_FALSE(bad4.Finish().ok());
}

}  // namespace
}  // namespace slam_mms::eval
