#pragma once
// Fast float approximations used to bound splats (never for exact geometry).
#include <cmath>

namespace slam_mms::internal {

constexpr float kPiF = 3.14159265358979f;

/// atan(x) for |x| <= 1, max error about 1e-5 rad.
inline float FastAtanUnit(float x) {
  const float x2 = x * x;
  return x *
         (0.99997726f +
          x2 * (-0.33262347f +
                x2 * (0.19354346f + x2 * (-0.11643287f + x2 * (0.05265332f + x2 * -0.01172120f)))));
}

/// atan2(y, x), max error about 1e-5 rad; 0 for (0, 0).
inline float FastAtan2(float y, float x) {
  const float ax = std::fabs(x);
  const float ay = std::fabs(y);
  const float mx = ax > ay ? ax : ay;
  if (mx == 0.0f) return 0.0f;
  const float mn = ax > ay ? ay : ax;
  float r = FastAtanUnit(mn / mx);
  if (ay > ax) r = 0.5f * kPiF - r;
  if (x < 0.0f) r = kPiF - r;
  return y < 0.0f ? -r : r;
}

/// FastAtan2 without branches (the same operations and result; selects instead of the early
/// return), for loops the compiler is to vectorise.
inline float FastAtan2Branchless(float y, float x) {
  const float ax = __builtin_fabsf(x);
  const float ay = __builtin_fabsf(y);
  const float mx = ax > ay ? ax : ay;
  const float mn = ax > ay ? ay : ax;
  float r = FastAtanUnit(mn / mx);
  r = ay > ax ? 0.5f * kPiF - r : r;
  r = x < 0.0f ? kPiF - r : r;
  r = y < 0.0f ? -r : r;
  return mx == 0.0f ? 0.0f : r;
}

}  // namespace slam_mms::internal
