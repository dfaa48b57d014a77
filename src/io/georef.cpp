// GeoReference through GeographicLib (ENU <-> geodetic, exact) and PROJ (geodetic <-> output CRS).
// See georef.hpp.
#include "slam_mms/io/georef.hpp"

#include <proj.h>

#include <GeographicLib/LocalCartesian.hpp>
#include <GeographicLib/UTMUPS.hpp>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <utility>

#include "io/file_util.hpp"
#include "slam_mms/io/trajectory_io.hpp"

namespace slam_mms {

namespace fs = std::filesystem;

namespace {

constexpr double kDeg = M_PI / 180.0;

std::string Str(const char* s) { return s == nullptr ? std::string() : std::string(s); }

void NoLog(void*, int, const char*) {}  // the library never prints: PROJ's messages are dropped

std::string ContextError(PJ_CONTEXT* ctx) {
  const int err = proj_context_errno(ctx);
  if (err == 0) return "no detail from PROJ";
  return Str(proj_context_errno_string(ctx, err));
}

double WrapPi(double a) { return std::remainder(a, 2.0 * M_PI); }

// z-y'-x'' angles (roll, pitch, heading) [rad] of R_level_body (ENU level, FLU body), SBET style.
Eigen::Vector3d EulerNedFrd(const Eigen::Matrix3d& R_level_body) {
  Eigen::Matrix3d A;  // R_ned_enu
  A << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  const Eigen::Matrix3d B = Eigen::Vector3d(1, -1, -1).asDiagonal();  // R_flu_frd
  const Eigen::Matrix3d R = A * R_level_body * B;                     // R_ned_frd
  const double heading = std::atan2(R(1, 0), R(0, 0));
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  const double roll = std::atan2(R(2, 1), R(2, 2));
  return {roll, pitch, heading};
}

}  // namespace

struct GeoReference::Proj {
  PJ_CONTEXT* ctx = nullptr;
  PJ* op = nullptr;  ///< EPSG:4979 -> target, normalised: (lon, lat, h) -> (E, N, z).
  std::unique_ptr<GeographicLib::LocalCartesian> enu;
  ~Proj() {
    if (op != nullptr) proj_destroy(op);
    if (ctx != nullptr) proj_context_destroy(ctx);
  }
};

GeoReference::GeoReference(GeoReference&& other) noexcept = default;
GeoReference& GeoReference::operator=(GeoReference&& other) noexcept = default;
GeoReference::~GeoReference() = default;

StatusOr<GeoReference> GeoReference::Create(const GeodeticPoint& origin, const std::string& crs) {
  const std::string where = "GeoReference: ";
  if (!std::isfinite(origin.latitude_deg) || !std::isfinite(origin.longitude_deg) ||
      !std::isfinite(origin.height_m) || std::abs(origin.latitude_deg) > 90.0 ||
      std::abs(origin.longitude_deg) > 180.0) {
    return InvalidArgumentError(where + "origin (" + std::to_string(origin.latitude_deg) + ", " +
                                std::to_string(origin.longitude_deg) + ", " +
                                std::to_string(origin.height_m) + ") is not a valid WGS-84 point");
  }
  std::string target = crs;
  if (target.empty()) {
    if (origin.latitude_deg < -80.0 || origin.latitude_deg > 84.0) {
      return InvalidArgumentError(where + "origin latitude " + std::to_string(origin.latitude_deg) +
                                  " deg is outside UTM's band [-80, 84]: give a projected CRS "
                                  "(--crs EPSG:nnnn, e.g. a polar stereographic one)");
    }
    int zone = 0;
    try {
      zone = GeographicLib::UTMUPS::StandardZone(origin.latitude_deg, origin.longitude_deg);
    } catch (const std::exception& e) {
      return InvalidArgumentError(where + "no UTM zone for the origin: " + e.what());
    }
    target = "EPSG:" + std::to_string((origin.latitude_deg >= 0.0 ? 32600 : 32700) + zone);
  }
  GeoReference g;
  g.origin_ = origin;
  g.crs_request_ = crs;
  g.proj_ = std::make_unique<Proj>();
  Proj& p = *g.proj_;
  p.ctx = proj_context_create();
  if (p.ctx == nullptr) return InternalError(where + "proj_context_create failed");
  proj_log_func(p.ctx, nullptr, NoLog);
  const std::string what = "output CRS '" + target + "'";

  PJ* target_crs = proj_create(p.ctx, target.c_str());
  if (target_crs == nullptr) {
    // PROJ's own text for an unknown code is "Unknown error (code 4096)": not worth repeating.
    const std::string detail = ContextError(p.ctx);
    const bool useful = detail.find("Unknown error") == std::string::npos;
    return InvalidArgumentError(where + what + " is unknown to PROJ" +
                                (useful ? " (" + detail + ")" : std::string()) +
                                "; give a projected CRS such as EPSG:25832 or EPSG:32632");
  }
  // Everything PROJ allocates below is released on every path.
  struct Guard {
    PJ* pj;
    ~Guard() {
      if (pj != nullptr) proj_destroy(pj);
    }
  } crs_guard{target_crs};
  const PJ_TYPE type = proj_get_type(target_crs);
  if (type != PJ_TYPE_PROJECTED_CRS) {
    const char* kind = "not a CRS";
    switch (type) {
      case PJ_TYPE_GEOGRAPHIC_2D_CRS:
      case PJ_TYPE_GEOGRAPHIC_3D_CRS:
      case PJ_TYPE_GEOGRAPHIC_CRS: kind = "a geographic CRS (degrees)"; break;
      case PJ_TYPE_GEOCENTRIC_CRS: kind = "a geocentric CRS"; break;
      case PJ_TYPE_COMPOUND_CRS: kind = "a compound CRS (heights stay ellipsoidal here)"; break;
      case PJ_TYPE_VERTICAL_CRS: kind = "a vertical CRS"; break;
      default: break;
    }
    return InvalidArgumentError(where + what + " is " + kind +
                                "; a projected CRS with easting/northing in metres is needed "
                                "(e.g. EPSG:25832, EPSG:32632)");
  }
  PJ* cs = proj_crs_get_coordinate_system(p.ctx, target_crs);
  Guard cs_guard{cs};
  const int axes = cs == nullptr ? 0 : proj_cs_get_axis_count(p.ctx, cs);
  if (axes != 2) {
    return InvalidArgumentError(where + what + " has " + std::to_string(axes) +
                                " axes; 2 (easting, northing) are needed");
  }
  bool has_east = false, has_north = false;
  for (int i = 0; i < axes; ++i) {
    const char* direction = nullptr;
    const char* unit = nullptr;
    double factor = 0.0;
    proj_cs_get_axis_info(p.ctx, cs, i, nullptr, nullptr, &direction, &factor, &unit, nullptr,
                          nullptr);
    const std::string dir = Str(direction);
    has_east = has_east || dir == "east";
    has_north = has_north || dir == "north";
    if (std::abs(factor - 1.0) > 1e-12) {
      return InvalidArgumentError(where + what + " axis " + std::to_string(i) + " is in '" +
                                  Str(unit) + "'; metres are needed");
    }
  }
  if (!has_east || !has_north) {
    return InvalidArgumentError(where + what +
                                " does not have east and north axes (e.g. a south-oriented or "
                                "polar CRS); easting/northing are needed");
  }
  if (Str(proj_get_id_auth_name(target_crs, 0)) == "EPSG") {
    g.epsg_ = std::atoi(Str(proj_get_id_code(target_crs, 0)).c_str());
  }
  g.crs_name_ = Str(proj_get_name(target_crs));
  const char* const wkt_options[] = {"MULTILINE=NO", nullptr};
  g.wkt1_ = Str(proj_as_wkt(p.ctx, target_crs, PJ_WKT1_GDAL, wkt_options));
  g.wkt2_ = Str(proj_as_wkt(p.ctx, target_crs, PJ_WKT2_2019, wkt_options));
  if (g.wkt1_.empty()) {
    return InvalidArgumentError(where + what + " has no WKT1 form (" + ContextError(p.ctx) + ")");
  }

  PJ* source = proj_create(p.ctx, "EPSG:4979");
  Guard source_guard{source};
  if (source == nullptr) {
    return InternalError(where + "EPSG:4979 unknown to PROJ (" + ContextError(p.ctx) +
                         "): is proj-data (proj.db) installed?");
  }
  PJ* raw = proj_create_crs_to_crs_from_pj(p.ctx, source, target_crs, nullptr, nullptr);
  if (raw == nullptr) {
    return InvalidArgumentError(where + "no transformation from WGS 84 to " + what + " (" +
                                ContextError(p.ctx) + ")");
  }
  p.op = proj_normalize_for_visualization(p.ctx, raw);
  proj_destroy(raw);
  if (p.op == nullptr) {
    return InternalError(where + "proj_normalize_for_visualization failed for " + what);
  }
  p.enu = std::make_unique<GeographicLib::LocalCartesian>(origin.latitude_deg, origin.longitude_deg,
                                                          origin.height_m);
  // The operation PROJ uses at the origin (and a check that the origin lies in the CRS's domain).
  StatusOr<Eigen::Vector3d> o = g.GeodeticToProjected(origin);
  if (!o.ok()) {
    return InvalidArgumentError(where + "the origin cannot be expressed in " + what + ": " +
                                o.status().message());
  }
  if (PJ* used = proj_trans_get_last_used_operation(p.op)) {
    g.operation_name_ = Str(proj_get_name(used));
    g.operation_accuracy_m_ = proj_coordoperation_get_accuracy(p.ctx, used);
    proj_destroy(used);
  } else {
    g.operation_name_ = Str(proj_get_name(p.op));
    g.operation_accuracy_m_ = proj_coordoperation_get_accuracy(p.ctx, p.op);
  }
  return g;
}

Status GeoReference::CheckCrs(const std::string& crs) {
  if (crs.empty()) return OkStatus();
  GeodeticPoint probe;
  PJ_CONTEXT* ctx = proj_context_create();
  if (ctx != nullptr) {
    proj_log_func(ctx, nullptr, NoLog);
    if (PJ* pj = proj_create(ctx, crs.c_str())) {
      double west = 0, south = 0, east = 0, north = 0;
      if (proj_get_area_of_use(ctx, pj, &west, &south, &east, &north, nullptr) && west > -1000.0) {
        if (east < west) east += 360.0;  // across the antimeridian
        probe.latitude_deg = 0.5 * (south + north);
        probe.longitude_deg = std::remainder(0.5 * (west + east), 360.0);
      }
      proj_destroy(pj);
    }
    proj_context_destroy(ctx);
  }
  return Create(probe, crs).status();
}

GeodeticPoint GeoReference::EnuToGeodetic(const Eigen::Vector3d& p_world) const {
  GeodeticPoint g;
  proj_->enu->Reverse(p_world.x(), p_world.y(), p_world.z(), g.latitude_deg, g.longitude_deg,
                      g.height_m);
  return g;
}

Eigen::Vector3d GeoReference::GeodeticToEnu(const GeodeticPoint& g) const {
  Eigen::Vector3d p;
  proj_->enu->Forward(g.latitude_deg, g.longitude_deg, g.height_m, p.x(), p.y(), p.z());
  return p;
}

StatusOr<Eigen::Vector3d> GeoReference::GeodeticToProjected(const GeodeticPoint& g) const {
  proj_errno_reset(proj_->op);
  const PJ_COORD c =
      proj_trans(proj_->op, PJ_FWD, proj_coord(g.longitude_deg, g.latitude_deg, g.height_m, 0.0));
  if (proj_errno(proj_->op) != 0 || !std::isfinite(c.xyz.x) || !std::isfinite(c.xyz.y) ||
      c.xyz.x == HUGE_VAL) {
    const int err = proj_errno(proj_->op);
    return InvalidArgumentError(
        "GeoReference: PROJ cannot transform (" + std::to_string(g.latitude_deg) + ", " +
        std::to_string(g.longitude_deg) + ") to " + crs_name_ + " (" +
        (err != 0 ? Str(proj_context_errno_string(proj_->ctx, err)) : std::string("no result")) +
        ")");
  }
  return Eigen::Vector3d(c.xyz.x, c.xyz.y, g.height_m);  // heights stay WGS-84 ellipsoidal
}

StatusOr<GeodeticPoint> GeoReference::ProjectedToGeodetic(const Eigen::Vector3d& enh) const {
  proj_errno_reset(proj_->op);
  const PJ_COORD c = proj_trans(proj_->op, PJ_INV, proj_coord(enh.x(), enh.y(), enh.z(), 0.0));
  if (proj_errno(proj_->op) != 0 || !std::isfinite(c.lpz.lam) || !std::isfinite(c.lpz.phi) ||
      c.lpz.lam == HUGE_VAL) {
    return InvalidArgumentError("GeoReference: PROJ cannot transform (" + std::to_string(enh.x()) +
                                ", " + std::to_string(enh.y()) + ") of " + crs_name_ +
                                " to WGS 84");
  }
  return GeodeticPoint{c.lpz.phi, c.lpz.lam, enh.z()};  // normalised: x = lon, y = lat
}

StatusOr<Eigen::Vector3d> GeoReference::EnuToProjected(const Eigen::Vector3d& p_world) const {
  return GeodeticToProjected(EnuToGeodetic(p_world));
}

Status GeoReference::EnuToProjected(const std::vector<Eigen::Vector3d>& p_world,
                                    std::vector<Eigen::Vector3d>* out) const {
  static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double), "packed Vector3d expected");
  const size_t n = p_world.size();
  out->resize(n);
  std::vector<double> h(n);
  for (size_t i = 0; i < n; ++i) {
    const GeodeticPoint g = EnuToGeodetic(p_world[i]);
    (*out)[i] = Eigen::Vector3d(g.longitude_deg, g.latitude_deg, g.height_m);
    h[i] = g.height_m;
  }
  if (n == 0) return OkStatus();
  proj_errno_reset(proj_->op);
  const size_t stride = sizeof(Eigen::Vector3d);
  double* base = out->front().data();
  const size_t done = proj_trans_generic(proj_->op, PJ_FWD, base, stride, n, base + 1, stride, n,
                                         base + 2, stride, n, nullptr, 0, 0);
  if (done != n)
    return InternalError("GeoReference: proj_trans_generic transformed only some points");
  for (size_t i = 0; i < n; ++i) {
    Eigen::Vector3d& q = (*out)[i];
    if (!std::isfinite(q.x()) || !std::isfinite(q.y()) || q.x() == HUGE_VAL) {
      return InvalidArgumentError(
          "GeoReference: point " + std::to_string(i) + " (" + std::to_string(p_world[i].x()) +
          ", " + std::to_string(p_world[i].y()) + ", " + std::to_string(p_world[i].z()) +
          " m ENU) cannot be expressed in " + crs_name_);
    }
    q.z() = h[i];
  }
  return OkStatus();
}

StatusOr<Eigen::Vector3d> GeoReference::ProjectedToEnu(const Eigen::Vector3d& enh) const {
  SLAM_MMS_ASSIGN_OR_RETURN(const GeodeticPoint g, ProjectedToGeodetic(enh));
  return GeodeticToEnu(g);
}

Eigen::Matrix3d GeoReference::R_world_level(const GeodeticPoint& g) const {
  std::vector<double> M(9);
  double x, y, z;
  proj_->enu->Forward(g.latitude_deg, g.longitude_deg, g.height_m, x, y, z, M);
  Eigen::Matrix3d R;
  R << M[0], M[1], M[2], M[3], M[4], M[5], M[6], M[7], M[8];
  return R;  // v_world = M v_level (GeographicLib: v0 = M v1)
}

StatusOr<double> GeoReference::TrueNorthFromGridNorthDeg(const GeodeticPoint& g) const {
  constexpr double kStepDeg = 1e-6;
  GeodeticPoint a = g, b = g;
  // Centred difference along the meridian (one-sided at the poles).
  a.latitude_deg = std::max(-90.0, g.latitude_deg - kStepDeg);
  b.latitude_deg = std::min(90.0, g.latitude_deg + kStepDeg);
  SLAM_MMS_ASSIGN_OR_RETURN(const Eigen::Vector3d pa, GeodeticToProjected(a));
  SLAM_MMS_ASSIGN_OR_RETURN(const Eigen::Vector3d pb, GeodeticToProjected(b));
  return std::atan2(pb.x() - pa.x(), pb.y() - pa.y()) / kDeg;
}

LocalAttitude LocalAttitudeOf(const GeoReference& geo, const Eigen::Isometry3d& T_world_body) {
  const GeodeticPoint g = geo.EnuToGeodetic(T_world_body.translation());
  const Eigen::Matrix3d R_level_body = geo.R_world_level(g).transpose() * T_world_body.linear();
  const Eigen::Vector3d e = EulerNedFrd(R_level_body) / kDeg;
  LocalAttitude a;
  a.roll_deg = e.x();
  a.pitch_deg = e.y();
  a.heading_deg = e.z() < 0.0 ? e.z() + 360.0 : e.z();
  if (a.heading_deg >= 360.0) a.heading_deg -= 360.0;
  return a;
}

// ---- GPS time ----

StatusOr<int> GpsMinusUtcSeconds(Timestamp utc) {
  // POSIX seconds at which GPS - UTC steps up by one (IERS Bulletin C, leap second at the end of
  // the day before): 1981-07-01 ... 2017-01-01.
  static constexpr std::array<int64_t, 18> kSteps = {
      362793600, 394329600,  425865600,  489024000,  567993600,  631152000,
      662688000, 709948800,  741484800,  773020800,  820454400,  867715200,
      915148800, 1136073600, 1230768000, 1341100800, 1435708800, 1483228800};
  constexpr int64_t kGpsEpochPosix = 315964800;  // 1980-01-06T00:00:00Z
  const int64_t s = utc.nanoseconds() >= 0 ? utc.nanoseconds() / 1000000000
                                           : -((-utc.nanoseconds() + 999999999) / 1000000000);
  if (s < kGpsEpochPosix) {
    return OutOfRangeError("GpsMinusUtcSeconds: " + std::to_string(utc.nanoseconds()) +
                           " ns is before the GPS epoch 1980-01-06");
  }
  int leap = 0;
  for (const int64_t step : kSteps) leap += s >= step ? 1 : 0;
  return leap;
}

StatusOr<double> GpsSecondsFromUtc(Timestamp utc) {
  SLAM_MMS_ASSIGN_OR_RETURN(const int leap, GpsMinusUtcSeconds(utc));
  constexpr int64_t kGpsEpochNs = int64_t{315964800} * 1000000000;
  // Integer nanoseconds first: the double keeps ~60 ns at 1.5e9 s.
  const int64_t gps_ns = utc.nanoseconds() - kGpsEpochNs + int64_t{leap} * 1000000000;
  return static_cast<double>(gps_ns / 1000000000) + static_cast<double>(gps_ns % 1000000000) * 1e-9;
}

StatusOr<double> AdjustedGpsTimeFromUtc(Timestamp utc) {
  SLAM_MMS_ASSIGN_OR_RETURN(const int leap, GpsMinusUtcSeconds(utc));
  constexpr int64_t kGpsEpochNs = int64_t{315964800} * 1000000000;
  const int64_t adjusted_ns = utc.nanoseconds() - kGpsEpochNs + int64_t{leap} * 1000000000 -
                              int64_t{1000000000} * 1000000000;
  return static_cast<double>(adjusted_ns / 1000000000) +
         static_cast<double>(adjusted_ns % 1000000000) * 1e-9;
}

// ---- georef.json ----

StatusOr<std::string> GeoReferenceJson(const GeoReference& geo) {
  using json = nlohmann::ordered_json;
  const GeodeticPoint& o = geo.origin();
  SLAM_MMS_ASSIGN_OR_RETURN(const Eigen::Vector3d op, geo.GeodeticToProjected(o));
  SLAM_MMS_ASSIGN_OR_RETURN(const double north_deg, geo.TrueNorthFromGridNorthDeg(o));
  json j;
  j["format"] = "slam_mms georef";
  j["format_version"] = 1;
  j["origin"] = {{"latitude_deg", o.latitude_deg},
                 {"longitude_deg", o.longitude_deg},
                 {"height_m", o.height_m},
                 {"datum", "WGS 84 (EPSG:4979)"},
                 {"height_reference", "WGS 84 ellipsoid"},
                 {"source", "the first valid GNSS fix of the run"}};
  j["world_frame"] = {
      {"kind", "local ENU"},
      {"axes", "x east, y north, z up [m]"},
      {"definition",
       "Cartesian frame tangent to the WGS 84 ellipsoid at the origin (origin at its ellipsoidal "
       "height); p_world -> geodetic by GeographicLib LocalCartesian (exact)"},
      {"files", json::array({"<method>.tum", "<method>.kitti", "<method>_cov.csv",
                             "<method>_level1.tum", "map_<method>.ply", "map_<method>.pcd"})}};
  json crs = {{"requested", geo.crs_request()},
              {"name", geo.crs_name()},
              {"axes", "easting, northing [m]"},
              {"wkt1_gdal", geo.wkt1()},
              {"wkt2_2019", geo.wkt2()},
              {"operation", {{"from", "EPSG:4979"}, {"name", geo.operation_name()}}},
              {"library", std::string("PROJ ") + proj_info().version},
              {"origin_easting_m", op.x()},
              {"origin_northing_m", op.y()},
              {"origin_true_north_from_grid_north_deg", north_deg},
              {"files", json::array({"<method>_utm.csv or <method>_epsg<code>.csv",
                                     "map_<method>.las", "map_<method>_tiles/tile_<E>_<N>.las"})}};
  crs["epsg"] = geo.epsg() > 0 ? json(geo.epsg()) : json(nullptr);
  crs["operation"]["accuracy_m"] =
      geo.operation_accuracy_m() >= 0.0 ? json(geo.operation_accuracy_m()) : json(nullptr);
  j["crs"] = std::move(crs);
  j["vertical"] = {{"kind", "ellipsoidal"},
                   {"datum", "WGS 84 ellipsoid"},
                   {"geoid_applied", false},
                   {"note",
                    "every height (h_ellipsoid_m, h_m, LAS Z, ENU z + origin) is ellipsoidal; no "
                    "geoid model is applied and no vertical CRS is attached; orthometric height = "
                    "h - N(geoid) is left to the user"}};
  j["units"] = {{"length", "metre"}, {"angle", "degree"}, {"time", "see time"}};
  j["time"] = {
      {"t_utc_ns",
       "int64 nanoseconds since 1970-01-01T00:00:00Z, UTC (POSIX: leap seconds not counted); the "
       "one time format of the outputs"},
      {"t_s", "t_utc_ns * 1e-9 as a float, for convenience (TUM files use it)"},
      {"pose_time", "each pose's time is its scan's first point (the paper's convention)"},
      {"las_gps_time",
       "adjusted standard GPS time = GPS seconds since 1980-01-06T00:00:00Z - 1e9, GPS = UTC + "
       "leap seconds (18 s since 2017-01-01), from each point's own time"}};
  j["attitude"] = {
      {"convention",
       "roll, pitch, heading: z-y'-x'' angles of the body's forward-right-down axes w.r.t. north-"
       "east-down of the local level frame at the pose's own position (Applanix SBET style)"},
      {"heading",
       "clockwise from true north in <method>_wgs84.csv, from grid north in the "
       "projected CSV (grid = true + true_north_from_grid_north)"}};
  return j.dump(2) + "\n";
}

Status WriteGeorefJson(const GeoReference& geo, const fs::path& file) {
  SLAM_MMS_ASSIGN_OR_RETURN(const std::string text, GeoReferenceJson(geo));
  return io_internal::WriteFileBytes(file, text);
}

// ---- trajectory CSVs ----

namespace {

struct PoseRow {
  GeodeticPoint g;
  Eigen::Vector3d attitude_deg;                  ///< roll, pitch, heading (true)
  std::optional<Eigen::Vector3d> sigma_enu_m;    ///< local level east, north, up
  std::optional<Eigen::Matrix2d> cov_en;         ///< local level east/north covariance
  std::optional<Eigen::Vector3d> sigma_att_deg;  ///< roll, pitch, heading
};

PoseRow MakeRow(const GeoReference& geo, const StampedPose& p) {
  PoseRow r;
  const Eigen::Isometry3d& T = p.T_world_body;
  r.g = geo.EnuToGeodetic(T.translation());
  const Eigen::Matrix3d R_wl = geo.R_world_level(r.g);
  const Eigen::Matrix3d R_level_body = R_wl.transpose() * T.linear();
  const LocalAttitude a = LocalAttitudeOf(geo, T);
  r.attitude_deg = Eigen::Vector3d(a.roll_deg, a.pitch_deg, a.heading_deg);
  if (p.cov_T_world_body) {
    const Eigen::Matrix<double, 6, 6>& C = *p.cov_T_world_body;
    // Right perturbation T = T_hat Exp([omega, v]): p = p_hat + R v, R = R_hat Exp(omega).
    const Eigen::Matrix3d Rb = R_level_body;
    const Eigen::Matrix3d cov_p = Rb * C.block<3, 3>(3, 3) * Rb.transpose();
    r.sigma_enu_m = cov_p.diagonal().cwiseMax(0.0).cwiseSqrt();
    r.cov_en = cov_p.block<2, 2>(0, 0);
    // Euler angles' Jacobian w.r.t. omega by central differences (angles wrapped).
    constexpr double kEps = 1e-6;
    Eigen::Matrix3d J;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Matrix3d dR =
          Eigen::AngleAxisd(kEps, Eigen::Vector3d::Unit(k)).toRotationMatrix();
      const Eigen::Vector3d plus = EulerNedFrd(Rb * dR);
      const Eigen::Vector3d minus = EulerNedFrd(Rb * dR.transpose());
      for (int a2 = 0; a2 < 3; ++a2) J(a2, k) = WrapPi(plus[a2] - minus[a2]) / (2.0 * kEps);
    }
    const Eigen::Matrix3d cov_att = J * C.block<3, 3>(0, 0) * J.transpose();
    r.sigma_att_deg = cov_att.diagonal().cwiseMax(0.0).cwiseSqrt() / kDeg;
  }
  return r;
}

std::string Fmt(const char* format, double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), format, v);
  return buf;
}

void AppendTime(std::string* line, Timestamp t) {
  *line += std::to_string(t.nanoseconds());
  *line += ',';
  *line += FormatSecondsExact(t);
}

void AppendAttitudeAndSigmas(std::string* line, const Eigen::Vector3d& attitude_deg,
                             const std::optional<Eigen::Vector3d>& sigma_pos_m,
                             const std::optional<Eigen::Vector3d>& sigma_att_deg) {
  for (int k = 0; k < 3; ++k) *line += Fmt(",%.6f", attitude_deg[k]);
  for (int k = 0; k < 3; ++k) *line += sigma_pos_m ? Fmt(",%.6g", (*sigma_pos_m)[k]) : ",";
  for (int k = 0; k < 3; ++k) *line += sigma_att_deg ? Fmt(",%.6g", (*sigma_att_deg)[k]) : ",";
}

}  // namespace

Status WriteTrajectoryWgs84Csv(const Trajectory& trajectory, const GeoReference& geo,
                               const fs::path& file) {
  std::string text =
      "t_utc_ns,t_s,lat_deg,lon_deg,h_ellipsoid_m,roll_deg,pitch_deg,heading_deg,sigma_east_m,"
      "sigma_north_m,sigma_up_m,sigma_roll_deg,sigma_pitch_deg,sigma_heading_deg\n";
  for (const StampedPose& p : trajectory.poses()) {
    const PoseRow r = MakeRow(geo, p);
    std::string line;
    AppendTime(&line, p.stamp);
    line += Fmt(",%.10f", r.g.latitude_deg);
    line += Fmt(",%.10f", r.g.longitude_deg);
    line += Fmt(",%.4f", r.g.height_m);
    AppendAttitudeAndSigmas(&line, r.attitude_deg, r.sigma_enu_m, r.sigma_att_deg);
    text += line;
    text += '\n';
  }
  return io_internal::WriteFileBytes(file, text);
}

Status WriteTrajectoryProjectedCsv(const Trajectory& trajectory, const GeoReference& geo,
                                   const fs::path& file) {
  std::string text =
      "t_utc_ns,t_s,easting_m,northing_m,h_m,roll_deg,pitch_deg,grid_heading_deg,"
      "sigma_easting_m,sigma_northing_m,sigma_up_m,sigma_roll_deg,sigma_pitch_deg,"
      "sigma_heading_deg\n";
  for (const StampedPose& p : trajectory.poses()) {
    const PoseRow r = MakeRow(geo, p);
    SLAM_MMS_ASSIGN_OR_RETURN(const Eigen::Vector3d enh, geo.GeodeticToProjected(r.g));
    SLAM_MMS_ASSIGN_OR_RETURN(const double alpha_deg, geo.TrueNorthFromGridNorthDeg(r.g));
    Eigen::Vector3d attitude = r.attitude_deg;
    attitude.z() = std::fmod(attitude.z() + alpha_deg + 720.0, 360.0);
    std::optional<Eigen::Vector3d> sigma;
    if (r.sigma_enu_m) {
      // Level (east, north) -> grid (E, N): a clockwise rotation by alpha (scale factor ignored).
      const double c = std::cos(alpha_deg * kDeg), s = std::sin(alpha_deg * kDeg);
      Eigen::Matrix2d G;
      G << c, s, -s, c;
      const Eigen::Matrix2d cov = G * *r.cov_en * G.transpose();
      sigma = Eigen::Vector3d(std::sqrt(std::max(0.0, cov(0, 0))),
                              std::sqrt(std::max(0.0, cov(1, 1))), r.sigma_enu_m->z());
    }
    std::string line;
    AppendTime(&line, p.stamp);
    line += Fmt(",%.4f", enh.x());
    line += Fmt(",%.4f", enh.y());
    line += Fmt(",%.4f", enh.z());
    AppendAttitudeAndSigmas(&line, attitude, sigma, r.sigma_att_deg);
    text += line;
    text += '\n';
  }
  return io_internal::WriteFileBytes(file, text);
}

}  // namespace slam_mms
