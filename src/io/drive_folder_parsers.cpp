#include "io/drive_folder_parsers.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>

#include "io/binary_util.hpp"
#include "io/file_util.hpp"
#include "io/parsers.hpp"
#include "io/point_file_format.hpp"
#include "slam_mms/io/oxts_record.hpp"

namespace slam_mms::io_internal {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

// The attitude sigma group of initial_state.csv and pos.csv (all three or none).
const std::vector<const char*>& RpySigmaColumns() {
  static const std::vector<const char*> c = {"sigma_roll_deg", "sigma_pitch_deg", "sigma_yaw_deg"};
  return c;
}

// Reads `columns` of `row` as finite doubles into `out`.
Status Doubles(const CsvTable& t, size_t row, const std::vector<const char*>& columns,
               double* out) {
  for (size_t k = 0; k < columns.size(); ++k) {
    SLAM_MMS_RETURN_IF_ERROR(t.Double(row, columns[k], &out[k]));
  }
  return OkStatus();
}

Status CheckRange(const CsvTable& t, size_t row, const char* column, double v, double lo,
                  double hi) {
  if (v < lo || v > hi) {
    return DataLossError(t.Where(row, column) + ": " + FormatDouble(v) + " outside [" +
                         FormatDouble(lo) + ", " + FormatDouble(hi) + "]");
  }
  return OkStatus();
}

// Attitude R = Rz(yaw) Ry(pitch) Rx(roll) from degrees, computed as OxtsAttitude does.
Eigen::Matrix3d AttitudeFromDeg(double roll_deg, double pitch_deg, double yaw_deg) {
  OxtsRecord r;
  r.roll_rad = roll_deg * kDegToRad;
  r.pitch_rad = pitch_deg * kDegToRad;
  r.yaw_rad = yaw_deg * kDegToRad;
  return OxtsAttitude(r);
}

// Optional columns of pos.csv come in groups of three; a group is all there or absent.
Status GroupComplete(const CsvTable& t, const std::vector<const char*>& group, bool* present) {
  size_t n = 0;
  for (const char* c : group) n += t.Has(c) ? 1 : 0;
  *present = n == group.size();
  if (n != 0 && n != group.size()) {
    std::string names;
    for (const char* c : group) names += std::string(names.empty() ? "" : ",") + c;
    return DataLossError(t.file() + ": header has only " + std::to_string(n) + " of the columns " +
                         names + "; give all three or none");
  }
  return OkStatus();
}

}  // namespace

const CsvSchema& ScansCsvSchema() {
  static const CsvSchema s{{"file", "stamp_start_ns", "stamp_end_ns"}, {}};
  return s;
}
const CsvSchema& ImuCsvSchema() {
  static const CsvSchema s{{"stamp_ns", "ax", "ay", "az", "wx", "wy", "wz"}, {}};
  return s;
}
const CsvSchema& GnssCsvSchema() {
  static const CsvSchema s{
      {"stamp_ns", "lat_deg", "lon_deg", "height_m", "sigma_e_m", "sigma_n_m", "sigma_u_m", "fix"},
      {"num_sats"}};
  return s;
}
const CsvSchema& InitialStateCsvSchema() {
  static const CsvSchema s{
      {"stamp_ns", "roll_deg", "pitch_deg", "yaw_deg", "v_east_mps", "v_north_mps", "v_up_mps"},
      {"sigma_roll_deg", "sigma_pitch_deg", "sigma_yaw_deg"}};
  return s;
}
const CsvSchema& PosCsvSchema() {
  static const CsvSchema s{
      {"stamp_ns", "lat_deg", "lon_deg", "height_m", "roll_deg", "pitch_deg", "yaw_deg"},
      {"sigma_roll_deg", "sigma_pitch_deg", "sigma_yaw_deg", "sigma_e_m", "sigma_n_m",
       "sigma_u_m"}};
  return s;
}

const char* GnssFixCsvName(GnssFixType type) {
  switch (type) {
    case GnssFixType::kSingle: return "sps";
    case GnssFixType::kDifferential: return "dgps";
    case GnssFixType::kRtkFloat: return "float";
    case GnssFixType::kRtkFixed: return "fixed";
    default: return "none";
  }
}

bool ParseGnssFixCsvName(const std::string& name, GnssFixType* type) {
  for (const GnssFixType t : {GnssFixType::kNone, GnssFixType::kSingle, GnssFixType::kDifferential,
                              GnssFixType::kRtkFloat, GnssFixType::kRtkFixed}) {
    if (name == GnssFixCsvName(t)) {
      *type = t;
      return true;
    }
  }
  return false;
}

// ------------------------------------------------------------------------------------------------
StatusOr<std::vector<FolderScanEntry>> ParseScansCsv(std::string_view bytes,
                                                     const std::string& file) {
  SLAM_MMS_ASSIGN_OR_RETURN(const CsvTable t, CsvTable::Parse(bytes, file, ScansCsvSchema()));
  std::vector<FolderScanEntry> out;
  out.reserve(t.num_rows());
  std::map<std::string, int> seen;
  for (size_t r = 0; r < t.num_rows(); ++r) {
    FolderScanEntry e;
    e.line = t.line(r);
    e.file = t.Text(r, "file");
    if (e.file.empty()) return DataLossError(t.Where(r, "file") + ": empty");
    const std::filesystem::path p(e.file);
    bool dotdot = false;
    for (const auto& part : p) dotdot = dotdot || part == "..";
    if (p.is_absolute() || dotdot) {
      return DataLossError(t.Where(r, "file") + ": '" + e.file +
                           "' must be a name relative to scans/ (no absolute path, no '..')");
    }
    ScanFileKind kind;
    if (!ScanFileKindOf(e.file, &kind)) {
      return DataLossError(t.Where(r, "file") + ": '" + e.file +
                           "' has an unknown extension (expected .pcd, .ply or .bin)");
    }
    if (const auto it = seen.find(e.file); it != seen.end()) {
      return DataLossError(t.Where(r, "file") + ": '" + e.file + "' already listed on line " +
                           std::to_string(it->second));
    }
    seen[e.file] = e.line;
    SLAM_MMS_RETURN_IF_ERROR(t.Stamp(r, "stamp_start_ns", &e.start));
    SLAM_MMS_RETURN_IF_ERROR(t.Stamp(r, "stamp_end_ns", &e.end));
    if (e.end <= e.start) {
      return DataLossError(t.Where(r, "stamp_end_ns") + ": " + std::to_string(e.end.nanoseconds()) +
                           " not after stamp_start_ns " + std::to_string(e.start.nanoseconds()));
    }
    if (!out.empty() && e.start <= out.back().start) {
      return DataLossError(
          t.Where(r, "stamp_start_ns") + ": " + std::to_string(e.start.nanoseconds()) +
          (e.start == out.back().start ? " duplicated" : " goes backwards") + " (line " +
          std::to_string(out.back().line) + " has " +
          std::to_string(out.back().start.nanoseconds()) + "); stamps must strictly increase");
    }
    out.push_back(std::move(e));
  }
  return out;
}

Status ParseImuCsv(std::string_view bytes, const std::string& file, std::vector<ImuSample>* imu,
                   std::vector<std::string>* sources) {
  SLAM_MMS_ASSIGN_OR_RETURN(const CsvTable t, CsvTable::Parse(bytes, file, ImuCsvSchema()));
  std::vector<Timestamp> stamps;
  SLAM_MMS_RETURN_IF_ERROR(t.IncreasingStamps("stamp_ns", &stamps));
  imu->clear();
  sources->clear();
  imu->reserve(t.num_rows());
  for (size_t r = 0; r < t.num_rows(); ++r) {
    double v[6];
    SLAM_MMS_RETURN_IF_ERROR(Doubles(t, r, {"ax", "ay", "az", "wx", "wy", "wz"}, v));
    ImuSample s;
    s.stamp = stamps[r];
    s.accel_mps2 = Eigen::Vector3d(v[0], v[1], v[2]);
    s.gyro_radps = Eigen::Vector3d(v[3], v[4], v[5]);
    imu->push_back(s);
    sources->push_back(t.Source(r));
  }
  return OkStatus();
}

Status ParseGnssCsv(std::string_view bytes, const std::string& file, std::vector<GnssFix>* gnss,
                    std::vector<std::string>* sources) {
  SLAM_MMS_ASSIGN_OR_RETURN(const CsvTable t, CsvTable::Parse(bytes, file, GnssCsvSchema()));
  std::vector<Timestamp> stamps;
  SLAM_MMS_RETURN_IF_ERROR(t.IncreasingStamps("stamp_ns", &stamps));
  gnss->clear();
  sources->clear();
  gnss->reserve(t.num_rows());
  for (size_t r = 0; r < t.num_rows(); ++r) {
    double v[6];
    SLAM_MMS_RETURN_IF_ERROR(Doubles(
        t, r, {"lat_deg", "lon_deg", "height_m", "sigma_e_m", "sigma_n_m", "sigma_u_m"}, v));
    SLAM_MMS_RETURN_IF_ERROR(CheckRange(t, r, "lat_deg", v[0], -90.0, 90.0));
    SLAM_MMS_RETURN_IF_ERROR(CheckRange(t, r, "lon_deg", v[1], -180.0, 180.0));
    for (int k = 3; k < 6; ++k) {
      static const char* kNames[] = {"sigma_e_m", "sigma_n_m", "sigma_u_m"};
      if (v[k] < 0.0) {
        return DataLossError(t.Where(r, kNames[k - 3]) + ": " + FormatDouble(v[k]) +
                             " is negative");
      }
    }
    GnssFix fix;
    fix.stamp = stamps[r];
    fix.latitude_deg = v[0];
    fix.longitude_deg = v[1];
    fix.height_m = v[2];
    fix.sigma_horizontal_m = v[3] == v[4] ? v[3] : std::sqrt(0.5 * (v[3] * v[3] + v[4] * v[4]));
    fix.sigma_vertical_m = v[5];
    if (!ParseGnssFixCsvName(t.Text(r, "fix"), &fix.type)) {
      return DataLossError(t.Where(r, "fix") + ": '" + t.Text(r, "fix").substr(0, 40) +
                           "' is not one of none, sps, dgps, float, fixed");
    }
    if (t.Has("num_sats")) {
      int64_t n = 0;
      SLAM_MMS_RETURN_IF_ERROR(t.Int64(r, "num_sats", &n));
      if (n < 0 || n > 1000) {
        return DataLossError(t.Where(r, "num_sats") + ": " + std::to_string(n) +
                             " outside [0, 1000]");
      }
      fix.num_satellites = static_cast<int>(n);
    }
    gnss->push_back(fix);
    sources->push_back(t.Source(r));
  }
  return OkStatus();
}

Status ParseInitialStateCsv(std::string_view bytes, const std::string& file,
                            std::optional<InsState>* state, std::string* source,
                            std::optional<Eigen::Vector3d>* sigma_rpy_rad) {
  SLAM_MMS_ASSIGN_OR_RETURN(const CsvTable t,
                            CsvTable::Parse(bytes, file, InitialStateCsvSchema()));
  state->reset();
  source->clear();
  sigma_rpy_rad->reset();
  if (t.num_rows() == 0) return OkStatus();
  bool has_sigmas = false;
  SLAM_MMS_RETURN_IF_ERROR(GroupComplete(t, RpySigmaColumns(), &has_sigmas));
  if (has_sigmas) {
    double sg[3];
    SLAM_MMS_RETURN_IF_ERROR(Doubles(t, 0, RpySigmaColumns(), sg));
    for (int k = 0; k < 3; ++k) {
      SLAM_MMS_RETURN_IF_ERROR(CheckRange(t, 0, RpySigmaColumns()[k], sg[k], 1e-9, 180.0));
    }
    *sigma_rpy_rad = Eigen::Vector3d(sg[0], sg[1], sg[2]) * kDegToRad;
  }
  InsState s;
  SLAM_MMS_RETURN_IF_ERROR(t.Stamp(0, "stamp_ns", &s.stamp));
  double v[6];
  SLAM_MMS_RETURN_IF_ERROR(Doubles(
      t, 0, {"roll_deg", "pitch_deg", "yaw_deg", "v_east_mps", "v_north_mps", "v_up_mps"}, v));
  s.T_world_body.linear() = AttitudeFromDeg(v[0], v[1], v[2]);
  s.v_world_mps = Eigen::Vector3d(v[3], v[4], v[5]);
  *state = s;
  *source = t.Source(0);
  return OkStatus();
}

Status ParsePosCsv(std::string_view bytes, const std::string& file, std::vector<PosRecord>* pos,
                   std::vector<std::string>* sources) {
  SLAM_MMS_ASSIGN_OR_RETURN(const CsvTable t, CsvTable::Parse(bytes, file, PosCsvSchema()));
  bool has_rpy = false, has_enu = false;
  SLAM_MMS_RETURN_IF_ERROR(GroupComplete(t, RpySigmaColumns(), &has_rpy));
  SLAM_MMS_RETURN_IF_ERROR(GroupComplete(t, {"sigma_e_m", "sigma_n_m", "sigma_u_m"}, &has_enu));
  std::vector<Timestamp> stamps;
  SLAM_MMS_RETURN_IF_ERROR(t.IncreasingStamps("stamp_ns", &stamps));
  pos->clear();
  sources->clear();
  pos->reserve(t.num_rows());
  for (size_t r = 0; r < t.num_rows(); ++r) {
    double v[6];
    SLAM_MMS_RETURN_IF_ERROR(
        Doubles(t, r, {"lat_deg", "lon_deg", "height_m", "roll_deg", "pitch_deg", "yaw_deg"}, v));
    SLAM_MMS_RETURN_IF_ERROR(CheckRange(t, r, "lat_deg", v[0], -90.0, 90.0));
    SLAM_MMS_RETURN_IF_ERROR(CheckRange(t, r, "lon_deg", v[1], -180.0, 180.0));
    PosRecord p;
    p.stamp = stamps[r];
    p.latitude_deg = v[0];
    p.longitude_deg = v[1];
    p.height_m = v[2];
    p.R_enu_body = AttitudeFromDeg(v[3], v[4], v[5]);
    double s[3];
    if (has_rpy) {
      SLAM_MMS_RETURN_IF_ERROR(Doubles(t, r, RpySigmaColumns(), s));
      p.sigma_rpy_rad = Eigen::Vector3d(s[0], s[1], s[2]) * kDegToRad;
    }
    if (has_enu) {
      SLAM_MMS_RETURN_IF_ERROR(Doubles(t, r, {"sigma_e_m", "sigma_n_m", "sigma_u_m"}, s));
      p.sigma_enu_m = Eigen::Vector3d(s[0], s[1], s[2]);
    }
    pos->push_back(p);
    sources->push_back(t.Source(r));
  }
  return OkStatus();
}

// ------------------------------------------------------------------------------------------------
bool ScanFileKindOf(const std::string& name, ScanFileKind* kind) {
  std::string ext = std::filesystem::path(name).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (ext == ".pcd") {
    *kind = ScanFileKind::kPcd;
  } else if (ext == ".ply") {
    *kind = ScanFileKind::kPly;
  } else if (ext == ".bin") {
    *kind = ScanFileKind::kKittiBin;
  } else {
    return false;
  }
  return true;
}

Status ParseScanFile(std::string_view bytes, ScanFileKind kind, const std::string& file,
                     ScanFilePoints* points) {
  points->xyzr.clear();
  points->time_s.clear();
  points->time_field.clear();
  if (kind == ScanFileKind::kKittiBin) {
    SLAM_MMS_RETURN_IF_ERROR(ParseKittiBinScan(bytes, file, &points->xyzr));
    points->declared_points = points->xyzr.size() / 4;
    return OkStatus();
  }
  PointFileLayout layout;
  if (kind == ScanFileKind::kPcd) {
    SLAM_MMS_ASSIGN_OR_RETURN(layout, ParsePcdHeader(bytes, file));
  } else {
    SLAM_MMS_ASSIGN_OR_RETURN(layout, ParsePlyHeader(bytes, file));
  }
  points->declared_points = layout.num_points;
  const auto find = [&layout](std::initializer_list<const char*> names, std::string* found) {
    for (const char* n : names) {
      const int c = layout.ColumnIndex(n);
      if (c >= 0) {
        if (found != nullptr) *found = n;
        return c;
      }
    }
    return -1;
  };
  std::vector<int> wanted = {find({"x"}, nullptr), find({"y"}, nullptr), find({"z"}, nullptr),
                             find({"intensity", "reflectance", "scalar_intensity"}, nullptr)};
  for (size_t k = 0; k < 3; ++k) {
    if (wanted[k] < 0) {
      return DataLossError(file + ": " + layout.format + " has no field '" +
                           std::string(1, static_cast<char>('x' + k)) +
                           "' (a scan needs x, y, z; optional intensity and t/time/timestamp)");
    }
  }
  std::string time_field;
  const int time_column = find({"t", "time", "timestamp"}, &time_field);
  if (time_column >= 0) wanted.push_back(time_column);
  std::vector<float> values;
  SLAM_MMS_RETURN_IF_ERROR(DecodePointColumns(bytes, layout, file, wanted, &values));
  const size_t m = wanted.size();
  const size_t n = values.size() / m;
  if (m == 4) {
    points->xyzr = std::move(values);
    return OkStatus();
  }
  points->time_field = time_field;
  points->xyzr.resize(4 * n);
  points->time_s.resize(n);
  for (size_t i = 0; i < n; ++i) {
    std::copy_n(&values[i * m], 4, &points->xyzr[4 * i]);
    points->time_s[i] = values[i * m + 4];
  }
  return OkStatus();
}

// ------------------------------------------------------------------------------------------------
std::string FormatScanFile(const PointCloud& cloud, ScanFileKind kind, bool ascii, bool with_time) {
  const size_t n = cloud.size();
  with_time = with_time && kind != ScanFileKind::kKittiBin;
  const std::string count = std::to_string(n);
  std::string out;
  if (kind == ScanFileKind::kPcd) {
    out = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\n";
    out += with_time ? "FIELDS x y z intensity t\nSIZE 4 4 4 4 4\nTYPE F F F F F\nCOUNT 1 1 1 1 1\n"
                     : "FIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\n";
    out += "WIDTH " + count + "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + count + "\nDATA " +
           (ascii ? "ascii\n" : "binary\n");
  } else if (kind == ScanFileKind::kPly) {
    out = std::string("ply\nformat ") + (ascii ? "ascii" : "binary_little_endian") +
          " 1.0\ncomment slam_mms scan\nelement vertex " + count +
          "\nproperty float x\nproperty float y\nproperty float z\nproperty float intensity\n";
    if (with_time) out += "property float t\n";
    out += "end_header\n";
  }
  const bool have_time = cloud.time_offsets_s().size() == n;
  if (ascii && kind != ScanFileKind::kKittiBin) {
    char buf[96];
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3f& p = cloud.points()[i];
      int len = std::snprintf(buf, sizeof(buf), "%.9g %.9g %.9g %.9g", p.x(), p.y(), p.z(),
                              cloud.intensities()[i]);
      out.append(buf, static_cast<size_t>(len));
      if (with_time) {
        len = std::snprintf(buf, sizeof(buf), " %.9g", have_time ? cloud.time_offsets_s()[i] : 0.f);
        out.append(buf, static_cast<size_t>(len));
      }
      out += '\n';
    }
    return out;
  }
  const size_t header = out.size();
  const size_t record = with_time ? 20 : 16;
  out.resize(header + n * record);
  char* q = out.data() + header;
  for (size_t i = 0; i < n; ++i, q += record) {
    const Eigen::Vector3f& p = cloud.points()[i];
    PutLe<float>(q, p.x());
    PutLe<float>(q + 4, p.y());
    PutLe<float>(q + 8, p.z());
    PutLe<float>(q + 12, cloud.intensities()[i]);
    if (with_time) PutLe<float>(q + 16, have_time ? cloud.time_offsets_s()[i] : 0.0f);
  }
  return out;
}

}  // namespace slam_mms::io_internal
