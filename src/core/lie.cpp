#include "slam_mms/core/lie.hpp"

#include <algorithm>
#include <cmath>

namespace slam_mms {
namespace so3 {

Eigen::Matrix3d Hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d W;
  W << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return W;
}

Eigen::Vector3d Vee(const Eigen::Matrix3d& W) { return {W(2, 1), W(0, 2), W(1, 0)}; }

Eigen::Matrix3d Exp(const Eigen::Vector3d& w) { return ExpQuaternion(w).toRotationMatrix(); }

Eigen::Quaterniond ExpQuaternion(const Eigen::Vector3d& w) {
  const double theta2 = w.squaredNorm();
  const double theta = std::sqrt(theta2);
  double real;
  double imag_factor;
  if (theta < 1e-8) {
    real = 1.0 - theta2 / 8.0;
    imag_factor = 0.5 - theta2 / 48.0;
  } else {
    real = std::cos(0.5 * theta);
    imag_factor = std::sin(0.5 * theta) / theta;
  }
  Eigen::Quaterniond q(real, imag_factor * w.x(), imag_factor * w.y(), imag_factor * w.z());
  q.normalize();
  return q;
}

Eigen::Vector3d Log(const Eigen::Quaterniond& q_in) {
  Eigen::Quaterniond q = q_in.normalized();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();  // angle in [0, pi]
  const double sin_half = q.vec().norm();
  const double cos_half = q.w();
  if (sin_half < 1e-10) {
    // theta ~ 2 * sin_half; w = 2 * vec / cos_half * (1 - ...) to second order.
    return (2.0 / cos_half) * q.vec();
  }
  const double theta = 2.0 * std::atan2(sin_half, cos_half);
  return (theta / sin_half) * q.vec();
}

Eigen::Vector3d Log(const Eigen::Matrix3d& R) { return Log(Eigen::Quaterniond(R)); }

Eigen::Matrix3d RightJacobian(const Eigen::Vector3d& w) { return LeftJacobian(-w); }

Eigen::Matrix3d RightJacobianInverse(const Eigen::Vector3d& w) { return LeftJacobianInverse(-w); }

Eigen::Matrix3d LeftJacobian(const Eigen::Vector3d& w) {
  const double theta2 = w.squaredNorm();
  const Eigen::Matrix3d W = Hat(w);
  if (theta2 < 1e-10) {
    return Eigen::Matrix3d::Identity() + 0.5 * W + (1.0 / 6.0) * W * W;
  }
  const double theta = std::sqrt(theta2);
  const double a = (1.0 - std::cos(theta)) / theta2;
  const double b = (theta - std::sin(theta)) / (theta2 * theta);
  return Eigen::Matrix3d::Identity() + a * W + b * W * W;
}

Eigen::Matrix3d LeftJacobianInverse(const Eigen::Vector3d& w) {
  const double theta2 = w.squaredNorm();
  const Eigen::Matrix3d W = Hat(w);
  if (theta2 < 1e-10) {
    return Eigen::Matrix3d::Identity() - 0.5 * W + (1.0 / 12.0) * W * W;
  }
  const double theta = std::sqrt(theta2);
  const double half = 0.5 * theta;
  const double c = (1.0 - half * std::cos(half) / std::sin(half)) / theta2;
  return Eigen::Matrix3d::Identity() - 0.5 * W + c * W * W;
}

}  // namespace so3

namespace se3 {
namespace {
// Barfoot's Q(rho, phi) block of the SE(3) left Jacobian.
Eigen::Matrix3d QMatrix(const Eigen::Vector3d& phi, const Eigen::Vector3d& rho) {
  const Eigen::Matrix3d P = so3::Hat(phi);
  const Eigen::Matrix3d Rh = so3::Hat(rho);
  const double theta2 = phi.squaredNorm();
  double c1;
  double c2;
  double c3;
  if (theta2 < 1e-8) {
    c1 = 1.0 / 6.0 - theta2 / 120.0;
    c2 = 1.0 / 24.0 - theta2 / 720.0;
    c3 = 1.0 / 120.0 - theta2 / 2520.0;
  } else {
    const double theta = std::sqrt(theta2);
    const double s = std::sin(theta);
    const double c = std::cos(theta);
    c1 = (theta - s) / (theta2 * theta);
    c2 = (theta2 + 2.0 * c - 2.0) / (2.0 * theta2 * theta2);
    c3 = (2.0 * theta - 3.0 * s + theta * c) / (2.0 * theta2 * theta2 * theta);
  }
  const Eigen::Matrix3d PR = P * Rh;
  const Eigen::Matrix3d RP = Rh * P;
  const Eigen::Matrix3d PRP = PR * P;
  return 0.5 * Rh + c1 * (PR + RP + PRP) + c2 * (P * PR + RP * P - 3.0 * PRP) +
         c3 * (PRP * P + P * PRP);
}
}  // namespace

Eigen::Isometry3d Exp(const Vector6d& xi) {
  const Eigen::Vector3d w = xi.head<3>();
  const Eigen::Vector3d v = xi.tail<3>();
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = so3::Exp(w);
  T.translation() = so3::LeftJacobian(w) * v;
  return T;
}

Vector6d Log(const Eigen::Isometry3d& T) {
  Vector6d xi;
  const Eigen::Vector3d w = so3::Log(Eigen::Matrix3d(T.linear()));
  xi.head<3>() = w;
  xi.tail<3>() = so3::LeftJacobianInverse(w) * T.translation();
  return xi;
}

Matrix6d Adjoint(const Eigen::Isometry3d& T) {
  Matrix6d A = Matrix6d::Zero();
  const Eigen::Matrix3d R = T.linear();
  A.block<3, 3>(0, 0) = R;
  A.block<3, 3>(3, 3) = R;
  A.block<3, 3>(3, 0) = so3::Hat(T.translation()) * R;
  return A;
}

Matrix6d LeftJacobian(const Vector6d& xi) {
  const Eigen::Vector3d w = xi.head<3>();
  const Eigen::Vector3d v = xi.tail<3>();
  Matrix6d J = Matrix6d::Zero();
  const Eigen::Matrix3d Jl = so3::LeftJacobian(w);
  J.block<3, 3>(0, 0) = Jl;
  J.block<3, 3>(3, 3) = Jl;
  J.block<3, 3>(3, 0) = QMatrix(w, v);
  return J;
}

Matrix6d RightJacobian(const Vector6d& xi) { return LeftJacobian(-xi); }

Matrix6d RightJacobianInverse(const Vector6d& xi) {
  const Eigen::Vector3d w = -xi.head<3>();
  const Eigen::Vector3d v = -xi.tail<3>();
  const Eigen::Matrix3d Jinv = so3::LeftJacobianInverse(w);
  Matrix6d J = Matrix6d::Zero();
  J.block<3, 3>(0, 0) = Jinv;
  J.block<3, 3>(3, 3) = Jinv;
  J.block<3, 3>(3, 0) = -Jinv * QMatrix(w, v) * Jinv;
  return J;
}

}  // namespace se3

Eigen::Isometry3d MakeIsometry(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

Eigen::Isometry3d MakeIsometry(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) {
  return MakeIsometry(q.normalized().toRotationMatrix(), t);
}

Eigen::Isometry3d Orthonormalized(const Eigen::Isometry3d& T) {
  return MakeIsometry(Eigen::Quaterniond(T.linear()).normalized(), T.translation());
}

Eigen::Isometry3d InterpolatePose(const Eigen::Isometry3d& T_a, const Eigen::Isometry3d& T_b,
                                  double alpha) {
  const Eigen::Matrix3d R_a = T_a.linear();
  const Eigen::Vector3d dw = so3::Log(Eigen::Matrix3d(R_a.transpose() * T_b.linear()));
  const Eigen::Matrix3d R = R_a * so3::Exp(alpha * dw);
  const Eigen::Vector3d t = T_a.translation() + alpha * (T_b.translation() - T_a.translation());
  return MakeIsometry(R, t);
}

Eigen::Vector3d RollPitchYaw(const Eigen::Matrix3d& R) {
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  const double roll = std::atan2(R(2, 1), R(2, 2));
  const double yaw = std::atan2(R(1, 0), R(0, 0));
  return {roll, pitch, yaw};
}

Eigen::Matrix3d FromRollPitchYaw(double roll, double pitch, double yaw) {
  return (Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

double RotationAngle(const Eigen::Matrix3d& R) { return so3::Log(R).norm(); }

}  // namespace slam_mms
