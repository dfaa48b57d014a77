#include "slam_mms/eval/report.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "slam_mms/version.hpp"
#include "testing/test_data.hpp"

namespace slam_mms::eval {
namespace {

using Json = nlohmann::ordered_json;

std::vector<std::string> Keys(const Json& j) {
  std::vector<std::string> k;
  for (auto it = j.begin(); it != j.end(); ++it) k.push_back(it.key());
  return k;
}

Json ParseOrFail(const std::string& text) {
  Json j = Json::parse(text, nullptr, false);
  EXPECT_FALSE(j.is_discarded()) << "not valid JSON:\n" << text;
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
  full.rot_mean_rpy_deg = Eigen::Vector3d(-0.05, 0.1, -0.3);
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
  r.input.kind = "kitti_raw";
  r.input.scans_total = 150;
  r.input.imu_noise = "/drives/0013/imu_noise.yaml";
  r.input.oxts_inertial_delay_s = 0.055;
  r.input.skipped_scans = {{"velodyne_points/data/0000000005.bin", "truncated: 1000 bytes"},
                           {"velodyne_points/data/0000000009.bin", "quote \" and \\ and \n"}};
  r.command_line = {"slam_mms_run", "--out=o", "--config", "a b.yaml"};
  r.options_json = R"({"localizer": {"submap_duration_s": 2.5, "icp": {"max_iterations": 30}},
                       "origin_height_m": null})";
  r.georef_json = R"({"crs": "EPSG:32632", "origin": [49.0, 8.4, 110.0]})";
  r.complete = false;
  r.warnings = {"--gnss-outage 300:30 starts after the drive's last scan (190.0 s)", "SIGINT"};
  r.outputs = {"full.tum", "map_full.las"};
  return r;
}

TEST(ReportTest, JsonHasTheSchemaKeysAndRoundTrips) {
  const EvalReport r = SampleReport();
  const StatusOr<std::string> text = ReportToJson(r);
  ASSERT_TRUE(text.ok()) << text.status().ToString();
  const Json j = ParseOrFail(*text);
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(Keys(j),
            (std::vector<std::string>{"version", "complete", "command_line", "input",
                                      "gnss_outages", "methods", "ground_truth_map", "options",
                                      "georef", "extrinsics", "warnings", "outputs"}));
  EXPECT_EQ(j["version"], SLAM_MMS_VERSION_STRING);
  EXPECT_EQ(j["warnings"].get<std::vector<std::string>>(), r.warnings);
  EXPECT_EQ(j["complete"], false);
  EXPECT_EQ(j["command_line"].get<std::vector<std::string>>(), r.command_line);
  const Json& input = j["input"];
  EXPECT_EQ(Keys(input),
            (std::vector<std::string>{"drive", "kind", "scans", "scans_total", "scans_processed",
                                      "duration_s", "ground_truth", "skipped_scans", "imu_noise",
                                      "oxts_inertial_delay_s"}));
  EXPECT_EQ(input["drive"], "2011_09_26_drive_0013_sync");
  EXPECT_EQ(input["kind"], "kitti_raw");
  EXPECT_EQ(input["scans"], 144);
  EXPECT_EQ(input["scans_processed"], 144);
  EXPECT_EQ(input["scans_total"], 150);
  EXPECT_EQ(input["duration_s"].get<double>(), 14.3);
  EXPECT_EQ(input["ground_truth"], "oxts");
  ASSERT_EQ(input["skipped_scans"]["count"], 2);
  ASSERT_EQ(input["skipped_scans"]["scans"].size(), 2u);
  EXPECT_EQ(input["skipped_scans"]["scans"][0]["source"], r.input.skipped_scans[0].source);
  EXPECT_EQ(input["skipped_scans"]["scans"][1]["reason"], r.input.skipped_scans[1].reason);
  EXPECT_EQ(input["imu_noise"], r.input.imu_noise);
  EXPECT_EQ(input["oxts_inertial_delay_s"].get<double>(), 0.055);

  const Json& outages = j["gnss_outages"];
  ASSERT_EQ(outages.size(), 2u);
  EXPECT_EQ(outages[1].size(), 2u);
  EXPECT_EQ(outages[1][0].get<double>(), 30.0);
  EXPECT_EQ(outages[1][1].get<double>(), 20.0);

  const std::vector<std::string> method_keys = {"ate_rmse_m",
                                                "ate_rmse_xyz_m",
                                                "rot_rmse_deg",
                                                "rot_rmse_rpy_deg",
                                                "rot_mean_rpy_deg",
                                                "t_rel_pct",
                                                "r_rel_deg_per_100m",
                                                "max_pos_err_in_outage_m",
                                                "max_rot_err_in_outage_deg",
                                                "mme",
                                                "nees",
                                                "scans_per_s",
                                                "peak_rss_mb",
                                                "vs_oxts_velocity"};
  const Json& methods = j["methods"];
  EXPECT_EQ(Keys(methods), (std::vector<std::string>{"full", "lidar_only"}));
  const Json& full = methods["full"];
  EXPECT_EQ(Keys(full), method_keys);
  EXPECT_EQ(full["ate_rmse_m"].get<double>(), 0.42);
  ASSERT_EQ(full["rot_rmse_rpy_deg"].size(), 3u);
  EXPECT_EQ(full["rot_rmse_rpy_deg"][2].get<double>(), 0.4);
  ASSERT_EQ(full["rot_mean_rpy_deg"].size(), 3u);
  EXPECT_EQ(full["rot_mean_rpy_deg"][2].get<double>(), -0.3);  // signed
  EXPECT_EQ(full["peak_rss_mb"].get<double>(), 812.0);
  const Json& lidar = methods["lidar_only"];
  EXPECT_EQ(Keys(lidar), method_keys);
  EXPECT_EQ(lidar["ate_rmse_m"].get<double>(), 3.0);
  EXPECT_TRUE(lidar["ate_rmse_xyz_m"].is_null());
  EXPECT_TRUE(lidar["t_rel_pct"].is_null());
  EXPECT_TRUE(lidar["mme"].is_null());  // NaN -> null

  EXPECT_EQ(Keys(j["ground_truth_map"]), (std::vector<std::string>{"mme"}));
  EXPECT_TRUE(j["ground_truth_map"]["mme"].is_null());
  // The embedded texts, parsed: same tree.
  EXPECT_EQ(j["options"], Json::parse(r.options_json));
  EXPECT_EQ(j["options"]["localizer"]["icp"]["max_iterations"], 30);
  EXPECT_TRUE(j["options"]["origin_height_m"].is_null());
  EXPECT_EQ(j["georef"]["crs"], "EPSG:32632");
  EXPECT_EQ(j["outputs"]["files"].get<std::vector<std::string>>(), r.outputs);
}

TEST(ReportTest, DoublesReadBackExactlyAndDefaultsAreNull) {
  EvalReport r;
  r.input.ground_truth = "none";
  r.input.duration_s = 0.1 + 0.2;  // 0.30000000000000004
  MethodReport m;
  m.ate_rmse_m = 1.0 / 3.0;
  m.scans_per_s = 1e-300;
  m.peak_rss_mb = 123456789.123456789;
  r.methods.emplace_back("gnss_ins", m);
  const StatusOr<std::string> text = ReportToJson(r);
  ASSERT_TRUE(text.ok()) << text.status().ToString();
  const Json j = ParseOrFail(*text);
  EXPECT_EQ(j["input"]["duration_s"].get<double>(), 0.1 + 0.2);
  EXPECT_EQ(j["methods"]["gnss_ins"]["ate_rmse_m"].get<double>(), 1.0 / 3.0);
  EXPECT_EQ(j["methods"]["gnss_ins"]["scans_per_s"].get<double>(), 1e-300);
  EXPECT_EQ(j["methods"]["gnss_ins"]["peak_rss_mb"].get<double>(), 123456789.123456789);
  // Unset: null kind/total/options/georef, complete, no skipped scans, no "outputs" key.
  EXPECT_TRUE(j["input"]["kind"].is_null());
  EXPECT_TRUE(j["input"]["scans_total"].is_null());
  EXPECT_EQ(j["input"]["skipped_scans"]["count"], 0);
  EXPECT_TRUE(j["input"]["skipped_scans"]["scans"].empty());
  EXPECT_TRUE(j["input"]["imu_noise"].is_null());
  EXPECT_TRUE(j["input"]["oxts_inertial_delay_s"].is_null());
  EXPECT_TRUE(j["options"].is_null());
  EXPECT_TRUE(j["georef"].is_null());
  EXPECT_TRUE(j["extrinsics"].is_null());
  EXPECT_EQ(j["complete"], true);
  EXPECT_TRUE(j["command_line"].is_array());
  EXPECT_TRUE(j["warnings"].is_array() && j["warnings"].empty());
  EXPECT_FALSE(j.contains("outputs"));
}

TEST(ReportTest, WritesFileAndValidatesNames) {
  const std::filesystem::path dir = slam_mms::testing::MakeTempDir("eval_report");
  const std::filesystem::path file = dir / "report.json";
  ASSERT_TRUE(WriteReportJson(SampleReport(), file).ok());
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  const Json j = ParseOrFail(ss.str());
  EXPECT_TRUE(j.contains("methods"));
  EXPECT_EQ(ss.str(), *ReportToJson(SampleReport()));

  EvalReport bad = SampleReport();
  bad.input.ground_truth = "gps";
  EXPECT_EQ(ReportToJson(bad).status().code(), StatusCode::kInvalidArgument);
  bad = SampleReport();
  bad.input.kind = "pcap";
  EXPECT_NE(ReportToJson(bad).status().message().find("pcap"), std::string::npos);
  bad = SampleReport();
  bad.methods.emplace_back("suma", MethodReport());
  EXPECT_NE(ReportToJson(bad).status().message().find("suma"), std::string::npos);
  bad = SampleReport();
  bad.methods.emplace_back("full", MethodReport());
  EXPECT_FALSE(ReportToJson(bad).ok());
  // Embedded texts must be JSON objects.
  bad = SampleReport();
  bad.options_json = "{\"localizer\": ";
  StatusOr<std::string> t = ReportToJson(bad);
  ASSERT_FALSE(t.ok());
  EXPECT_EQ(t.status().code(), StatusCode::kInvalidArgument);
  EXPECT_NE(t.status().message().find("options_json"), std::string::npos);
  bad = SampleReport();
  bad.georef_json = "[1, 2]";
  t = ReportToJson(bad);
  ASSERT_FALSE(t.ok());
  EXPECT_NE(t.status().message().find("georef_json"), std::string::npos);
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

TEST(ReportTest, SecondReferenceIsWrittenUnderItsMethod) {
  AteResult ate;
  ate.ate_rmse_m = 0.25;
  ate.rot_rmse_deg = 0.5;
  RelativeErrorResult rel;
  rel.num_segments = 4;
  rel.t_rel_pct = 0.75;
  rel.r_rel_deg_per_100m = 1.25;
  OutageErrorResult out;  // no pose in an outage: null
  const ReferenceMetrics r = MakeReferenceMetrics(&ate, &rel, &out);
  EXPECT_EQ(*r.ate_rmse_m, 0.25);
  EXPECT_EQ(*r.r_rel_deg_per_100m, 1.25);
  EXPECT_FALSE(r.max_pos_err_in_outage_m.has_value());

  EvalReport report;
  report.input.ground_truth = "oxts";
  MethodReport full;
  full.ate_rmse_m = 0.5;
  full.vs_oxts_velocity = r;
  report.methods.emplace_back("full", full);
  report.methods.emplace_back("gnss_ins", MethodReport());
  const Json j = ParseOrFail(ReportToJson(report).value());
  const Json& v = j["methods"]["full"]["vs_oxts_velocity"];
  EXPECT_EQ(Keys(v), (std::vector<std::string>{"ate_rmse_m", "rot_rmse_deg", "t_rel_pct",
                                               "r_rel_deg_per_100m", "max_pos_err_in_outage_m"}));
  EXPECT_EQ(v["ate_rmse_m"].get<double>(), 0.25);
  EXPECT_EQ(v["rot_rmse_deg"].get<double>(), 0.5);
  EXPECT_EQ(v["t_rel_pct"].get<double>(), 0.75);
  EXPECT_TRUE(v["max_pos_err_in_outage_m"].is_null());
  EXPECT_EQ(j["methods"]["full"]["ate_rmse_m"].get<double>(), 0.5);  // the first reference's
  EXPECT_TRUE(j["methods"]["gnss_ins"]["vs_oxts_velocity"].is_null());
}

}  // namespace
}  // namespace slam_mms::eval
