#include "slam_mms/io/oxts_record.hpp"

#include <Eigen/Geometry>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <sstream>

namespace slam_mms {
namespace {

constexpr const char* kFieldNames[OxtsRecord::kNumFields] = {
    "lat",          "lon",     "alt",     "roll",    "pitch",   "yaw",    "vn", "ve",
    "vf",           "vl",      "vu",      "ax",      "ay",      "az",     "af", "al",
    "au",           "wx",      "wy",      "wz",      "wf",      "wl",     "wu", "pos_accuracy",
    "vel_accuracy", "navstat", "numsats", "posmode", "velmode", "orimode"};

constexpr int kFirstIntegerField = 25;  // navstat .. orimode (0-based 25..29)

std::string Where(const std::string& file, int line_number) {
  std::ostringstream os;
  os << file << ":" << line_number;
  return os.str();
}

}  // namespace

std::array<double, OxtsRecord::kNumFields> OxtsRecord::ToArray() const {
  return {lat_deg,
          lon_deg,
          alt_m,
          roll_rad,
          pitch_rad,
          yaw_rad,
          vn,
          ve,
          vf,
          vl,
          vu,
          ax,
          ay,
          az,
          af,
          al,
          au,
          wx,
          wy,
          wz,
          wf,
          wl,
          wu,
          pos_accuracy_m,
          vel_accuracy_mps,
          static_cast<double>(navstat),
          static_cast<double>(numsats),
          static_cast<double>(posmode),
          static_cast<double>(velmode),
          static_cast<double>(orimode)};
}

OxtsRecord OxtsRecord::FromArray(const std::array<double, kNumFields>& v) {
  OxtsRecord r;
  r.lat_deg = v[0];
  r.lon_deg = v[1];
  r.alt_m = v[2];
  r.roll_rad = v[3];
  r.pitch_rad = v[4];
  r.yaw_rad = v[5];
  r.vn = v[6];
  r.ve = v[7];
  r.vf = v[8];
  r.vl = v[9];
  r.vu = v[10];
  r.ax = v[11];
  r.ay = v[12];
  r.az = v[13];
  r.af = v[14];
  r.al = v[15];
  r.au = v[16];
  r.wx = v[17];
  r.wy = v[18];
  r.wz = v[19];
  r.wf = v[20];
  r.wl = v[21];
  r.wu = v[22];
  r.pos_accuracy_m = v[23];
  r.vel_accuracy_mps = v[24];
  r.navstat = static_cast<int>(std::lround(v[25]));
  r.numsats = static_cast<int>(std::lround(v[26]));
  r.posmode = static_cast<int>(std::lround(v[27]));
  r.velmode = static_cast<int>(std::lround(v[28]));
  r.orimode = static_cast<int>(std::lround(v[29]));
  return r;
}

const char* OxtsRecord::FieldName(int i) {
  return (i >= 0 && i < kNumFields) ? kFieldNames[i] : "?";
}

StatusOr<OxtsRecord> ParseOxtsLine(const std::string& line, const std::string& file,
                                   int line_number) {
  std::array<double, OxtsRecord::kNumFields> values{};
  const char* p = line.c_str();
  const char* const end = p + line.size();
  int count = 0;
  while (true) {
    while (p < end && std::isspace(static_cast<unsigned char>(*p))) ++p;
    if (p >= end) break;
    const char* token_start = p;
    while (p < end && !std::isspace(static_cast<unsigned char>(*p))) ++p;
    const std::string token(token_start, p);
    if (count >= OxtsRecord::kNumFields) {
      return DataLossError(Where(file, line_number) + ": OXTS line has more than " +
                           std::to_string(OxtsRecord::kNumFields) + " numbers (extra token '" +
                           token + "' after field 30 (orimode))");
    }
    const std::string field =
        "field " + std::to_string(count + 1) + " (" + OxtsRecord::FieldName(count) + ")";
    char* parse_end = nullptr;
    errno = 0;
    const double v = std::strtod(token.c_str(), &parse_end);
    if (parse_end != token.c_str() + token.size() || token.empty()) {
      return DataLossError(Where(file, line_number) + ": " + field + ": cannot parse '" + token +
                           "' as a number");
    }
    if (!std::isfinite(v)) {
      return DataLossError(Where(file, line_number) + ": " + field + ": value '" + token +
                           "' is not finite");
    }
    if (count >= kFirstIntegerField && v != std::floor(v)) {
      return DataLossError(Where(file, line_number) + ": " + field + ": value '" + token +
                           "' must be an integer");
    }
    values[count++] = v;
  }
  if (count != OxtsRecord::kNumFields) {
    std::string missing = count < OxtsRecord::kNumFields
                              ? std::string("; field ") + std::to_string(count + 1) + " (" +
                                    OxtsRecord::FieldName(count) + ") is missing"
                              : std::string();
    return DataLossError(Where(file, line_number) + ": OXTS line has " + std::to_string(count) +
                         " numbers, expected " + std::to_string(OxtsRecord::kNumFields) + missing);
  }
  return OxtsRecord::FromArray(values);
}

std::string FormatOxtsLine(const OxtsRecord& record) {
  const auto values = record.ToArray();
  std::string out;
  out.reserve(30 * 24);
  char buf[40];
  for (int i = 0; i < OxtsRecord::kNumFields; ++i) {
    if (i >= kFirstIntegerField) {
      std::snprintf(buf, sizeof(buf), "%lld", static_cast<long long>(values[i]));
    } else {
      std::snprintf(buf, sizeof(buf), "%.17g", values[i]);
    }
    if (i > 0) out += ' ';
    out += buf;
  }
  return out;
}

GnssFixType OxtsFixType(const OxtsRecord& record) {
  if (record.navstat != kOxtsNavstatLocked) return GnssFixType::kNone;
  switch (static_cast<OxtsGnssMode>(record.posmode)) {
    case OxtsGnssMode::kDoppler:
    case OxtsGnssMode::kSps: return GnssFixType::kSingle;
    case OxtsGnssMode::kDifferential:
    case OxtsGnssMode::kWaas:
    case OxtsGnssMode::kOmnistarVbs: return GnssFixType::kDifferential;
    case OxtsGnssMode::kRtkFloat:
    case OxtsGnssMode::kOmnistarHp: return GnssFixType::kRtkFloat;
    case OxtsGnssMode::kRtkInteger: return GnssFixType::kRtkFixed;
    default: return GnssFixType::kNone;
  }
}

GnssFix ToGnssFix(const OxtsRecord& record, Timestamp stamp) {
  GnssFix fix;
  fix.stamp = stamp;
  fix.latitude_deg = record.lat_deg;
  fix.longitude_deg = record.lon_deg;
  fix.height_m = record.alt_m;
  fix.sigma_horizontal_m = record.pos_accuracy_m;
  fix.sigma_vertical_m = 1.5 * record.pos_accuracy_m;
  fix.type = OxtsFixType(record);
  fix.num_satellites = record.numsats;
  return fix;
}

ImuSample ToImuSample(const OxtsRecord& record, Timestamp stamp) {
  ImuSample s;
  s.stamp = stamp;
  s.accel_mps2 = Eigen::Vector3d(record.ax, record.ay, record.az);
  s.gyro_radps = Eigen::Vector3d(record.wx, record.wy, record.wz);
  return s;
}

Eigen::Matrix3d OxtsAttitude(const OxtsRecord& record) {
  return (Eigen::AngleAxisd(record.yaw_rad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(record.pitch_rad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(record.roll_rad, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d OxtsVelocityEnu(const OxtsRecord& record) {
  return Eigen::Vector3d(record.ve, record.vn, record.vu);
}

void SetOxtsAttitude(const Eigen::Matrix3d& R, OxtsRecord* record) {
  // R = Rz(yaw) Ry(pitch) Rx(roll): R(2,0) = -sin(pitch), R(2,1) = cos(p) sin(r),
  // R(2,2) = cos(p) cos(r), R(1,0) = sin(y) cos(p), R(0,0) = cos(y) cos(p).
  record->pitch_rad = std::atan2(-R(2, 0), std::hypot(R(2, 1), R(2, 2)));
  record->roll_rad = std::atan2(R(2, 1), R(2, 2));
  record->yaw_rad = std::atan2(R(1, 0), R(0, 0));
}

const char* OxtsDataFormatText() {
  return "lat:   latitude of the oxts-unit (deg)\n"
         "lon:   longitude of the oxts-unit (deg)\n"
         "alt:   altitude of the oxts-unit (m)\n"
         "roll:  roll angle (rad),    0 = level, positive = left side up,      range: -pi   .. "
         "+pi\n"
         "pitch: pitch angle (rad),   0 = level, positive = front down,        range: -pi/2 .. "
         "+pi/2\n"
         "yaw:   heading (rad),       0 = east,  positive = counter clockwise, range: -pi   .. "
         "+pi\n"
         "vn:    velocity towards north (m/s)\n"
         "ve:    velocity towards east (m/s)\n"
         "vf:    forward velocity, i.e. parallel to earth-surface (m/s)\n"
         "vl:    leftward velocity, i.e. parallel to earth-surface (m/s)\n"
         "vu:    upward velocity, i.e. perpendicular to earth-surface (m/s)\n"
         "ax:    acceleration in x, i.e. in direction of vehicle front (m/s^2)\n"
         "ay:    acceleration in y, i.e. in direction of vehicle left (m/s^2)\n"
         "az:    acceleration in z, i.e. in direction of vehicle top (m/s^2)\n"
         "af:    forward acceleration (m/s^2)\n"
         "al:    leftward acceleration (m/s^2)\n"
         "au:    upward acceleration (m/s^2)\n"
         "wx:    angular rate around x (rad/s)\n"
         "wy:    angular rate around y (rad/s)\n"
         "wz:    angular rate around z (rad/s)\n"
         "wf:    angular rate around forward axis (rad/s)\n"
         "wl:    angular rate around leftward axis (rad/s)\n"
         "wu:    angular rate around upward axis (rad/s)\n"
         "pos_accuracy:  position accuracy (north/east in m)\n"
         "vel_accuracy:  velocity accuracy (north/east in m/s)\n"
         "navstat:       navigation status (see navstat_to_string)\n"
         "numsats:       number of satellites tracked by primary GPS receiver\n"
         "posmode:       position mode of primary GPS receiver (see gps_mode_to_string)\n"
         "velmode:       velocity mode of primary GPS receiver (see gps_mode_to_string)\n"
         "orimode:       orientation mode of primary GPS receiver (see gps_mode_to_string)\n";
}

}  // namespace slam_mms
