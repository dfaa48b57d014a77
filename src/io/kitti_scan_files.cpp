// KITTI's scan and calibration files: the .bin / .txt scan parsers, their conversion into a
// PointCloud (KittiPointsToCloud), ReadKittiScanFile and the rigid calibration files (split from
// kitti_raw_reader.cpp, which reads the drive folder).
#include <Eigen/SVD>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <optional>

#include "io/file_util.hpp"
#include "io/parsers.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/io/kitti_raw_reader.hpp"

namespace slam_mms {

namespace fs = std::filesystem;
using io_internal::ReadLines;

Status io_internal::ReadKittiRawScan(const fs::path& file, std::vector<float>* xyzr) {
  xyzr->clear();
  if (file.extension() == ".bin") {
    SLAM_MMS_ASSIGN_OR_RETURN(const std::string bytes, io_internal::ReadFileBytes(file));
    return io_internal::ParseKittiBinScan(bytes, file.string(), xyzr);
  }
  if (file.extension() == ".txt") {
    SLAM_MMS_ASSIGN_OR_RETURN(const auto lines, ReadLines(file));
    return io_internal::ParseKittiTextScan(lines, file.string(), xyzr);
  }
  return InvalidArgumentError(file.string() + ": unknown scan file extension (.bin or .txt)");
}

Status io_internal::ParseKittiBinScan(std::string_view bytes, const std::string& file,
                                      std::vector<float>* xyzr) {
  static_assert(sizeof(float) == 4, "float32 required");
  xyzr->clear();
  if (bytes.size() % 16 != 0) {
    return DataLossError(file + ": size " + std::to_string(bytes.size()) +
                         " bytes is not a multiple of 16 (float32 x y z reflectance per point)");
  }
  xyzr->resize(bytes.size() / 4);
  if (!bytes.empty()) std::memcpy(xyzr->data(), bytes.data(), bytes.size());
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__
  for (float& f : *xyzr) {
    uint32_t u;
    std::memcpy(&u, &f, 4);
    u = __builtin_bswap32(u);
    std::memcpy(&f, &u, 4);
  }
#endif
  return OkStatus();
}

Status io_internal::ParseKittiTextScan(const std::vector<std::string>& lines,
                                       const std::string& file, std::vector<float>* xyzr) {
  xyzr->clear();
  xyzr->reserve(4 * lines.size());
  for (size_t l = 0; l < lines.size(); ++l) {
    if (IsBlank(lines[l])) continue;
    const char* p = lines[l].c_str();
    for (int f = 0; f < 4; ++f) {
      char* end = nullptr;
      const float v = std::strtof(p, &end);
      if (end == p) {
        static constexpr const char* kNames[4] = {"x", "y", "z", "reflectance"};
        return DataLossError(file + ":" + std::to_string(l + 1) + ": field " +
                             std::to_string(f + 1) + " (" + kNames[f] +
                             ") missing or not a number");
      }
      xyzr->push_back(v);
      p = end;
    }
    while (*p != '\0' && std::isspace(static_cast<unsigned char>(*p))) ++p;
    if (*p != '\0') {
      return DataLossError(file + ":" + std::to_string(l + 1) +
                           ": more than 4 numbers (x y z reflectance) on the line");
    }
  }
  return OkStatus();
}

size_t io_internal::KittiPointsToCloud(const std::vector<float>& xyzr,
                                       const KittiRawReader::Options& o, double duration_s,
                                       PointCloud* cloud,
                                       const std::vector<float>* time_offsets_s) {
  const size_t n = xyzr.size() / 4;
  const double angle = o.vertical_correction_deg * M_PI / 180.0;
  const double cos_a = std::cos(angle);
  const double sin_a = std::sin(angle);
  // Clockwise: t = 0.5 (1 - atan2(y, x)/pi); counter-clockwise: 0.5 (1 + atan2(y, x)/pi).
  const float time_sign = o.spin == SpinDirection::kClockwise ? -1.0f : 1.0f;
  const auto half_duration = static_cast<float>(0.5 * duration_s);
  constexpr auto kInvPi = static_cast<float>(1.0 / M_PI);
  cloud->resize(n);
  auto& out_pts = cloud->points();
  auto& out_refl = cloud->intensities();
  auto& out_time = cloud->time_offsets_s();
  size_t kept = 0;
  for (size_t k = 0; k < n; ++k) {
    const float* v = &xyzr[4 * k];
    if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2]) ||
        !std::isfinite(v[3]) ||
        (time_offsets_s != nullptr && !std::isfinite((*time_offsets_s)[k]))) {
      continue;
    }
    Eigen::Vector3f q(v[0], v[1], v[2]);
    if (o.vertical_angle_correction) {
      // Rotation by `angle` about k = (p x z)/|p x z| (KISS-ICP). k is orthogonal to p, so
      // Rodrigues reduces to p cos(a) + (k x p) sin(a), with k x p = (-x z, -y z, x^2 + y^2)/r.
      const double x = v[0], y = v[1], z = v[2];
      const double r = std::sqrt(x * x + y * y);
      if (r > 1e-9) {
        q = Eigen::Vector3d(x * cos_a - sin_a * x * z / r, y * cos_a - sin_a * y * z / r,
                            z * cos_a + sin_a * r)
                .cast<float>();
        if (!q.allFinite()) continue;  // |p| near FLT_MAX: the rotated point overflows float
      }
    }
    out_pts[kept] = q;
    out_refl[kept] = v[3];
    // Azimuth of the recorded point (the vertical correction keeps it).
    if (o.per_point_time && time_offsets_s != nullptr) {
      out_time[kept] = (*time_offsets_s)[k];
    } else if (o.per_point_time) {
      const float f = 1.0f + time_sign * std::atan2(v[1], v[0]) * kInvPi;  // [0, 2] up to rounding
      out_time[kept] = half_duration * std::min(2.0f, std::max(0.0f, f));
    } else {
      out_time[kept] = 0.0f;
    }
    ++kept;
  }
  cloud->resize(kept);
  return n - kept;
}

StatusOr<PointCloud> ReadKittiScanFile(const fs::path& file) {
  std::vector<float> xyzr;
  SLAM_MMS_RETURN_IF_ERROR(io_internal::ReadKittiRawScan(file, &xyzr));
  PointCloud cloud;
  const size_t n = xyzr.size() / 4;
  cloud.resize(n);
  for (size_t k = 0; k < n; ++k) {
    cloud.points()[k] = Eigen::Vector3f(xyzr[4 * k], xyzr[4 * k + 1], xyzr[4 * k + 2]);
    cloud.intensities()[k] = xyzr[4 * k + 3];
  }
  return cloud;
}

StatusOr<Eigen::Isometry3d> ReadKittiRigidCalibration(const fs::path& file) {
  std::error_code ec;
  if (!fs::exists(file, ec))
    return NotFoundError("calibration file " + file.string() + " not found");
  SLAM_MMS_ASSIGN_OR_RETURN(const auto lines, ReadLines(file));
  return io_internal::ParseKittiRigidCalibrationLines(lines, file.string());
}

StatusOr<Eigen::Isometry3d> io_internal::ParseKittiRigidCalibrationLines(
    const std::vector<std::string>& lines, const std::string& file) {
  std::optional<Eigen::Matrix3d> R;
  std::optional<Eigen::Vector3d> T;
  for (size_t l = 0; l < lines.size(); ++l) {
    const std::string& line = lines[l];
    const std::string where = file + ":" + std::to_string(l + 1);
    if (io_internal::IsBlank(line)) continue;
    const size_t colon = line.find(':');
    if (colon == std::string::npos) {
      return DataLossError(where + ": calibration line without 'key:'");
    }
    const std::string key = line.substr(0, colon);
    if (key != "R" && key != "T") continue;  // calib_time, delta_f, ...
    const auto tokens = io_internal::SplitWhitespace(line.substr(colon + 1));
    const size_t expected = key == "R" ? 9 : 3;
    if (tokens.size() != expected) {
      return DataLossError(where + ": key " + key + " has " + std::to_string(tokens.size()) +
                           " numbers, expected " + std::to_string(expected));
    }
    double v[9];
    for (size_t k = 0; k < expected; ++k) {
      if (!io_internal::ParseDouble(tokens[k], &v[k])) {
        return DataLossError(where + ": key " + key + " value " + std::to_string(k + 1) + " '" +
                             tokens[k] + "' is not a finite number");
      }
    }
    if (key == "R") {
      if (R) return DataLossError(where + ": key R given twice");
      Eigen::Matrix3d m;
      m << v[0], v[1], v[2], v[3], v[4], v[5], v[6], v[7], v[8];
      const double err = (m.transpose() * m - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
      if (err > 1e-4 || m.determinant() < 0.0) {
        return DataLossError(where +
                             ": key R is not a rotation (max |R^T R - I| = " + std::to_string(err) +
                             ", det = " + std::to_string(m.determinant()) + ")");
      }
      R = m;
    } else {
      if (T) return DataLossError(where + ": key T given twice");
      T = Eigen::Vector3d(v[0], v[1], v[2]);
    }
  }
  if (!R) return DataLossError(file + ": key R (9 numbers) missing");
  if (!T) return DataLossError(file + ": key T (3 numbers) missing");
  // The file carries 7 digits: project R onto SO(3) (changes entries by ~1e-7).
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(*R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Isometry3d iso = Eigen::Isometry3d::Identity();
  iso.linear() = svd.matrixU() * svd.matrixV().transpose();
  iso.translation() = *T;
  return iso;
}

}  // namespace slam_mms
