#pragma once
// SO(3) and SE(3) maps and Jacobians. Conventions (ARCHITECTURE.md): tangent vectors are rotation
// first, xi = [omega; v]; perturbations are on the right, T = T_hat * Exp(delta); Exp/Log of SE(3)
// are the exact group maps (with the V matrix), so Exp(Log(T)) == T.
//
// Thread safety: pure functions.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace slam_mms {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

namespace so3 {
/// Skew-symmetric matrix: Hat(a) * b == a.cross(b).
Eigen::Matrix3d Hat(const Eigen::Vector3d& w);
Eigen::Vector3d Vee(const Eigen::Matrix3d& W);
/// Rodrigues' formula, accurate near zero.
Eigen::Matrix3d Exp(const Eigen::Vector3d& w);
Eigen::Quaterniond ExpQuaternion(const Eigen::Vector3d& w);
/// The rotation vector of R, angle in [0, pi]; accurate near 0 and pi.
Eigen::Vector3d Log(const Eigen::Matrix3d& R);
Eigen::Vector3d Log(const Eigen::Quaterniond& q);
/// Right Jacobian: Exp(w + dw) ~= Exp(w) * Exp(Jr(w) dw).
Eigen::Matrix3d RightJacobian(const Eigen::Vector3d& w);
Eigen::Matrix3d RightJacobianInverse(const Eigen::Vector3d& w);
/// Left Jacobian: Exp(w + dw) ~= Exp(Jl(w) dw) * Exp(w).
Eigen::Matrix3d LeftJacobian(const Eigen::Vector3d& w);
Eigen::Matrix3d LeftJacobianInverse(const Eigen::Vector3d& w);
}  // namespace so3

namespace se3 {
/// Exact exponential of xi = [omega; v].
Eigen::Isometry3d Exp(const Vector6d& xi);
/// Exact logarithm, xi = [omega; v].
Vector6d Log(const Eigen::Isometry3d& T);
/// Adjoint (rotation-first): Exp(Ad(T) xi) == T Exp(xi) T^-1.
Matrix6d Adjoint(const Eigen::Isometry3d& T);
/// Right Jacobian: Exp(xi + d) ~= Exp(xi) * Exp(Jr(xi) d).
Matrix6d RightJacobian(const Vector6d& xi);
Matrix6d RightJacobianInverse(const Vector6d& xi);
Matrix6d LeftJacobian(const Vector6d& xi);
}  // namespace se3

/// Isometry from rotation and translation.
Eigen::Isometry3d MakeIsometry(const Eigen::Matrix3d& R, const Eigen::Vector3d& t);
Eigen::Isometry3d MakeIsometry(const Eigen::Quaterniond& q, const Eigen::Vector3d& t);

/// Re-orthonormalises the rotation part (numerical drift after long products).
Eigen::Isometry3d Orthonormalized(const Eigen::Isometry3d& T);

/// Pose at fraction `alpha` between T_a (alpha 0) and T_b (alpha 1): rotation by slerp, translation
/// linear. The physical model for a vehicle between two nearby samples. alpha outside [0, 1]
/// extrapolates.
Eigen::Isometry3d InterpolatePose(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b,
                                  double alpha);

/// Roll, pitch, yaw [rad] of R = Rz(yaw) Ry(pitch) Rx(roll) (the KITTI/OXTS convention).
Eigen::Vector3d RollPitchYaw(const Eigen::Matrix3d& R);
Eigen::Matrix3d FromRollPitchYaw(double roll, double pitch, double yaw);

/// Rotation angle of R [rad], in [0, pi].
double RotationAngle(const Eigen::Matrix3d& R);

}  // namespace slam_mms
