#pragma once
// The Ceres parameter-block conventions shared by every module that builds Ceres problems (ins,
// backend, pipeline). BINDING for all modules:
//   pose block     double[7] = [tx, ty, tz, qx, qy, qz, qw]   (T_world_body; the last four are in
//                  Eigen::Quaterniond memory order, so Eigen::Map<Eigen::Quaterniond>(x + 3) works)
//   manifold       ceres::ProductManifold<ceres::EuclideanManifold<3>,
//   ceres::EigenQuaternionManifold>
//                  (tangent [dt(3), d(3)]: translation perturbed additively in world; rotation
//                  perturbed on the LEFT in world with Ceres's half-angle tangent,
//                  q = [cos|d|, sin|d| d/|d|] * q_hat, i.e. R = Exp(2 d) * R_hat. Solvers never see
//                  this: cost functions work on the ambient block, and covariances of the solver's
//                  tangent must be converted before being reported in the library's
//                  right-perturbed, rotation-first convention.)
//   velocity block double[3] = v_world [m/s]
//   bias block     double[6] = [ba(3) m/s^2, bg(3) rad/s]
// Cost functions return Jacobians with respect to the ambient 7-vector; Ceres chains them with the
// manifold's PlusJacobian.
//
// Thread safety: pure functions.

#include <ceres/manifold.h>
#include <ceres/product_manifold.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <memory>

namespace slam_mms {

inline constexpr int kPoseBlockSize = 7;
inline constexpr int kPoseTangentSize = 6;
inline constexpr int kVelocityBlockSize = 3;
inline constexpr int kBiasBlockSize = 6;

using PoseManifold =
    ceres::ProductManifold<ceres::EuclideanManifold<3>, ceres::EigenQuaternionManifold>;
using PoseBlock = std::array<double, kPoseBlockSize>;

/// A new pose manifold; hand it to Problem::SetManifold (the problem takes ownership by default).
inline ceres::Manifold* NewPoseManifold() {
  return new PoseManifold(ceres::EuclideanManifold<3>(), ceres::EigenQuaternionManifold());
}

/// Writes T into x[0..6] = [t, q(xyzw)], the quaternion normalised.
inline void PoseToBlock(const Eigen::Isometry3d& T, double* x) {
  Eigen::Quaterniond q(T.linear());
  q.normalize();
  x[0] = T.translation().x();
  x[1] = T.translation().y();
  x[2] = T.translation().z();
  x[3] = q.x();
  x[4] = q.y();
  x[5] = q.z();
  x[6] = q.w();
}

inline PoseBlock PoseToBlock(const Eigen::Isometry3d& T) {
  PoseBlock b;
  PoseToBlock(T, b.data());
  return b;
}

/// Reads x[0..6] = [t, q(xyzw)] into an isometry (the quaternion is normalised on the way).
inline Eigen::Isometry3d PoseFromBlock(const double* x) {
  Eigen::Quaterniond q(Eigen::Map<const Eigen::Quaterniond>(x + 3));
  q.normalize();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.toRotationMatrix();
  T.translation() = Eigen::Map<const Eigen::Vector3d>(x);
  return T;
}

inline Eigen::Isometry3d PoseFromBlock(const PoseBlock& b) { return PoseFromBlock(b.data()); }

/// d(delta_theta)/d(q_ambient), 3x4, at the unit quaternion q, for the RIGHT rotation perturbation
/// R = R_hat * Exp(delta_theta) (the library's convention): delta_theta ~= 2 vec(q_hat^-1 * q').
/// A cost function that has its Jacobian J_theta (rows x 3) with respect to delta_theta returns
/// J_theta * QuaternionRightTangentToAmbient(q) as the Jacobian with respect to the 4 quaternion
/// numbers [qx, qy, qz, qw] (divided by |q| when the cost reads the normalised quaternion of a
/// non-unit block); Ceres then multiplies by the manifold's PlusJacobian.
inline Eigen::Matrix<double, 3, 4> QuaternionRightTangentToAmbient(const Eigen::Quaterniond& q) {
  Eigen::Matrix<double, 3, 4> J;
  const Eigen::Vector3d v = q.vec();
  Eigen::Matrix3d v_hat;
  v_hat << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  J.leftCols<3>() = 2.0 * (q.w() * Eigen::Matrix3d::Identity() - v_hat);
  J.col(3) = -2.0 * v;
  return J;
}

}  // namespace slam_mms
