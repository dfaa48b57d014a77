#include "slam_mms/io/extrinsics_yaml.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <vector>

#include "io/file_util.hpp"
#include "io/yaml_util.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {
namespace {

constexpr double kRotationTolerance = 1e-6;

using io_internal::YamlWhere;

// A sequence of exactly `n` finite numbers under `key`.
Status Numbers(const YAML::Node& node, const std::string& key, size_t n, const std::string& file,
               std::vector<double>* values) {
  const std::string where = YamlWhere(file, node) + ": " + key;
  if (!node.IsSequence()) {
    return DataLossError(where + " must be a sequence of " + std::to_string(n) + " numbers");
  }
  if (node.size() != n) {
    return DataLossError(where + " has " + std::to_string(node.size()) + " numbers, expected " +
                         std::to_string(n));
  }
  values->clear();
  for (size_t k = 0; k < n; ++k) {
    double d = 0.0;
    SLAM_MMS_RETURN_IF_ERROR(
        io_internal::YamlFiniteNumber(node[k], where + "[" + std::to_string(k) + "]", "", &d));
    values->push_back(d);
  }
  return OkStatus();
}

Status RotationCheck(const Eigen::Matrix3d& R, const std::string& where) {
  const double err = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  const double det = R.determinant();
  if (!(err <= kRotationTolerance) || !(det > 0.0)) {
    return DataLossError(
        where + ": the rotation part is not a rotation (max |R^T R - I| = " + std::to_string(err) +
        ", det = " + std::to_string(det) + "; must be orthonormal within 1e-6 with det +1)");
  }
  return OkStatus();
}

StatusOr<Eigen::Isometry3d> ParseTransform(const YAML::Node& node, const std::string& file) {
  const std::string where = YamlWhere(file, node) + ": T_body_lidar";
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  std::vector<double> v;
  if (node.IsSequence()) {
    SLAM_MMS_RETURN_IF_ERROR(Numbers(node, "T_body_lidar", 16, file, &v));
    Eigen::Matrix4d M;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) M(r, c) = v[static_cast<size_t>(4 * r + c)];
    }
    if (M(3, 0) != 0.0 || M(3, 1) != 0.0 || M(3, 2) != 0.0 || M(3, 3) != 1.0) {
      return DataLossError(where + ": last row is " + std::to_string(M(3, 0)) + " " +
                           std::to_string(M(3, 1)) + " " + std::to_string(M(3, 2)) + " " +
                           std::to_string(M(3, 3)) + ", must be 0 0 0 1");
    }
    SLAM_MMS_RETURN_IF_ERROR(RotationCheck(M.topLeftCorner<3, 3>(), where));
    T.linear() = M.topLeftCorner<3, 3>();
    T.translation() = M.topRightCorner<3, 1>();
    return T;
  }
  if (node.IsMap()) {
    for (const auto& kv : node) {
      const std::string k = kv.first.as<std::string>();
      if (k != "xyz" && k != "rpy_deg") {
        return DataLossError(YamlWhere(file, kv.first) + ": T_body_lidar: unknown key '" + k +
                             "' (expected xyz and rpy_deg)");
      }
    }
    if (!node["xyz"] || !node["rpy_deg"]) {
      return DataLossError(where + " needs both xyz: [x, y, z] and rpy_deg: [roll, pitch, yaw]");
    }
    std::vector<double> rpy;
    SLAM_MMS_RETURN_IF_ERROR(Numbers(node["xyz"], "T_body_lidar.xyz", 3, file, &v));
    SLAM_MMS_RETURN_IF_ERROR(Numbers(node["rpy_deg"], "T_body_lidar.rpy_deg", 3, file, &rpy));
    constexpr double kDegToRad = M_PI / 180.0;
    T.linear() = FromRollPitchYaw(rpy[0] * kDegToRad, rpy[1] * kDegToRad, rpy[2] * kDegToRad);
    T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
    return T;
  }
  return DataLossError(where +
                       " must be 16 numbers [4x4 row-major] or {xyz: [...], rpy_deg: [...]}");
}

}  // namespace

StatusOr<DriveExtrinsics> ParseExtrinsicsYaml(const std::string& text, const std::string& file) {
  try {
    SLAM_MMS_ASSIGN_OR_RETURN(const YAML::Node root, io_internal::YamlOneDocument(text, file));
    if (!root.IsMap()) {
      return DataLossError(file + ": extrinsics must be a YAML map with key T_body_lidar");
    }
    DriveExtrinsics out;
    bool have_T = false;
    for (const auto& kv : root) {
      if (!kv.first.IsScalar()) {
        return DataLossError(YamlWhere(file, kv.first) + ": keys must be plain names");
      }
      const std::string key = kv.first.Scalar();
      if (key == "T_body_lidar") {
        SLAM_MMS_ASSIGN_OR_RETURN(out.T_body_lidar, ParseTransform(kv.second, file));
        have_T = true;
      } else if (key == "t_body_antenna_m") {
        std::vector<double> v;
        SLAM_MMS_RETURN_IF_ERROR(Numbers(kv.second, key, 3, file, &v));
        out.t_body_antenna_m = Eigen::Vector3d(v[0], v[1], v[2]);
      } else if (key == "lidar_time_offset_s") {
        SLAM_MMS_RETURN_IF_ERROR(io_internal::YamlFiniteNumber(
            kv.second, YamlWhere(file, kv.second) + ": " + key, " [s]", &out.lidar_time_offset_s));
      } else if (key == "imu_frame_is_vehicle_frame") {
        const std::string v = kv.second.IsScalar() ? kv.second.Scalar() : std::string();
        if (v != "true" && v != "false") {
          return DataLossError(YamlWhere(file, kv.first) + ": " + key +
                               " must be true or false, got '" + v + "'");
        }
        out.imu_frame_is_vehicle_frame = v == "true";
      } else {
        SLAM_MMS_LOG(kInfo) << YamlWhere(file, kv.first) << ": key '" << key << "' ignored";
      }
    }
    if (!have_T) return DataLossError(file + ": key T_body_lidar missing");
    return out;
  } catch (const YAML::Exception& e) {
    return DataLossError(file + ":" + std::to_string(e.mark.line + 1) + ": YAML error: " + e.msg);
  } catch (const std::exception& e) {
    return DataLossError(file + ": YAML error: " + e.what());
  }
}

StatusOr<DriveExtrinsics> ReadExtrinsicsYaml(const std::filesystem::path& file) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec)) {
    return NotFoundError("extrinsics file " + file.string() + " not found");
  }
  SLAM_MMS_ASSIGN_OR_RETURN(const std::string text, io_internal::ReadFileBytes(file));
  return ParseExtrinsicsYaml(text, file.string());
}

std::string FormatExtrinsicsYaml(const DriveExtrinsics& e) {
  using io_internal::FormatDouble;
  const Eigen::Matrix4d M = e.T_body_lidar.matrix();
  std::string s =
      "# slam_mms drive extrinsics. p_body = T_body_lidar * p_lidar (4x4 row-major);\n"
      "# t_body_antenna_m: GNSS antenna in the body frame [m].\nT_body_lidar: [";
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      s += (r == 3 ? (c == 3 ? "1" : "0") : FormatDouble(M(r, c)));
      if (r * 4 + c < 15) s += (c == 3 ? ",\n               " : ", ");
    }
  }
  s += "]\n";
  if (e.t_body_antenna_m) {
    const Eigen::Vector3d& a = *e.t_body_antenna_m;
    s += "t_body_antenna_m: [" + FormatDouble(a.x()) + ", " + FormatDouble(a.y()) + ", " +
         FormatDouble(a.z()) + "]\n";
  }
  if (e.lidar_time_offset_s != 0.0) {
    s += "# a LiDAR stamp s is the time s + lidar_time_offset_s on the IMU/GNSS clock [s].\n"
         "lidar_time_offset_s: " +
         FormatDouble(e.lidar_time_offset_s) + "\n";
  }
  if (e.imu_frame_is_vehicle_frame) {
    s += "# the body (IMU) frame is the vehicle's: x forward, y left, z up.\n"
         "imu_frame_is_vehicle_frame: ";
    s += *e.imu_frame_is_vehicle_frame ? "true\n" : "false\n";
  }
  return s;
}

Status WriteExtrinsicsYaml(const DriveExtrinsics& extrinsics, const std::filesystem::path& file) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  if (!out) return UnavailableError("cannot create " + file.string());
  out << FormatExtrinsicsYaml(extrinsics);
  out.close();
  if (!out) return UnavailableError("cannot write " + file.string());
  return OkStatus();
}

}  // namespace slam_mms
