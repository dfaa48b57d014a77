#include "slam_mms_sweep/rules.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

namespace slam_mms::sweep {
namespace fs = std::filesystem;
using Json = nlohmann::json;

namespace {

constexpr double kDegenerateFlagFraction = 0.1;

std::optional<double> Num(const Json& j, const std::string& method, const std::string& key) {
  if (!j.is_object() || !j.contains("methods") || !j["methods"].contains(method)) return {};
  const Json& m = j["methods"][method];
  if (!m.contains(key) || !m[key].is_number()) return {};
  return m[key].get<double>();
}

std::string F(const std::optional<double>& v, const char* fmt = "%.3f") {
  if (!v) return "-";
  char buf[64];
  std::snprintf(buf, sizeof(buf), fmt, *v);
  return buf;
}

RuleOutcome Outcome(const std::string& rule, bool pass, const std::string& reason) {
  return {rule, pass ? "pass" : "FAIL", reason};
}

RuleOutcome NotApplicable(const std::string& rule, const std::string& why) {
  return {rule, "n/a", why};
}

RuleOutcome Sane(const RunRecord& r) {
  if (!r.process_error.empty()) return Outcome("sane", false, r.process_error);
  if (!r.result.is_object()) return Outcome("sane", false, "no result.json");
  if (r.result.contains("error")) {
    return Outcome("sane", false, r.result["error"].get<std::string>());
  }
  const Json& methods = r.result["methods"];
  for (const std::string& mode : r.spec["modes"].get<std::vector<std::string>>()) {
    if (!methods.contains(mode)) return Outcome("sane", false, mode + ": no result");
    const Json& m = methods[mode];
    if (m["status"] != "ok") return Outcome("sane", false, mode + ": " + m["status"].dump());
    if (!m["complete"].get<bool>()) return Outcome("sane", false, mode + ": incomplete");
    if (!m["finite"].get<bool>()) return Outcome("sane", false, mode + ": NaN/inf in the output");
    if (m["scans_processed"] != m["scans_total"]) {
      return Outcome("sane", false,
                     mode + ": " + m["scans_processed"].dump() + " of " + m["scans_total"].dump() +
                         " scans processed");
    }
    if (m["ate_rmse_m"].is_null()) return Outcome("sane", false, mode + ": no ATE");
  }
  return Outcome("sane", true, "");
}

RuleOutcome LidarTracks(const RunRecord& r) {
  const Json& j = r.result;
  // Drift from the start: lidar_only begins at the initial state the POS gave, whose own error
  // (up to metres with SPS) is not the tracker's.
  const std::optional<double> err = Num(j, "lidar_only", "max_drift_from_start_m");
  if (!err) return NotApplicable("lidar_tracks", "no lidar_only result");
  const double path = j["sim"]["path_m"].get<double>();
  const std::optional<double> degen = Num(j, "lidar_only", "degenerate_fraction");
  const std::optional<double> t_rel = Num(j, "lidar_only", "t_rel_pct");
  char why[256];
  if (degen && *degen >= kDegenerateFlagFraction) {
    std::snprintf(why, sizeof(why),
                  "degenerate (%.0f%% of scans): max drift %.3f m, limit 3%% of %.1f m = %.3f m",
                  100 * *degen, *err, path, 0.03 * path);
    return Outcome("lidar_tracks", *err <= 0.03 * path, why);
  }
  if (t_rel) {
    std::snprintf(why, sizeof(why), "t_rel %.3f %% (limit 1.0 %%), max drift %.3f m", *t_rel, *err);
    return Outcome("lidar_tracks", *t_rel <= 1.0, why);
  }
  std::snprintf(why, sizeof(why), "no 10 m segment: max drift %.3f m, limit %.3f m", *err,
                0.01 * path + 0.1);
  return Outcome("lidar_tracks", *err <= 0.01 * path + 0.1, why);
}

RuleOutcome FullVsPosRtk(const RunRecord& r) {
  const Json& j = r.result;
  const bool outage = !r.spec["outage"].is_null();
  const double fixed = j["sim"]["fraction_fixed"].get<double>();
  if (outage || fixed < 0.99) {
    char why[96];
    std::snprintf(why, sizeof(why), "GNSS %.0f%% fixed%s", 100 * fixed, outage ? ", outage" : "");
    return NotApplicable("full_vs_pos_rtk", why);
  }
  const auto fa = Num(j, "full", "ate_rmse_m"), ga = Num(j, "gnss_ins", "ate_rmse_m");
  const auto fr = Num(j, "full", "rot_rmse_deg"), gr = Num(j, "gnss_ins", "rot_rmse_deg");
  if (!fa || !ga || !fr || !gr) return NotApplicable("full_vs_pos_rtk", "full or gnss_ins missing");
  const double ate_limit = std::max(1.1 * *ga, *ga + 0.02), rot_limit = *gr + 0.05;
  char why[256];
  std::snprintf(why, sizeof(why), "ATE %.3f m (limit %.3f), rot %.3f deg (limit %.3f)", *fa,
                ate_limit, *fr, rot_limit);
  return Outcome("full_vs_pos_rtk", *fa <= ate_limit && *fr <= rot_limit, why);
}

// full's rotation RMSE against the POS's: level 2 must not turn the map by more than the POS it
// starts from is off. `standing_still` on standing windows (a free yaw followed the GNSS noise of
// a vehicle at rest), `full_rot_vs_pos` on moving ones (under single-point GNSS a free yaw turned
// moving drives by 1-6 deg).
RuleOutcome FullRotationWithinThePos(const RunRecord& r, bool standing_rule) {
  const char* rule = standing_rule ? "standing_still" : "full_rot_vs_pos";
  const std::string classes = r.spec["motion"]["classes"].get<std::string>();
  const bool standing = ("+" + classes + "+").find("+standing+") != std::string::npos;
  if (standing != standing_rule) {
    return NotApplicable(rule, standing ? "standing (standing_still)" : "moving");
  }
  const auto fr = Num(r.result, "full", "rot_rmse_deg");
  const auto gr = Num(r.result, "gnss_ins", "rot_rmse_deg");
  if (!fr || !gr) return NotApplicable(rule, "full or gnss_ins missing");
  char why[128];
  std::snprintf(why, sizeof(why), "full rot %.3f deg, limit gnss_ins %.3f + 0.05", *fr, *gr);
  return Outcome(rule, *fr <= *gr + 0.05, why);
}

RuleOutcome FullMapSharper(const RunRecord& r) {
  const auto fm = Num(r.result, "full", "mme"), gm = Num(r.result, "gnss_ins", "mme");
  if (!fm || !gm) return NotApplicable("full_map_sharper", "full or gnss_ins MME missing");
  char why[96];
  std::snprintf(why, sizeof(why), "MME full %.4f, gnss_ins %.4f", *fm, *gm);
  return Outcome("full_map_sharper", *fm < *gm, why);
}

// An absolute bound: full's ATE within twice its input's own error + 0.1 m, the input being the
// OXTS records' positions (the GNSS/INS solution the POS reads its fixes from; during an outage
// the simulated RT3003's own dead reckoning). The relative rules pass a run where full and
// gnss_ins diverge together (session 25: 38 m and 68 m on 2011_09_26_drive_0093).
RuleOutcome FullBounded(const RunRecord& r) {
  // find(), not const operator[]: a result without "sim" must not be undefined behaviour.
  const auto sim = r.result.find("sim");
  const bool has = sim != r.result.end() && sim->is_object() && sim->contains("records_ate_m") &&
                   sim->at("records_ate_m").is_number();
  if (!has) {
    return NotApplicable("full_bounded", "no records_ate_m (a result from before session 26)");
  }
  const auto fa = Num(r.result, "full", "ate_rmse_m");
  if (!fa) return NotApplicable("full_bounded", "full missing");
  const double records = sim->at("records_ate_m").get<double>();
  const double limit = 2.0 * records + 0.1;
  char why[128];
  std::snprintf(why, sizeof(why), "full ATE %.3f m, limit 2 x records %.3f + 0.1 = %.3f", *fa,
                records, limit);
  return Outcome("full_bounded", *fa <= limit, why);
}

// sweep.md's table of level 2's relative factors against the truth (run_one.cpp's
// methods.full.level2_factors): per kind the chi2 (6 dof; 6 on average and a median of 5.35 for a
// factor whose covariance states its error) and the RMS of the error and of the stated sigma per
// axis (rotation in deg, translation in cm, the factor's axes).
std::string Level2FactorTable(const std::vector<RunRecord>& runs) {
  struct Stats {
    std::vector<double> chi2;
    Eigen::Matrix<double, 6, 1> err2 = Eigen::Matrix<double, 6, 1>::Zero();
    Eigen::Matrix<double, 6, 1> sigma2 = Eigen::Matrix<double, 6, 1>::Zero();
    size_t n = 0;
  };
  std::map<std::string, Stats> by_kind;
  for (const RunRecord& r : runs) {
    const Json& j = r.result;
    if (!j.is_object() || !j.contains("methods") || !j["methods"].contains("full")) continue;
    const Json& full = j["methods"]["full"];
    if (!full.contains("level2_factors")) continue;
    for (const Json& f : full["level2_factors"]) {
      Stats& st = by_kind[f["kind"].get<std::string>()];
      ++st.n;
      if (f["chi2"].is_number()) st.chi2.push_back(f["chi2"].get<double>());
      for (int i = 0; i < 6; ++i) {
        const double e = f["error"][i].get<double>(), sg = f["sigma"][i].get<double>();
        st.err2[i] += e * e;
        st.sigma2[i] += sg * sg;
      }
    }
  }
  if (by_kind.empty()) return "";
  std::ostringstream md;
  md << "\n## Level 2's relative factors against the truth (full)\n\n"
     << "Each reckon, map-to-map registration and loop factor of `full`'s level 2 against the "
        "truth's relative pose of its two submap references: chi2 with 6 dof against the "
        "factor's covariance (a covariance that states the error: mean 6, median 5.35, 1 % above "
        "16.81), and per axis (the factor's own: rotation x / y / z, then translation) the RMS of "
        "the error beside the RMS of the stated sigma.\n\n"
     << "| factor | n | chi2 mean | median | > 16.81 | rotation error RMS [deg] | stated [deg] | "
        "translation error RMS [cm] | stated [cm] |\n|---|---|---|---|---|---|---|---|---|\n";
  constexpr double kDeg = 180.0 / M_PI;
  for (auto& [kind, st] : by_kind) {
    std::sort(st.chi2.begin(), st.chi2.end());
    double mean = 0.0;
    size_t above = 0;
    for (double c : st.chi2) {
      mean += c;
      above += c > 16.81 ? 1 : 0;
    }
    const bool any = !st.chi2.empty();
    auto axes = [&](const Eigen::Matrix<double, 6, 1>& sum2, int from, double scale) {
      std::string text;
      for (int i = from; i < from + 3; ++i) {
        if (i > from) text += " / ";
        text += F(scale * std::sqrt(sum2[i] / static_cast<double>(st.n)), "%.3f");
      }
      return text;
    };
    md << "| " << kind << " | " << st.n << " | " << (any ? F(mean / st.chi2.size(), "%.2f") : "-")
       << " | " << (any ? F(st.chi2[st.chi2.size() / 2], "%.2f") : "-") << " | " << above << " | "
       << axes(st.err2, 0, kDeg) << " | " << axes(st.sigma2, 0, kDeg) << " | "
       << axes(st.err2, 3, 100.0) << " | " << axes(st.sigma2, 3, 100.0) << " |\n";
  }
  return md.str();
}

std::string Join(const std::vector<std::string>& v, const std::string& sep) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) s += (i ? sep : "") + v[i];
  return s;
}

}  // namespace

const std::vector<std::string>& RuleNames() {
  static const std::vector<std::string> names = {
      "sane",           "lidar_tracks",    "full_vs_pos_rtk",
      "standing_still", "full_rot_vs_pos", "full_map_sharper",
      "full_bounded"};
  return names;
}

std::vector<RuleOutcome> EvaluateRules(const RunRecord& r) {
  std::vector<RuleOutcome> out;
  out.push_back(Sane(r));
  // The rules below read result["sim"] and ["methods"] with const operator[]: both must exist.
  const bool has = r.result.is_object() && r.result.contains("methods") && r.result.contains("sim");
  if (!has) {
    for (size_t i = 1; i < RuleNames().size(); ++i) {
      out.push_back(NotApplicable(RuleNames()[i], "no result"));
    }
    return out;
  }
  out.push_back(LidarTracks(r));
  out.push_back(FullVsPosRtk(r));
  out.push_back(FullRotationWithinThePos(r, true));
  out.push_back(FullRotationWithinThePos(r, false));
  out.push_back(FullMapSharper(r));
  out.push_back(FullBounded(r));
  return out;
}

RuleOutcome EvaluateRealRule(const RunRecord& real) {
  const std::string rule = "real_lidar_drift";
  if (!real.process_error.empty()) return Outcome(rule, false, real.process_error);
  if (!real.result.is_object() || !real.result.contains("real")) {
    return Outcome(rule, false,
                   real.result.is_object() && real.result.contains("error")
                       ? real.result["error"].get<std::string>()
                       : "no result.json");
  }
  const Json& j = real.result["real"];
  const Json& t = j["t_rel_pct_by_length"]["10"];
  const Json& r = j["r_rel_deg_per_100m_by_length"]["25"];
  if (!t.is_number() || !r.is_number()) return Outcome(rule, false, "no 10 m / 25 m segment");
  char why[320];
  std::snprintf(why, sizeof(why),
                "t_rel(10 m) %.2f %% (peer 3.28), r_rel(25 m) %.2f deg/100 m (peer 0.89)",
                t.get<double>(), r.get<double>());
  std::string reason = why;
  if (j.contains("kitti_vertical_correction_deg") &&
      j["kitti_vertical_correction_deg"].is_number()) {
    std::snprintf(why, sizeof(why), ", KITTI vertical correction %.3f deg as the peer's",
                  j["kitti_vertical_correction_deg"].get<double>());
    reason += why;
  }
  const Json& raw =
      real.result.contains("real_uncorrected") ? real.result["real_uncorrected"] : Json();
  if (raw.is_object() && raw["t_rel_pct_by_length"]["10"].is_number() &&
      raw["r_rel_deg_per_100m_by_length"]["25"].is_number()) {
    std::snprintf(why, sizeof(why), " (uncorrected: %.2f %%, %.2f deg/100 m)",
                  raw["t_rel_pct_by_length"]["10"].get<double>(),
                  raw["r_rel_deg_per_100m_by_length"]["25"].get<double>());
    reason += why;
  }
  return Outcome(rule, t.get<double>() <= 3.28 && r.get<double>() <= 0.89, reason);
}

Status WriteSweepTables(const std::vector<RunRecord>& runs, const RunRecord* real,
                        const std::string& command, const fs::path& out_dir, int* num_failures) {
  static const std::vector<std::string> kModes = {"gnss_ins", "gnss_ins_smoothed", "full",
                                                  "lidar_only"};
  static const std::vector<std::string> kMetrics = {"ate_rmse_m",
                                                    "rot_rmse_deg",
                                                    "t_rel_pct",
                                                    "r_rel_deg_per_100m",
                                                    "max_pos_err_in_outage_m",
                                                    "mme",
                                                    "degenerate_fraction",
                                                    "skipped_scans",
                                                    "scans_per_s"};
  std::ostringstream csv, md;
  Json all = Json::array();
  std::map<std::string, std::map<std::string, int>> counts;  // rule -> verdict -> n
  std::vector<std::string> failures;
  std::vector<std::string> motions;
  // CSV.
  csv << "id,drive,seed,scenario,oxts_start_s,duration_s,classes,path_m,fraction_fixed,"
         "process_error";
  for (const std::string& m : kModes) {
    for (const std::string& k : kMetrics) csv << "," << m << "." << k;
  }
  for (const std::string& rule : RuleNames()) csv << "," << rule;
  csv << "\n";
  // Markdown.
  md << "# Robustness sweep\n\n"
     << "Command: `" << command << "`\n\n"
     << "Per run: the simulated drive along a window of a real KITTI motion (`classes` from the "
        "OXTS motion), its GNSS scenario, then per method ATE [m] / rotation RMSE [deg]; "
        "lidar_only t_rel [%] and its degenerate-scan fraction; MME of full vs gnss_ins; "
        "full's largest error inside the outage [m]; the rules (`.` pass, `-` n/a, `F` fail, "
        "in the order "
     << Join(RuleNames(), ", ") << ").\n\n"
     << "| run | seed | classes | GNSS | path m | fix % | gnss_ins | smoothed | full | "
        "lidar_only | lo t_rel | lo degen | MME full / gnss_ins | full out | rules |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  *num_failures = 0;
  for (const RunRecord& r : runs) {
    const std::vector<RuleOutcome> outcomes = EvaluateRules(r);
    const Json& j = r.result;
    const bool has_sim = j.is_object() && j.contains("sim");
    const double path = has_sim ? j["sim"]["path_m"].get<double>() : 0.0;
    const double fixed = has_sim ? j["sim"]["fraction_fixed"].get<double>() : 0.0;
    const std::string id = r.spec["id"].get<std::string>();
    const std::string drive = r.spec["drive"].get<std::string>();
    if (std::find(motions.begin(), motions.end(), drive) == motions.end()) motions.push_back(drive);
    csv << id << "," << drive << "," << r.spec["seed"] << ","
        << r.spec["scenario"].get<std::string>() << "," << r.spec.value("oxts_start_s", Json())
        << "," << r.spec.value("duration_s", Json()) << ","
        << r.spec["motion"]["classes"].get<std::string>() << "," << F(path, "%.2f") << ","
        << F(fixed, "%.3f") << ",\"" << r.process_error << "\"";
    for (const std::string& m : kModes) {
      for (const std::string& k : kMetrics) csv << "," << F(Num(j, m, k), "%.6g");
    }
    std::string flags;
    Json rules = Json::object();
    for (const RuleOutcome& o : outcomes) {
      csv << "," << o.verdict;
      ++counts[o.rule][o.verdict];
      flags += o.verdict == "pass" ? "." : o.verdict == "n/a" ? "-" : "F";
      rules[o.rule] = {{"verdict", o.verdict}, {"reason", o.reason}};
      if (o.verdict == "FAIL") {
        ++*num_failures;
        failures.push_back("- `" + id + "` (drive " + drive + ", seed " + r.spec["seed"].dump() +
                           "), rule **" + o.rule + "**: " + o.reason);
      }
    }
    csv << "\n";
    auto pair = [&](const std::string& m) {
      return F(Num(j, m, "ate_rmse_m")) + " / " + F(Num(j, m, "rot_rmse_deg"), "%.2f");
    };
    md << "| " << id << " | " << r.spec["seed"] << " | "
       << r.spec["motion"]["classes"].get<std::string>() << " | "
       << r.spec["scenario"].get<std::string>() << " | " << F(path, "%.0f") << " | "
       << F(100 * fixed, "%.0f") << " | " << pair("gnss_ins") << " | " << pair("gnss_ins_smoothed")
       << " | " << pair("full") << " | " << pair("lidar_only") << " | "
       << F(Num(j, "lidar_only", "t_rel_pct"), "%.2f") << " | "
       << F(Num(j, "lidar_only", "degenerate_fraction"), "%.2f") << " | "
       << F(Num(j, "full", "mme"), "%.3f") << " / " << F(Num(j, "gnss_ins", "mme"), "%.3f") << " | "
       << F(Num(j, "full", "max_pos_err_in_outage_m")) << " | `" << flags << "` |\n";
    all.push_back({{"spec", r.spec},
                   {"result", r.result},
                   {"process_error", r.process_error},
                   {"wall_s", r.wall_s},
                   {"rules", rules}});
  }
  md << "\n" << runs.size() << " runs over " << motions.size() << " distinct KITTI motions.\n\n";
  md << "| rule | pass | FAIL | n/a |\n|---|---|---|---|\n";
  for (const std::string& rule : RuleNames()) {
    md << "| " << rule << " | " << counts[rule]["pass"] << " | " << counts[rule]["FAIL"] << " | "
       << counts[rule]["n/a"] << " |\n";
  }
  Json real_json = nullptr;
  if (real != nullptr) {
    const RuleOutcome o = EvaluateRealRule(*real);
    md << "| " << o.rule << " | " << (o.verdict == "pass") << " | " << (o.verdict == "FAIL")
       << " | 0 |\n\nReal frames (lidar_only vs OXTS): " << o.verdict << ": " << o.reason << "\n";
    if (o.verdict == "FAIL") {
      ++*num_failures;
      failures.push_back("- real frames, rule **" + o.rule + "**: " + o.reason);
    }
    real_json = {{"result", real->result},
                 {"process_error", real->process_error},
                 {"rule", {{"verdict", o.verdict}, {"reason", o.reason}}}};
  }
  md << Level2FactorTable(runs);
  md << "\n## Failures\n\n" << (failures.empty() ? "None.\n" : Join(failures, "\n") + "\n");
  const Json doc{
      {"command", command}, {"runs", all}, {"real", real_json}, {"num_failures", *num_failures}};
  for (const auto& [name, text] : std::vector<std::pair<std::string, std::string>>{
           {"sweep.csv", csv.str()}, {"sweep.md", md.str()}, {"sweep.json", doc.dump(2) + "\n"}}) {
    std::ofstream f(out_dir / name);
    f << text;
    if (!f) return InternalError("sweep: cannot write " + (out_dir / name).string());
  }
  return OkStatus();
}

}  // namespace slam_mms::sweep
