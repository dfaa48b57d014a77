// libFuzzer target: a calib_imu_to_velo.txt file's bytes -> T_lidar_body, as
// ReadKittiRigidCalibration reads it; a parsed calibration must be a finite rigid transform.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/file_util.hpp"
#include "io/parsers.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slam_mms;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  auto T = io_internal::ParseKittiRigidCalibrationLines(io_internal::SplitLines(bytes),
                                                        "calib_imu_to_velo.txt");
  if (!T.ok()) return 0;
  const Eigen::Matrix3d R = T->linear();
  if (!T->matrix().allFinite()) __builtin_trap();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-9) {
    __builtin_trap();
  }
  return 0;
}
