#include "slam_mms/merge/drive_result_io.hpp"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <system_error>
#include <utility>

#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/io/map_io.hpp"

namespace slam_mms {
namespace {

using Json = nlohmann::json;
namespace fs = std::filesystem;

Json PoseJson(const Eigen::Isometry3d& T) {
  const Eigen::Quaterniond q(T.linear());
  const Eigen::Vector3d t = T.translation();
  return Json::array({t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()});
}

bool IsGnssBiasKind(SubmapFactorKind k) {
  return k == SubmapFactorKind::kGnssBias || k == SubmapFactorKind::kGnssBiasLink;
}

Json VectorJson(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }

Json MatrixJson(const Eigen::Matrix3d& m) {
  Json a = Json::array();
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) a.push_back(m(r, k));
  }
  return a;
}

Json CovarianceJson(const Matrix6d& c) {
  Json a = Json::array();
  for (int r = 0; r < 6; ++r) {
    for (int k = 0; k < 6; ++k) a.push_back(c(r, k));
  }
  return a;
}

std::string CloudName(SubmapId id, const char* kind) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "submaps/%06lld_%s.pcd", static_cast<long long>(id), kind);
  return buf;
}

// Reading: every error names the file and the JSON path of the field.
struct Reader {
  std::string file;

  Status Bad(const std::string& where, const std::string& what) const {
    return InvalidArgumentError(file + ": " + where + ": " + what);
  }

  StatusOr<const Json*> Field(const Json& obj, const std::string& where, const char* key) const {
    if (!obj.is_object() || !obj.contains(key)) return Bad(where, std::string("missing ") + key);
    return &obj.at(key);
  }

  StatusOr<double> Number(const Json& j, const std::string& where) const {
    if (!j.is_number()) return Bad(where, "not a number");
    const double v = j.get<double>();
    if (!std::isfinite(v)) return Bad(where, "not finite");
    return v;
  }

  StatusOr<int64_t> Integer(const Json& j, const std::string& where) const {
    if (!j.is_number_integer()) return Bad(where, "not an integer");
    return j.get<int64_t>();
  }

  template <int N>
  StatusOr<Eigen::Matrix<double, N, 1>> Numbers(const Json& j, const std::string& where) const {
    if (!j.is_array() || j.size() != static_cast<size_t>(N)) {
      return Bad(where, "not an array of " + std::to_string(N) + " numbers");
    }
    Eigen::Matrix<double, N, 1> v;
    for (int i = 0; i < N; ++i) {
      SLAM_MMS_ASSIGN_OR_RETURN(v[i], Number(j[i], where + "[" + std::to_string(i) + "]"));
    }
    return v;
  }

  StatusOr<Eigen::Isometry3d> Pose(const Json& j, const std::string& where) const {
    SLAM_MMS_ASSIGN_OR_RETURN(auto v, Numbers<7>(j, where));
    const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
    if (std::abs(q.norm() - 1.0) > 1e-6) return Bad(where, "quaternion is not unit");
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q.normalized().toRotationMatrix();
    T.translation() = v.head<3>();
    return T;
  }

  StatusOr<Eigen::Matrix3d> Matrix3(const Json& j, const std::string& where) const {
    SLAM_MMS_ASSIGN_OR_RETURN(auto v, Numbers<9>(j, where));
    Eigen::Matrix3d m;
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) m(r, k) = v[3 * r + k];
    }
    return m;
  }

  StatusOr<Matrix6d> Covariance(const Json& j, const std::string& where) const {
    SLAM_MMS_ASSIGN_OR_RETURN(auto v, Numbers<36>(j, where));
    Matrix6d c;
    for (int r = 0; r < 6; ++r) {
      for (int k = 0; k < 6; ++k) c(r, k) = v[6 * r + k];
    }
    return c;
  }

  template <typename T>
  StatusOr<T> Get(const Json& obj, const std::string& where, const char* key,
                  StatusOr<T> (Reader::*parse)(const Json&, const std::string&) const) const {
    SLAM_MMS_ASSIGN_OR_RETURN(const Json* j, Field(obj, where, key));
    return (this->*parse)(*j, where + "." + key);
  }
};

StatusOr<PointCloud> ReadCloud(const fs::path& dir, const std::string& name) {
  SLAM_MMS_ASSIGN_OR_RETURN(MapCloud map, ReadPcd(dir / name));
  return std::move(map.cloud);
}

}  // namespace

Status WriteDriveResult(const DriveResult& result, const fs::path& dir) {
  std::error_code ec;
  fs::create_directories(dir / "submaps", ec);
  if (ec) {
    return InternalError("WriteDriveResult: cannot create " + (dir / "submaps").string() + ": " +
                         ec.message());
  }
  Json j;
  j["format"] = "slam_mms_drive_result";
  j["version"] = kDriveResultVersion;
  j["origin"] = {{"latitude_deg", result.origin.latitude_deg},
                 {"longitude_deg", result.origin.longitude_deg},
                 {"height_m", result.origin.height_m}};
  j["T_body_lidar"] = PoseJson(result.T_body_lidar);
  Json avail = Json::array();
  for (const GnssAvailabilityInterval& a : result.gnss_availability) {
    avail.push_back({{"start_ns", a.start.nanoseconds()},
                     {"end_ns", a.end.nanoseconds()},
                     {"availability", static_cast<int>(a.availability)},
                     {"name", GnssAvailabilityName(a.availability)}});
  }
  j["gnss_availability"] = std::move(avail);
  Json submaps = Json::array();
  for (const DriveSubmap& s : result.submaps) {
    if (s.cov_submap_scan.size() != s.scans.size()) {
      return InvalidArgumentError("WriteDriveResult: submap " + std::to_string(s.id) + " has " +
                                  std::to_string(s.scans.size()) + " scans but " +
                                  std::to_string(s.cov_submap_scan.size()) + " covariances");
    }
    Json js;
    js["id"] = s.id;
    js["start_ns"] = s.start.nanoseconds();
    js["end_ns"] = s.end.nanoseconds();
    js["T_world_submap"] = PoseJson(s.T_world_submap);
    js["map_cloud"] = CloudName(s.id, "map");
    js["registration_cloud"] = CloudName(s.id, "reg");
    Json scans = Json::array();
    for (size_t i = 0; i < s.scans.size(); ++i) {
      scans.push_back({{"scan_id", s.scans[i].scan_id},
                       {"stamp_ns", s.scans[i].stamp.nanoseconds()},
                       {"T_submap_scan", PoseJson(s.scans[i].T_submap_scan)},
                       {"covariance", CovarianceJson(s.cov_submap_scan[i])}});
    }
    js["scans"] = std::move(scans);
    submaps.push_back(std::move(js));
    MapCloud map;
    map.cloud = s.map_cloud;
    SLAM_MMS_RETURN_IF_ERROR(WritePcd(map, dir / CloudName(s.id, "map")));
    map.cloud = s.registration_cloud;
    SLAM_MMS_RETURN_IF_ERROR(WritePcd(map, dir / CloudName(s.id, "reg")));
  }
  j["submaps"] = std::move(submaps);
  Json factors = Json::array();
  for (const SubmapGraphFactor& f : result.factors) {
    Json jf;
    jf["kind"] = SubmapFactorKindName(f.kind);
    jf["a"] = f.a;
    jf["b"] = f.b;
    if (f.kind == SubmapFactorKind::kGnss) {
      jf["p_world_antenna"] = VectorJson(f.p_world_antenna);
      jf["T_submap_body"] = PoseJson(f.T_submap_body);
      jf["t_body_antenna"] = VectorJson(f.t_body_antenna);
      jf["gnss_bias"] = f.gnss_bias;
    } else if (IsGnssBiasKind(f.kind)) {
      jf["gnss_bias"] = f.gnss_bias;
      if (f.kind == SubmapFactorKind::kGnssBiasLink) {
        jf["gnss_bias_from"] = f.gnss_bias_from;
        jf["transition"] = f.transition(0, 0);
      }
    } else {
      jf["T"] = PoseJson(f.T);
    }
    if (f.kind == SubmapFactorKind::kAttitudeChain) {
      jf["T_a"] = PoseJson(f.T_a);
      jf["transition"] = MatrixJson(f.transition);
    }
    jf["covariance"] = CovarianceJson(f.covariance);
    if (f.kind == SubmapFactorKind::kRegistration) {
      jf["loss"] = {{"type", RobustLossTypeName(f.loss.type)}, {"scale", f.loss.scale}};
    }
    factors.push_back(std::move(jf));
  }
  j["factors"] = std::move(factors);
  const fs::path file = dir / kDriveResultFileName;
  const fs::path tmp = dir / (std::string(kDriveResultFileName) + ".tmp");
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out << j.dump(1) << "\n";
    out.close();
    if (!out) return InternalError("WriteDriveResult: cannot write " + tmp.string());
  }
  fs::rename(tmp, file, ec);
  if (ec) return InternalError("WriteDriveResult: cannot rename to " + file.string());
  return OkStatus();
}

StatusOr<PointCloud> ReadDriveResultCloud(const fs::path& dir, SubmapId id, DriveResultCloud kind) {
  const std::string name = CloudName(id, kind == DriveResultCloud::kMap ? "map" : "reg");
  auto cloud = ReadCloud(dir, name);
  if (!cloud.ok()) {
    return Status(cloud.status().code(), "ReadDriveResultCloud: " + (dir / name).string() + ": " +
                                             cloud.status().message());
  }
  return cloud;
}

StatusOr<DriveResult> ReadDriveResult(const fs::path& dir, const DriveResultReadOptions& options) {
  const fs::path file = dir / kDriveResultFileName;
  std::ifstream in(file, std::ios::binary);
  if (!in) return NotFoundError("ReadDriveResult: cannot open " + file.string());
  Json j;
  try {
    j = Json::parse(in);
  } catch (const Json::parse_error& e) {
    return DataLossError("ReadDriveResult: " + file.string() + ": " + e.what());
  }
  const Reader r{file.string()};
  if (!j.is_object() || j.value("format", std::string()) != "slam_mms_drive_result") {
    return r.Bad("format", "not a slam_mms drive result (format \"slam_mms_drive_result\")");
  }
  SLAM_MMS_ASSIGN_OR_RETURN(int64_t version, r.Get<int64_t>(j, "", "version", &Reader::Integer));
  if (version < 1 || version > kDriveResultVersion) {
    return r.Bad("version", std::to_string(version) + " is not supported (this library reads 1.." +
                                std::to_string(kDriveResultVersion) + ")");
  }
  DriveResult out;
  SLAM_MMS_ASSIGN_OR_RETURN(const Json* origin, r.Field(j, "", "origin"));
  SLAM_MMS_ASSIGN_OR_RETURN(out.origin.latitude_deg,
                            r.Get<double>(*origin, "origin", "latitude_deg", &Reader::Number));
  SLAM_MMS_ASSIGN_OR_RETURN(out.origin.longitude_deg,
                            r.Get<double>(*origin, "origin", "longitude_deg", &Reader::Number));
  SLAM_MMS_ASSIGN_OR_RETURN(out.origin.height_m,
                            r.Get<double>(*origin, "origin", "height_m", &Reader::Number));
  SLAM_MMS_ASSIGN_OR_RETURN(out.T_body_lidar,
                            r.Get<Eigen::Isometry3d>(j, "", "T_body_lidar", &Reader::Pose));
  SLAM_MMS_ASSIGN_OR_RETURN(const Json* avail, r.Field(j, "", "gnss_availability"));
  for (size_t i = 0; avail->is_array() && i < avail->size(); ++i) {
    const std::string w = "gnss_availability[" + std::to_string(i) + "]";
    GnssAvailabilityInterval a;
    SLAM_MMS_ASSIGN_OR_RETURN(int64_t s,
                              r.Get<int64_t>((*avail)[i], w, "start_ns", &Reader::Integer));
    SLAM_MMS_ASSIGN_OR_RETURN(int64_t e,
                              r.Get<int64_t>((*avail)[i], w, "end_ns", &Reader::Integer));
    SLAM_MMS_ASSIGN_OR_RETURN(int64_t k,
                              r.Get<int64_t>((*avail)[i], w, "availability", &Reader::Integer));
    if (k < 0 || k > 2) return r.Bad(w + ".availability", std::to_string(k) + " not in 0..2");
    a.start = Timestamp::FromNanoseconds(s);
    a.end = Timestamp::FromNanoseconds(e);
    a.availability = static_cast<GnssAvailability>(k);
    out.gnss_availability.push_back(a);
  }
  SLAM_MMS_ASSIGN_OR_RETURN(const Json* submaps, r.Field(j, "", "submaps"));
  if (!submaps->is_array()) return r.Bad("submaps", "not an array");
  for (size_t i = 0; i < submaps->size(); ++i) {
    const Json& js = (*submaps)[i];
    const std::string w = "submaps[" + std::to_string(i) + "]";
    DriveSubmap s;
    SLAM_MMS_ASSIGN_OR_RETURN(s.id, r.Get<int64_t>(js, w, "id", &Reader::Integer));
    if (!out.submaps.empty() && s.id <= out.submaps.back().id) {
      return r.Bad(w + ".id", std::to_string(s.id) + " is not greater than the previous id");
    }
    SLAM_MMS_ASSIGN_OR_RETURN(int64_t s_ns, r.Get<int64_t>(js, w, "start_ns", &Reader::Integer));
    SLAM_MMS_ASSIGN_OR_RETURN(int64_t e_ns, r.Get<int64_t>(js, w, "end_ns", &Reader::Integer));
    s.start = Timestamp::FromNanoseconds(s_ns);
    s.end = Timestamp::FromNanoseconds(e_ns);
    SLAM_MMS_ASSIGN_OR_RETURN(s.T_world_submap,
                              r.Get<Eigen::Isometry3d>(js, w, "T_world_submap", &Reader::Pose));
    SLAM_MMS_ASSIGN_OR_RETURN(const Json* scans, r.Field(js, w, "scans"));
    if (!scans->is_array() || scans->empty()) return r.Bad(w + ".scans", "not a non-empty array");
    for (size_t k = 0; k < scans->size(); ++k) {
      const std::string ws = w + ".scans[" + std::to_string(k) + "]";
      SubmapScanPose sp;
      sp.submap = s.id;
      SLAM_MMS_ASSIGN_OR_RETURN(sp.scan_id,
                                r.Get<int64_t>((*scans)[k], ws, "scan_id", &Reader::Integer));
      SLAM_MMS_ASSIGN_OR_RETURN(int64_t t_ns,
                                r.Get<int64_t>((*scans)[k], ws, "stamp_ns", &Reader::Integer));
      sp.stamp = Timestamp::FromNanoseconds(t_ns);
      SLAM_MMS_ASSIGN_OR_RETURN(
          sp.T_submap_scan,
          r.Get<Eigen::Isometry3d>((*scans)[k], ws, "T_submap_scan", &Reader::Pose));
      sp.T_world_scan = s.T_world_submap * sp.T_submap_scan;
      SLAM_MMS_ASSIGN_OR_RETURN(
          Matrix6d cov, r.Get<Matrix6d>((*scans)[k], ws, "covariance", &Reader::Covariance));
      s.scans.push_back(sp);
      s.cov_submap_scan.push_back(cov);
    }
    for (const char* key : {"map_cloud", "registration_cloud"}) {
      SLAM_MMS_ASSIGN_OR_RETURN(const Json* name, r.Field(js, w, key));
      if (!name->is_string()) return r.Bad(w + "." + key, "not a string");
      const bool is_map = std::string(key) == "map_cloud";
      if (is_map && !options.map_clouds) {
        // Loaded later by ReadDriveResultCloud, which knows the writer's names only.
        if (name->get<std::string>() != CloudName(s.id, "map")) {
          return r.Bad(w + "." + key, "'" + name->get<std::string>() + "' is not " +
                                          CloudName(s.id, "map") + " (a renamed cloud file)");
        }
        std::error_code ec;
        if (!fs::is_regular_file(dir / name->get<std::string>(), ec)) {
          return NotFoundError(file.string() + ": " + w + "." + key + ": no file " +
                               (dir / name->get<std::string>()).string());
        }
        continue;
      }
      auto cloud = ReadCloud(dir, name->get<std::string>());
      if (!cloud.ok()) {
        return Status(cloud.status().code(),
                      file.string() + ": " + w + "." + key + ": " + cloud.status().message());
      }
      (is_map ? s.map_cloud : s.registration_cloud) = std::move(cloud).value();
    }
    out.submaps.push_back(std::move(s));
  }
  SLAM_MMS_ASSIGN_OR_RETURN(const Json* factors, r.Field(j, "", "factors"));
  if (!factors->is_array()) return r.Bad("factors", "not an array");
  for (size_t i = 0; i < factors->size(); ++i) {
    const Json& jf = (*factors)[i];
    const std::string w = "factors[" + std::to_string(i) + "]";
    SubmapGraphFactor f;
    SLAM_MMS_ASSIGN_OR_RETURN(const Json* kind, r.Field(jf, w, "kind"));
    if (!kind->is_string() ||
        !SubmapFactorKindFromName(kind->get<std::string>().c_str(), &f.kind)) {
      return r.Bad(w + ".kind", "unknown factor kind " + kind->dump());
    }
    SLAM_MMS_ASSIGN_OR_RETURN(f.a, r.Get<int64_t>(jf, w, "a", &Reader::Integer));
    SLAM_MMS_ASSIGN_OR_RETURN(f.b, r.Get<int64_t>(jf, w, "b", &Reader::Integer));
    SLAM_MMS_ASSIGN_OR_RETURN(f.covariance,
                              r.Get<Matrix6d>(jf, w, "covariance", &Reader::Covariance));
    if (f.kind == SubmapFactorKind::kGnss) {
      SLAM_MMS_ASSIGN_OR_RETURN(
          f.p_world_antenna, r.Get<Eigen::Vector3d>(jf, w, "p_world_antenna", &Reader::Numbers<3>));
      SLAM_MMS_ASSIGN_OR_RETURN(f.T_submap_body,
                                r.Get<Eigen::Isometry3d>(jf, w, "T_submap_body", &Reader::Pose));
      SLAM_MMS_ASSIGN_OR_RETURN(
          f.t_body_antenna, r.Get<Eigen::Vector3d>(jf, w, "t_body_antenna", &Reader::Numbers<3>));
      SLAM_MMS_ASSIGN_OR_RETURN(int64_t bias, r.Get<int64_t>(jf, w, "gnss_bias", &Reader::Integer));
      f.gnss_bias = static_cast<int>(bias);
    } else if (IsGnssBiasKind(f.kind)) {
      auto bias_key = [&](const char* key) -> StatusOr<int> {
        SLAM_MMS_ASSIGN_OR_RETURN(int64_t v, r.Get<int64_t>(jf, w, key, &Reader::Integer));
        if (v < 0 || v > std::numeric_limits<int>::max()) {
          return r.Bad(w + "." + key, "must be a bias key >= 0");
        }
        return static_cast<int>(v);
      };
      SLAM_MMS_ASSIGN_OR_RETURN(f.gnss_bias, bias_key("gnss_bias"));
      if (f.kind == SubmapFactorKind::kGnssBiasLink) {
        SLAM_MMS_ASSIGN_OR_RETURN(f.gnss_bias_from, bias_key("gnss_bias_from"));
        SLAM_MMS_ASSIGN_OR_RETURN(const Json* phi, r.Field(jf, w, "transition"));
        if (!phi->is_number() || !(phi->get<double>() >= 0.0 && phi->get<double>() <= 1.0)) {
          return r.Bad(w + ".transition", "must be a number in [0, 1]");
        }
        f.transition = phi->get<double>() * Eigen::Matrix3d::Identity();
      }
    } else {
      SLAM_MMS_ASSIGN_OR_RETURN(f.T, r.Get<Eigen::Isometry3d>(jf, w, "T", &Reader::Pose));
    }
    if (f.kind == SubmapFactorKind::kAttitudeChain) {
      SLAM_MMS_ASSIGN_OR_RETURN(f.T_a, r.Get<Eigen::Isometry3d>(jf, w, "T_a", &Reader::Pose));
      SLAM_MMS_ASSIGN_OR_RETURN(f.transition,
                                r.Get<Eigen::Matrix3d>(jf, w, "transition", &Reader::Matrix3));
    }
    if (f.kind == SubmapFactorKind::kRegistration) {
      SLAM_MMS_ASSIGN_OR_RETURN(const Json* loss, r.Field(jf, w, "loss"));
      const std::string type = loss->value("type", std::string());
      bool known = false;
      for (RobustLossType t :
           {RobustLossType::kNone, RobustLossType::kHuber, RobustLossType::kCauchy}) {
        if (type == RobustLossTypeName(t)) {
          f.loss.type = t;
          known = true;
        }
      }
      if (!known) return r.Bad(w + ".loss.type", "unknown loss '" + type + "'");
      SLAM_MMS_ASSIGN_OR_RETURN(f.loss.scale,
                                r.Get<double>(*loss, w + ".loss", "scale", &Reader::Number));
    }
    out.factors.push_back(f);
  }
  return out;
}

}  // namespace slam_mms
