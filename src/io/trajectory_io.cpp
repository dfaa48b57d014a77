#include "slam_mms/io/trajectory_io.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "io/file_util.hpp"
#include "io/parsers.hpp"

namespace slam_mms {

namespace fs = std::filesystem;
using io_internal::FormatDouble;
using io_internal::IsBlank;
using io_internal::ParseDouble;
using io_internal::ReadLines;
using io_internal::SplitWhitespace;

namespace {

std::string Where(const std::string& file, size_t line_index) {
  return file + ":" + std::to_string(line_index + 1);
}

// Rotation from a quaternion read from a file; rejects non-unit quaternions beyond rounding.
StatusOr<Eigen::Matrix3d> QuaternionToRotation(double qx, double qy, double qz, double qw,
                                               const std::string& where) {
  const double n = std::sqrt(qx * qx + qy * qy + qz * qz + qw * qw);
  if (!(std::abs(n - 1.0) < 1e-3)) {
    return DataLossError(where + ": quaternion (qx qy qz qw) has norm " + std::to_string(n) +
                         ", expected 1");
  }
  return Eigen::Quaterniond(qw / n, qx / n, qy / n, qz / n).toRotationMatrix();
}

// Parses `tokens[k]` as a finite double or returns the error naming the field.
Status ParseField(const std::vector<std::string>& tokens, size_t k, const char* name,
                  const std::string& where, double* value) {
  if (!ParseDouble(tokens[k], value)) {
    return DataLossError(where + ": field " + std::to_string(k + 1) + " (" + name + ") '" +
                         tokens[k] + "' is not a finite number");
  }
  return OkStatus();
}

std::string PoseQuaternionText(const Eigen::Isometry3d& T, char sep) {
  Eigen::Quaterniond q(T.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;  // canonical sign
  const Eigen::Vector3d& t = T.translation();
  std::string s;
  const double v[7] = {t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
  for (double x : v) {
    s += sep;
    s += FormatDouble(x);
  }
  return s;
}

// Splits a CSV line on commas (no quoting: the files hold numbers only).
std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    const size_t comma = line.find(',', start);
    std::string f =
        line.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    while (!f.empty() && std::isspace(static_cast<unsigned char>(f.back()))) f.pop_back();
    size_t b = 0;
    while (b < f.size() && std::isspace(static_cast<unsigned char>(f[b]))) ++b;
    out.push_back(f.substr(b));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return out;
}

}  // namespace

// Largest whole number of seconds whose nanoseconds (with any fraction) fit in int64.
constexpr int64_t kMaxWholeSeconds = 9223372035;

// ------------------------------------------------------------------------------------------------
StatusOr<Timestamp> ParseSecondsExact(const std::string& text) {
  const auto fail = [&](const char* why) {
    return InvalidArgumentError("bad time in seconds '" + text + "': " + why);
  };
  size_t pos = 0;
  bool negative = false;
  if (pos < text.size() && (text[pos] == '-' || text[pos] == '+')) negative = text[pos++] == '-';
  int64_t whole = 0;
  int whole_digits = 0;
  while (pos < text.size() && std::isdigit(static_cast<unsigned char>(text[pos]))) {
    if (whole_digits >= 11) return fail("too many integer digits");
    whole = whole * 10 + (text[pos++] - '0');
    ++whole_digits;
  }
  int64_t frac = 0;
  int frac_digits = 0;
  if (pos < text.size() && text[pos] == '.') {
    ++pos;
    while (pos < text.size() && std::isdigit(static_cast<unsigned char>(text[pos]))) {
      if (frac_digits == 9) return fail("more than 9 fraction digits");
      frac = frac * 10 + (text[pos++] - '0');
      ++frac_digits;
    }
  }
  if (pos != text.size()) return fail("not a plain decimal number");
  if (whole_digits + frac_digits == 0) return fail("no digits");
  // int64 nanoseconds: |t| < 9223372036.854775807 s.
  if (whole > kMaxWholeSeconds) return fail("out of the int64 nanosecond range");
  for (int i = frac_digits; i < 9; ++i) frac *= 10;
  const int64_t ns = whole * 1000000000LL + frac;
  return Timestamp::FromNanoseconds(negative ? -ns : ns);
}

std::string FormatSecondsExact(Timestamp stamp) {
  const int64_t ns = stamp.nanoseconds();
  const bool negative = ns < 0;
  // Magnitude without overflow for any realistic stamp.
  const uint64_t mag = negative ? static_cast<uint64_t>(-(ns + 1)) + 1 : static_cast<uint64_t>(ns);
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%s%llu.%09llu", negative ? "-" : "",
                static_cast<unsigned long long>(mag / 1000000000ULL),
                static_cast<unsigned long long>(mag % 1000000000ULL));
  return buf;
}

namespace {
// TUM stamps from other tools may have more than 9 digits or an exponent: exact where possible,
// else rounded to the nearest nanosecond through double.
StatusOr<Timestamp> ParseTumTime(const std::string& token) {
  auto exact = ParseSecondsExact(token);
  if (exact.ok()) return exact;
  double s = 0.0;
  if (!ParseDouble(token, &s)) return exact.status();
  if (std::abs(s) > static_cast<double>(kMaxWholeSeconds)) {
    return InvalidArgumentError("time in seconds '" + token +
                                "' out of the int64 nanosecond range");
  }
  return Timestamp::FromSeconds(s);
}
}  // namespace

// ------------------------------------------------------------------------------------------------
Status WriteTrajectoryTum(const Trajectory& trajectory, const fs::path& file) {
  std::string text;
  text.reserve(trajectory.size() * 160);
  for (const StampedPose& p : trajectory.poses()) {
    text += FormatSecondsExact(p.stamp);
    text += PoseQuaternionText(p.T_world_body, ' ');
    text += '\n';
  }
  return io_internal::WriteFileBytes(file, text);
}

StatusOr<Trajectory> ReadTrajectoryTum(const fs::path& file) {
  SLAM_MMS_ASSIGN_OR_RETURN(const auto lines, ReadLines(file));
  return io_internal::ParseTrajectoryTumLines(lines, file.string());
}

StatusOr<Trajectory> io_internal::ParseTrajectoryTumLines(const std::vector<std::string>& lines,
                                                          const std::string& file) {
  static constexpr const char* kNames[8] = {"t", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  Trajectory trajectory;
  for (size_t l = 0; l < lines.size(); ++l) {
    if (IsBlank(lines[l]) || lines[l].find_first_not_of(" \t") == lines[l].find('#')) continue;
    const std::string where = Where(file, l);
    const auto tokens = SplitWhitespace(lines[l]);
    if (tokens.size() != 8) {
      return DataLossError(where + ": TUM line has " + std::to_string(tokens.size()) +
                           " fields, expected 8 (t tx ty tz qx qy qz qw)");
    }
    auto stamp = ParseTumTime(tokens[0]);
    if (!stamp.ok()) return DataLossError(where + ": field 1 (t): " + stamp.status().message());
    double v[8];
    for (size_t k = 1; k < 8; ++k) {
      SLAM_MMS_RETURN_IF_ERROR(ParseField(tokens, k, kNames[k], where, &v[k]));
    }
    StampedPose pose;
    pose.stamp = *stamp;
    SLAM_MMS_ASSIGN_OR_RETURN(pose.T_world_body.linear(),
                              QuaternionToRotation(v[4], v[5], v[6], v[7], where));
    pose.T_world_body.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    const Status added = trajectory.Add(pose);
    if (!added.ok()) return DataLossError(where + ": " + added.message());
  }
  return trajectory;
}

// ------------------------------------------------------------------------------------------------
Status WriteTrajectoryKitti(const Trajectory& trajectory, const fs::path& file) {
  std::string text;
  text.reserve(trajectory.size() * 250);
  for (const StampedPose& p : trajectory.poses()) {
    const Eigen::Matrix<double, 3, 4> m = p.T_world_body.matrix().topRows<3>();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) {
        if (r + c > 0) text += ' ';
        text += FormatDouble(m(r, c));
      }
    }
    text += '\n';
  }
  return io_internal::WriteFileBytes(file, text);
}

StatusOr<std::vector<Eigen::Isometry3d>> ReadPosesKitti(const fs::path& file) {
  SLAM_MMS_ASSIGN_OR_RETURN(const auto lines, ReadLines(file));
  return io_internal::ParsePosesKittiLines(lines, file.string());
}

StatusOr<std::vector<Eigen::Isometry3d>> io_internal::ParsePosesKittiLines(
    const std::vector<std::string>& lines, const std::string& file) {
  static constexpr const char* kNames[12] = {"r00", "r01", "r02", "tx",  "r10", "r11",
                                             "r12", "ty",  "r20", "r21", "r22", "tz"};
  std::vector<Eigen::Isometry3d> poses;
  for (size_t l = 0; l < lines.size(); ++l) {
    if (IsBlank(lines[l])) continue;
    const std::string where = Where(file, l);
    const auto tokens = SplitWhitespace(lines[l]);
    if (tokens.size() != 12) {
      return DataLossError(where + ": KITTI pose line has " + std::to_string(tokens.size()) +
                           " numbers, expected 12 (3x4 row-major)");
    }
    Eigen::Matrix<double, 3, 4> m;
    for (size_t k = 0; k < 12; ++k) {
      SLAM_MMS_RETURN_IF_ERROR(ParseField(tokens, k, kNames[k], where, &m(k / 4, k % 4)));
    }
    const Eigen::Matrix3d R = m.leftCols<3>();
    const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (err > 1e-3 || R.determinant() < 0.0) {
      return DataLossError(where + ": rotation part is not a rotation (max |R^T R - I| = " +
                           std::to_string(err) + ")");
    }
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    // Re-orthonormalise (files often carry 6-9 digits).
    T.linear() = Eigen::Quaterniond(R).normalized().toRotationMatrix();
    T.translation() = m.col(3);
    poses.push_back(T);
  }
  return poses;
}

StatusOr<Trajectory> ReadTrajectoryKitti(const fs::path& file,
                                         const std::vector<Timestamp>& stamps) {
  SLAM_MMS_ASSIGN_OR_RETURN(const auto poses, ReadPosesKitti(file));
  if (poses.size() != stamps.size()) {
    return InvalidArgumentError(file.string() + ": " + std::to_string(poses.size()) +
                                " poses but " + std::to_string(stamps.size()) + " stamps given");
  }
  Trajectory trajectory;
  for (size_t i = 0; i < poses.size(); ++i) {
    SLAM_MMS_RETURN_IF_ERROR(trajectory.Add(stamps[i], poses[i]));
  }
  return trajectory;
}

// ------------------------------------------------------------------------------------------------
namespace {
constexpr const char* kCsvPoseFields[8] = {"stamp_ns", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};

std::string CsvHeader() {
  std::string h;
  for (int k = 0; k < 8; ++k) h += std::string(k ? "," : "") + kCsvPoseFields[k];
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) h += ",c" + std::to_string(r) + std::to_string(c);
  }
  return h;
}
}  // namespace

Status WriteTrajectoryCsv(const Trajectory& trajectory, const fs::path& file) {
  std::string text = CsvHeader() + "\n";
  for (const StampedPose& p : trajectory.poses()) {
    text += std::to_string(p.stamp.nanoseconds());
    text += PoseQuaternionText(p.T_world_body, ',');
    for (int k = 0; k < 36; ++k) {
      text += ',';
      if (p.cov_T_world_body) text += FormatDouble((*p.cov_T_world_body)(k / 6, k % 6));
    }
    text += '\n';
  }
  return io_internal::WriteFileBytes(file, text);
}

StatusOr<Trajectory> ReadTrajectoryCsv(const fs::path& file) {
  SLAM_MMS_ASSIGN_OR_RETURN(const auto lines, ReadLines(file));
  return io_internal::ParseTrajectoryCsvLines(lines, file.string());
}

StatusOr<Trajectory> io_internal::ParseTrajectoryCsvLines(const std::vector<std::string>& lines,
                                                          const std::string& file) {
  Trajectory trajectory;
  bool header_seen = false;
  for (size_t l = 0; l < lines.size(); ++l) {
    if (IsBlank(lines[l])) continue;
    const std::string where = Where(file, l);
    const auto f = SplitCsv(lines[l]);
    if (!header_seen) {
      if (f.empty() || f[0] != "stamp_ns") {
        return DataLossError(where + ": expected the header line starting with 'stamp_ns'");
      }
      if (f.size() != 44) {
        return DataLossError(where + ": header has " + std::to_string(f.size()) +
                             " columns, expected 44");
      }
      header_seen = true;
      continue;
    }
    if (f.size() != 44) {
      return DataLossError(where + ": CSV line has " + std::to_string(f.size()) +
                           " fields, expected 44 (stamp_ns, 7 pose, 36 covariance)");
    }
    char* end = nullptr;
    const long long ns = std::strtoll(f[0].c_str(), &end, 10);
    if (f[0].empty() || end != f[0].c_str() + f[0].size()) {
      return DataLossError(where + ": field 1 (stamp_ns) '" + f[0] + "' is not an integer");
    }
    double v[8];
    for (size_t k = 1; k < 8; ++k) {
      SLAM_MMS_RETURN_IF_ERROR(ParseField(f, k, kCsvPoseFields[k], where, &v[k]));
    }
    StampedPose pose;
    pose.stamp = Timestamp::FromNanoseconds(ns);
    SLAM_MMS_ASSIGN_OR_RETURN(pose.T_world_body.linear(),
                              QuaternionToRotation(v[4], v[5], v[6], v[7], where));
    pose.T_world_body.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    size_t empty = 0;
    for (size_t k = 8; k < 44; ++k) empty += f[k].empty() ? 1 : 0;
    if (empty != 0 && empty != 36) {
      return DataLossError(where + ": covariance has " + std::to_string(36 - empty) +
                           " of 36 fields; give all or none");
    }
    if (empty == 0) {
      Eigen::Matrix<double, 6, 6> cov;
      for (size_t k = 0; k < 36; ++k) {
        const std::string name = "c" + std::to_string(k / 6) + std::to_string(k % 6);
        SLAM_MMS_RETURN_IF_ERROR(ParseField(f, 8 + k, name.c_str(), where, &cov(k / 6, k % 6)));
      }
      pose.cov_T_world_body = cov;
    }
    const Status added = trajectory.Add(pose);
    if (!added.ok()) return DataLossError(where + ": " + added.message());
  }
  if (!header_seen) return DataLossError(file + ": empty CSV file (no header line)");
  return trajectory;
}

}  // namespace slam_mms
