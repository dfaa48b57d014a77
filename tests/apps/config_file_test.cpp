// slam_mms_run's YAML --config reader and --dump-config writer
// (examples/apps/slam_mms_run/config_file.cpp), registered in tests/CMakeLists.txt.
#include "slam_mms_run/config_file.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <sstream>

#include "testing/test_data.hpp"

namespace slam_mms::app {
namespace {

using Options = MappingSystem::Options;

Status Apply(const std::string& text, Options* o) { return ApplyConfigText(text, "my.yaml", o); }

// The message of a failing ApplyConfigText (empty where it did not fail).
std::string Error(const std::string& text) {
  Options o;
  const Status s = Apply(text, &o);
  EXPECT_FALSE(s.ok()) << "accepted:\n" << text;
  if (!s.ok()) {
    EXPECT_EQ(s.code(), StatusCode::kInvalidArgument) << s.ToString();
  }
  return s.ok() ? "" : s.message();
}

TEST(ConfigFileTest, NestedAndDottedKeys) {
  Options o;
  const Status s = Apply(
      "# a comment\n"
      "localizer:\n"
      "  submap_duration_s: 4.5   # trailing comment\n"
      "  icp: {max_iterations: 31}\n"
      "  surfels.max_distance_m: 90\n"
      "level2.use_loops: off\n"
      "ins.gnss.t_body_antenna: [0.1, -0.2, 0.75]\n"
      "ins:\n"
      "  gnss:\n"
      "    min_fix_type: rtk_float\n"
      "localizer.min_model_confidence: 0.3\n",
      &o);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(o.localizer.submap_duration_s, 4.5);
  EXPECT_EQ(o.localizer.icp.max_iterations, 31);
  EXPECT_EQ(o.localizer.surfels.max_distance_m, 90.0);
  EXPECT_FALSE(o.level2.use_loops);
  EXPECT_EQ(o.ins.gnss.t_body_antenna, Eigen::Vector3d(0.1, -0.2, 0.75));
  EXPECT_EQ(o.ins.gnss.min_fix_type, GnssFixType::kRtkFloat);
  EXPECT_EQ(o.localizer.min_model_confidence, 0.3f);
  // Untouched keys keep their defaults.
  EXPECT_EQ(o.level2.loop_distance_m, Options().level2.loop_distance_m);
  // An empty file (or only comments) changes nothing.
  Options e;
  ASSERT_TRUE(Apply("# nothing\n", &e).ok());
  EXPECT_EQ(OptionsToYaml(e), OptionsToYaml(Options()));
}

TEST(ConfigFileTest, ErrorsNameFileLineAndKey) {
  std::string m = Error("localizer:\n  submap_duration_s: 5\n  bogus_key: 3\n");
  EXPECT_NE(m.find("my.yaml:3: unknown key 'localizer.bogus_key'"), std::string::npos) << m;
  m = Error("level2.use_loops: maybe\n");
  EXPECT_NE(m.find("my.yaml:1: key 'level2.use_loops': bad value 'maybe' (expected bool)"),
            std::string::npos)
      << m;
  m = Error("\n\nlocalizer:\n  submap_duration_s: [1, 2]\n");
  EXPECT_NE(m.find("my.yaml:4: key 'localizer.submap_duration_s': expected double, got a list"),
            std::string::npos)
      << m;
  m = Error("level2:\n  max_iterations: {a: 1}\n");
  EXPECT_NE(m.find("my.yaml:2: key 'level2.max_iterations': expected int, got a mapping"),
            std::string::npos)
      << m;
  m = Error("level2:\n  max_iterations: 2.5\n");
  EXPECT_NE(m.find("my.yaml:2: key 'level2.max_iterations': bad value '2.5'"), std::string::npos)
      << m;
  // yaml-cpp's Load keeps the first document only: `{}` then a key is two documents.
  m = Error("{}\nlevel2.use_loops: false\n");
  EXPECT_NE(m.find("my.yaml:2: a second YAML document"), std::string::npos) << m;
  m = Error("level2.use_loops: false\n---\nlevel2.use_gnss: false\n");
  EXPECT_NE(m.find("my.yaml:3: a second YAML document"), std::string::npos) << m;
  m = Error("localizer: 3\n");
  EXPECT_NE(m.find("my.yaml:1: 'localizer' is a group of keys: expected a mapping"),
            std::string::npos)
      << m;
  m = Error("level2.use_gnss: true\nlevel2:\n  use_gnss: false\n");
  EXPECT_NE(m.find("my.yaml:3: key 'level2.use_gnss' given twice"), std::string::npos) << m;
  m = Error("num_threads: 2\nnum_threads: 3\n");
  EXPECT_NE(m.find("my.yaml:2: key 'num_threads' given twice"), std::string::npos) << m;
  m = Error("localizer:\n  icp: [1,\n  x: 2\n");
  EXPECT_NE(m.find("my.yaml:"), std::string::npos) << m;
  EXPECT_NE(m.find("not valid YAML"), std::string::npos) << m;
  m = Error("localizer.submap_duration_s = 2\n");  // the old key = value format
  EXPECT_NE(m.find("my.yaml:1: expected a mapping"), std::string::npos) << m;
  m = Error("ins.gnss.t_body_antenna: [1, 2]\n");
  EXPECT_NE(m.find("key 'ins.gnss.t_body_antenna': bad value '[1, 2]' (expected vector3)"),
            std::string::npos)
      << m;
  m = Error("ins.gnss.min_fix_type: rtk\n");
  EXPECT_NE(m.find("expected enum: none|single|differential|rtk_float|rtk_fixed"),
            std::string::npos)
      << m;
  m = Error("map_voxel_m:\n");
  EXPECT_NE(m.find("my.yaml:1: key 'map_voxel_m': expected double, got no value"),
            std::string::npos)
      << m;
  m = Error("origin_latitude_deg: 49\norigin_longitude_deg: 8.4\n");
  EXPECT_NE(m.find("must be given together"), std::string::npos) << m;
  // Options::Validate()'s message, after the file name.
  m = Error("num_threads: 0\n");
  EXPECT_EQ(m.rfind("my.yaml: ", 0), 0u) << m;
  EXPECT_NE(m.find("num_threads"), std::string::npos) << m;
}

TEST(ConfigFileTest, DumpReadDumpIsIdentical) {
  Options o;
  o.localizer.submap_duration_s = 0.1 + 0.2;  // needs 17 digits
  o.localizer.min_model_confidence = 0.3f;
  o.level2.use_loops = false;
  o.ins.gnss.t_body_antenna = Eigen::Vector3d(1.0 / 3.0, -0.5, 1e-7);
  o.ins.gnss.min_fix_type = GnssFixType::kRtkFixed;
  o.localizer.spill_dir = "/tmp/a \"quoted\" dir";
  o.origin = GeodeticPoint{49.011, 8.4235, 112.5};
  o.num_threads = 3;
  const std::string yaml = OptionsToYaml(o);
  // Every key is there, with a comment naming its type and default.
  for (const ConfigKeyInfo& k : ConfigKeys()) {
    const std::string leaf = k.key.substr(k.key.rfind('.') + 1);
    EXPECT_NE(yaml.find(leaf + ": "), std::string::npos) << k.key;
  }
  EXPECT_NE(yaml.find("  submap_duration_s: 0.30000000000000004  # double; default "),
            std::string::npos)
      << yaml;

  Options back;
  const Status s = Apply(yaml, &back);
  ASSERT_TRUE(s.ok()) << s.ToString() << "\n" << yaml;
  EXPECT_EQ(OptionsToYaml(back), yaml);
  EXPECT_EQ(OptionsToJson(back), OptionsToJson(o));
  EXPECT_EQ(back.localizer.submap_duration_s, o.localizer.submap_duration_s);
  EXPECT_EQ(back.localizer.min_model_confidence, 0.3f);
  EXPECT_FALSE(back.level2.use_loops);
  EXPECT_EQ(back.ins.gnss.t_body_antenna, o.ins.gnss.t_body_antenna);
  EXPECT_EQ(back.ins.gnss.min_fix_type, GnssFixType::kRtkFixed);
  EXPECT_EQ(back.localizer.spill_dir, o.localizer.spill_dir);
  ASSERT_TRUE(back.origin.has_value());
  EXPECT_EQ(back.origin->longitude_deg, 8.4235);
  EXPECT_EQ(back.num_threads, 3);

  // The defaults (unset origin, no spill folder: ~) round-trip too, also through a file.
  const std::filesystem::path dir = slam_mms::testing::MakeTempDir("config_file");
  const std::filesystem::path file = dir / "dump.yaml";
  Options d;
  ASSERT_TRUE(WriteConfigFile(Options(), file).ok());
  ASSERT_TRUE(ApplyConfigFile(file, &o).ok());  // onto the non-default options above
  EXPECT_FALSE(o.origin.has_value());
  EXPECT_TRUE(o.localizer.spill_dir.empty());
  EXPECT_EQ(OptionsToYaml(o), OptionsToYaml(d));
  EXPECT_FALSE(WriteConfigFile(d, dir / "no_such_dir" / "x.yaml").ok());
  const Status missing = ApplyConfigFile(dir / "none.yaml", &d);
  EXPECT_EQ(missing.code(), StatusCode::kNotFound);
  EXPECT_NE(missing.message().find("none.yaml"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(ConfigFileTest, JsonHasTheSameTree) {
  Options o;
  o.localizer.icp.max_iterations = 17;
  o.localizer.min_model_confidence = 0.3f;
  const nlohmann::json j = nlohmann::json::parse(OptionsToJson(o));
  ASSERT_TRUE(j.is_object());
  EXPECT_EQ(j["localizer"]["icp"]["max_iterations"], 17);
  EXPECT_EQ(j["level2"]["use_loops"], o.level2.use_loops);
  EXPECT_EQ(j["ins"]["gnss"]["t_body_antenna"].size(), 3u);
  EXPECT_TRUE(j["origin_latitude_deg"].is_null());
  EXPECT_EQ(j["localizer"]["renderer"], "auto");
  // A float option shows its shortest text (0.3, not 0.30000001192092896).
  EXPECT_EQ(j["localizer"]["min_model_confidence"].get<double>(), 0.3);
  // Every key appears once as a leaf.
  size_t leaves = 0;
  std::function<void(const nlohmann::json&)> count = [&](const nlohmann::json& n) {
    for (const auto& [k, v] : n.items()) {
      if (v.is_object()) {
        count(v);
      } else {
        ++leaves;
      }
    }
  };
  count(j);
  EXPECT_EQ(leaves, ConfigKeys().size());
}

// drive.* keys set the drive runner's options (RunConfig::drive); the keys moved from level2.
TEST(ConfigFileTest, DriveKeysAndMovedKeys) {
  RunConfig c;
  const Status s = ApplyConfigText(
      "drive:\n"
      "  estimate_extrinsics: true\n"
      "  extrinsic_calibration: {attitude_reference: travel_direction, max_scans: 50}\n"
      "level2.use_loops: off\n",
      "my.yaml", &c);
  ASSERT_TRUE(s.ok()) << s.ToString();
  EXPECT_TRUE(c.drive.estimate_extrinsics);
  EXPECT_EQ(c.drive.extrinsic_calibration.attitude_reference,
            ExtrinsicCalibrationOptions::AttitudeReference::kTravelDirection);
  EXPECT_EQ(c.drive.extrinsic_calibration.max_scans, 50);
  EXPECT_FALSE(c.system.level2.use_loops);
  // Dump, read, dump again: the same bytes, drive keys included.
  const std::string yaml = OptionsToYaml(c);
  EXPECT_NE(yaml.find("drive:\n  estimate_extrinsics: true  # bool; default false"),
            std::string::npos)
      << yaml;
  RunConfig back;
  ASSERT_TRUE(ApplyConfigText(yaml, "dump.yaml", &back).ok());
  EXPECT_EQ(OptionsToYaml(back), yaml);
  // The calibration's own rules apply (DriveRunOptions::Validate).
  RunConfig bad;
  const Status invalid =
      ApplyConfigText("drive.extrinsic_calibration.max_scans: 0\n", "b.yaml", &bad);
  ASSERT_FALSE(invalid.ok());
  EXPECT_NE(invalid.message().find("b.yaml: "), std::string::npos) << invalid.message();
  EXPECT_NE(invalid.message().find("max_scans"), std::string::npos) << invalid.message();
  // The old keys name their new place, nested or dotted.
  EXPECT_NE(Error("level2:\n  estimate_extrinsics: true\n")
                .find("my.yaml:2: key 'level2.estimate_extrinsics' moved to "
                      "'drive.estimate_extrinsics'"),
            std::string::npos);
  EXPECT_NE(Error("level2.extrinsic_calibration.max_scans: 5\n")
                .find("moved to 'drive.extrinsic_calibration.max_scans'"),
            std::string::npos);
  // A caller of MappingSystem options alone refuses drive keys it would ignore, takes defaults.
  EXPECT_NE(Error("drive.estimate_extrinsics: true\n").find("my.yaml: drive.* keys"),
            std::string::npos);
  Options o;
  EXPECT_TRUE(Apply("drive.estimate_extrinsics: false\nlevel2.use_loops: off\n", &o).ok());
  EXPECT_FALSE(o.level2.use_loops);
}

}  // namespace
}  // namespace slam_mms::app
