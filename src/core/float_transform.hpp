#pragma once
// FloatTransform: a rotation and translation as twelve floats, applied with the operation order
// of Eigen's Matrix3f * Vector3f (+ Vector3f): row . x as r0 x + (r1 y + r2 z), then + t. Loops
// written with it in plain float arithmetic (which the compiler vectorises) give the same floats
// as the Eigen expressions they replace. Private to the library (src/core; not installed).

#include <Eigen/Core>

namespace slam_mms::internal {

struct FloatTransform {
  float r00, r01, r02, r10, r11, r12, r20, r21, r22;
  float tx, ty, tz;

  FloatTransform(const Eigen::Matrix3f& R, const Eigen::Vector3f& t)
      : r00(R(0, 0)),
        r01(R(0, 1)),
        r02(R(0, 2)),
        r10(R(1, 0)),
        r11(R(1, 1)),
        r12(R(1, 2)),
        r20(R(2, 0)),
        r21(R(2, 1)),
        r22(R(2, 2)),
        tx(t.x()),
        ty(t.y()),
        tz(t.z()) {}

  /// (ox, oy, oz) = R (x, y, z), as Eigen's R * x.
  void Rotate(float x, float y, float z, float* ox, float* oy, float* oz) const {
    *ox = r00 * x + (r01 * y + r02 * z);
    *oy = r10 * x + (r11 * y + r12 * z);
    *oz = r20 * x + (r21 * y + r22 * z);
  }
  /// (ox, oy, oz) = R (x, y, z) + t, as Eigen's R * x + t.
  void Apply(float x, float y, float z, float* ox, float* oy, float* oz) const {
    Rotate(x, y, z, ox, oy, oz);
    *ox += tx;
    *oy += ty;
    *oz += tz;
  }
};

}  // namespace slam_mms::internal
