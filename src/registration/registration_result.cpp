#include "slam_mms/registration/registration_result.hpp"

namespace slam_mms {

const char* IcpTerminationName(IcpTermination termination) {
  switch (termination) {
    case IcpTermination::kConverged: return "CONVERGED";
    case IcpTermination::kMaxIterations: return "MAX_ITERATIONS";
    case IcpTermination::kTooFewCorrespondences: return "TOO_FEW_CORRESPONDENCES";
    case IcpTermination::kDegenerate: return "DEGENERATE";
  }
  return "UNKNOWN";
}

}  // namespace slam_mms
