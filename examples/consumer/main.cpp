// Links the installed slam_mms and uses a few public types; exits 0 on success.
#include <cstdio>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/version.hpp"

int main() {
  slam_mms::Vector6d xi;
  xi << 0.1, -0.2, 0.3, 1.0, 2.0, 3.0;
  const slam_mms::Vector6d back = slam_mms::se3::Log(slam_mms::se3::Exp(xi));
  const slam_mms::Status status = slam_mms::OkStatus();
  std::printf("slam_mms %s: round trip error %.3g, status %s\n", SLAM_MMS_VERSION_STRING,
              (back - xi).norm(), status.ToString().c_str());
  return (back - xi).norm() < 1e-9 && status.ok() ? 0 : 1;
}
