#include "slam_mms/core/sensor_data.hpp"

namespace slam_mms {

const char* GnssFixTypeName(GnssFixType type) {
  switch (type) {
    case GnssFixType::kNone: return "none";
    case GnssFixType::kSingle: return "single";
    case GnssFixType::kDifferential: return "differential";
    case GnssFixType::kRtkFloat: return "rtk_float";
    case GnssFixType::kRtkFixed: return "rtk_fixed";
  }
  return "?";
}

}  // namespace slam_mms
