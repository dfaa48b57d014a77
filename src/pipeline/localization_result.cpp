#include "slam_mms/pipeline/localization_result.hpp"

#include <string>

namespace slam_mms {

const char* MappingModeName(MappingMode mode) {
  switch (mode) {
    case MappingMode::kFull: return "full";
    case MappingMode::kGnssIns: return "gnss_ins";
    case MappingMode::kLidarOnly: return "lidar_only";
    case MappingMode::kGnssInsSmoothed: return "gnss_ins_smoothed";
  }
  return "?";
}

bool ParseMappingMode(const std::string& name, MappingMode* mode) {
  for (MappingMode m : {MappingMode::kFull, MappingMode::kGnssIns, MappingMode::kLidarOnly,
                        MappingMode::kGnssInsSmoothed}) {
    if (name == MappingModeName(m)) {
      *mode = m;
      return true;
    }
  }
  return false;
}

const char* MotionFactorTypeName(MotionFactorType type) {
  switch (type) {
    case MotionFactorType::kNone: return "none";
    case MotionFactorType::kOdometry: return "odometry";
    case MotionFactorType::kPreintegration: return "preintegration";
    case MotionFactorType::kConstantVelocity: return "constant_velocity";
    case MotionFactorType::kPos: return "pos";
  }
  return "?";
}

const std::array<const char*, StageTimings::kNumStages>& StageTimings::Names() {
  static const std::array<const char*, kNumStages> names = {
      "deskew", "predict", "render", "register", "factors", "optimize", "integrate"};
  return names;
}

}  // namespace slam_mms
