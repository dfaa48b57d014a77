// libFuzzer target: a trajectory file's bytes -> poses, as ReadTrajectoryTum / ReadPosesKitti /
// ReadTrajectoryCsv read them (the first byte picks the format); parsed poses must be finite rigid
// transforms with strictly increasing stamps.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "io/file_util.hpp"
#include "io/parsers.hpp"

namespace {
bool IsRigid(const Eigen::Isometry3d& T) {
  const Eigen::Matrix3d R = T.linear();
  return T.matrix().allFinite() &&
         (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-9;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace slam_mms;
  if (size == 0) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data + 1), size - 1);
  const auto lines = io_internal::SplitLines(bytes);
  switch (data[0] % 3) {
    case 0:
    case 2: {
      auto t = data[0] % 3 == 0 ? io_internal::ParseTrajectoryTumLines(lines, "fuzz.tum")
                                : io_internal::ParseTrajectoryCsvLines(lines, "fuzz.csv");
      if (!t.ok()) return 0;
      for (size_t i = 0; i < t->size(); ++i) {
        if (!IsRigid(t->poses()[i].T_world_body)) __builtin_trap();
        if (i > 0 && !(t->poses()[i - 1].stamp < t->poses()[i].stamp)) __builtin_trap();
      }
      break;
    }
    case 1: {
      auto poses = io_internal::ParsePosesKittiLines(lines, "fuzz.txt");
      if (!poses.ok()) return 0;
      for (const auto& T : *poses) {
        if (!IsRigid(T)) __builtin_trap();
      }
      break;
    }
  }
  return 0;
}
