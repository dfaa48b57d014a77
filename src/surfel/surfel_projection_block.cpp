#include "surfel/surfel_projection_block.hpp"

#include "core/float_transform.hpp"
#include "surfel/fast_math.hpp"

namespace slam_mms::internal {

void SurfelProjectionBlock::Project(const Surfel* surfels, const uint32_t* ids, int n,
                                    size_t remaining, const Eigen::Matrix3f& R,
                                    const Eigen::Vector3f& t, float min_r, float max_r,
                                    float fov_up, float rows_per_rad, float cols) {
  alignas(64) float x[kSize], y[kSize], z[kSize], mx[kSize], my[kSize], mz[kSize];
  constexpr size_t kPrefetch = 16;  // the active surfels are scattered over the slots
  for (int b = 0; b < n; ++b) {
    if (static_cast<size_t>(b) + kPrefetch < remaining) {
      __builtin_prefetch(&surfels[ids[b + static_cast<int>(kPrefetch)]], 1);
    }
    const Surfel& s = surfels[ids[b]];
    x[b] = s.position.x();
    y[b] = s.position.y();
    z[b] = s.position.z();
    mx[b] = s.normal.x();
    my[b] = s.normal.y();
    mz[b] = s.normal.z();
  }
  const FloatTransform T(R, t);
#pragma GCC ivdep
  for (int b = 0; b < n; ++b) {
    float qx, qy, qz, ux, uy, uz;
    T.Apply(x[b], y[b], z[b], &qx, &qy, &qz);
    T.Rotate(mx[b], my[b], mz[b], &ux, &uy, &uz);
    const float d = __builtin_sqrtf(qx * qx + (qy * qy + qz * qz));
    const bool facing = ux * qx + (uy * qy + uz * qz) < 0.0f;
    const float yaw = FastAtan2Branchless(qy, qx);
    const float pitch = FastAtan2Branchless(qz, __builtin_sqrtf(qx * qx + qy * qy));
    px[b] = qx;
    py[b] = qy;
    pz[b] = qz;
    nx[b] = ux;
    ny[b] = uy;
    nz[b] = uz;
    v[b] = (fov_up - pitch) * rows_per_rad;
    u[b] = 0.5f * (1.0f - yaw / kPiF) * cols;
    in_range[b] = static_cast<int32_t>((d >= min_r) & (d <= max_r) & facing);
  }
}

}  // namespace slam_mms::internal
