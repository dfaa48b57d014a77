// libFuzzer target: the same bytes as each CSV file of a drive folder (scans.csv, imu.csv,
// gnss.csv, initial_state.csv, pos.csv), parsed as FolderDriveReader does (one CsvTable helper);
// parsed streams must be strictly increasing and finite.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/drive_folder_parsers.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slam_mms;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  std::vector<std::string> sources;
  if (auto scans = io_internal::ParseScansCsv(bytes, "scans.csv"); scans.ok()) {
    for (size_t i = 0; i < scans->size(); ++i) {
      if ((*scans)[i].end <= (*scans)[i].start) __builtin_trap();
      if (i > 0 && (*scans)[i].start <= (*scans)[i - 1].start) __builtin_trap();
    }
  }
  std::vector<ImuSample> imu;
  if (io_internal::ParseImuCsv(bytes, "imu.csv", &imu, &sources).ok()) {
    for (size_t i = 0; i < imu.size(); ++i) {
      if (!imu[i].accel_mps2.allFinite() || !imu[i].gyro_radps.allFinite()) __builtin_trap();
      if (i > 0 && imu[i].stamp <= imu[i - 1].stamp) __builtin_trap();
    }
    if (sources.size() != imu.size()) __builtin_trap();
  }
  std::vector<GnssFix> gnss;
  if (io_internal::ParseGnssCsv(bytes, "gnss.csv", &gnss, &sources).ok()) {
    for (const GnssFix& f : gnss) {
      if (!std::isfinite(f.sigma_horizontal_m) || std::abs(f.latitude_deg) > 90.0) {
        __builtin_trap();
      }
    }
  }
  std::optional<InsState> state;
  std::string source;
  std::optional<Eigen::Vector3d> sigma_rpy_rad;
  if (io_internal::ParseInitialStateCsv(bytes, "initial_state.csv", &state, &source, &sigma_rpy_rad)
          .ok()) {
    if (state && !state->T_world_body.matrix().allFinite()) __builtin_trap();
    if (sigma_rpy_rad && !(sigma_rpy_rad->array() > 0.0).all()) __builtin_trap();
  }
  std::vector<PosRecord> pos;
  if (io_internal::ParsePosCsv(bytes, "pos.csv", &pos, &sources).ok()) {
    for (const PosRecord& p : pos) {
      if (!p.R_enu_body.allFinite()) __builtin_trap();
    }
  }
  return 0;
}
