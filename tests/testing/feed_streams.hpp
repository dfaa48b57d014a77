#pragma once
// Test helper: feeds IMU samples and GNSS fixes to a MappingSystem (or anything with AddImu and
// AddGnss) merged in time order, as a host delivering sensor streams would.
#include <cstddef>
#include <vector>

#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms::testing {

/// Feeds imu[*i_imu..] and gnss[*i_gnss..] with stamps <= t, merged in time order (IMU first on a
/// tie), and advances the cursors.
template <typename System>
Status FeedStreamsUpTo(System* system, const std::vector<ImuSample>& imu,
                       const std::vector<GnssFix>& gnss, Timestamp t, size_t* i_imu,
                       size_t* i_gnss) {
  for (;;) {
    const bool imu_next = *i_imu < imu.size() && imu[*i_imu].stamp <= t;
    const bool gnss_next = *i_gnss < gnss.size() && gnss[*i_gnss].stamp <= t;
    if (!imu_next && !gnss_next) return OkStatus();
    if (imu_next && (!gnss_next || imu[*i_imu].stamp <= gnss[*i_gnss].stamp)) {
      SLAM_MMS_RETURN_IF_ERROR(system->AddImu(imu[(*i_imu)++]));
    } else {
      SLAM_MMS_RETURN_IF_ERROR(system->AddGnss(gnss[(*i_gnss)++]));
    }
  }
}

}  // namespace slam_mms::testing
