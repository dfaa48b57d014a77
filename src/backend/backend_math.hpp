#pragma once
// Private helpers of the backend module: input validation (so that nothing invalid reaches Ceres,
// whose CHECKs abort the host) and square-root information matrices.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <cmath>
#include <string>

#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/status.hpp"

namespace slam_mms::backend_internal {

/// OK when every entry of `m` is finite.
template <typename Derived>
bool AllFinite(const Eigen::MatrixBase<Derived>& m) {
  return m.allFinite();
}

/// Finite, symmetric (relative 1e-9) and positive definite (smallest eigenvalue > 0 relative to
/// the largest by 1e-15, and > 0 absolutely).
template <int N>
Status ValidateCovariance(const Eigen::Matrix<double, N, N>& cov, const std::string& what) {
  if (!cov.allFinite()) return InvalidArgumentError(what + ": covariance has a NaN or Inf entry");
  const double scale = cov.cwiseAbs().maxCoeff();
  if (scale <= 0.0) return InvalidArgumentError(what + ": covariance is zero");
  if ((cov - cov.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) {
    return InvalidArgumentError(what + ": covariance is not symmetric");
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, N, N>> es(cov);
  const double min_ev = es.eigenvalues().minCoeff();
  const double max_ev = es.eigenvalues().maxCoeff();
  if (!(min_ev > 0.0) || min_ev < 1e-15 * max_ev) {
    return InvalidArgumentError(what +
                                ": covariance is not positive definite (smallest eigenvalue " +
                                std::to_string(min_ev) + ")");
  }
  return OkStatus();
}

/// Upper-triangular S with S^T S = cov^-1 (cov already validated).
template <int N>
Eigen::Matrix<double, N, N> SqrtInformation(const Eigen::Matrix<double, N, N>& cov) {
  using Mat = Eigen::Matrix<double, N, N>;
  const Mat sym = 0.5 * (cov + cov.transpose());
  Mat info = sym.llt().solve(Mat::Identity());
  info = 0.5 * (info + info.transpose());
  const Mat L = info.llt().matrixL();  // info = L L^T
  return L.transpose();
}

/// Finite translation and a rotation with |R^T R - I| < 1e-6 and det > 0.
inline Status ValidatePose(const Eigen::Isometry3d& T, const std::string& what) {
  if (!T.matrix().allFinite()) return InvalidArgumentError(what + ": pose has a NaN or Inf entry");
  const Eigen::Matrix3d R = T.linear();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
      R.determinant() <= 0.0) {
    return InvalidArgumentError(what + ": rotation is not orthonormal");
  }
  return OkStatus();
}

/// The error of T against T_ref in the factors' convention: [Log(R_ref^T R); R_ref^T (p - p_ref)].
inline Vector6d PoseError(const Eigen::Isometry3d& T_ref, const Eigen::Isometry3d& T) {
  Vector6d e;
  e.head<3>() = so3::Log(Eigen::Matrix3d(T_ref.linear().transpose() * T.linear()));
  e.tail<3>() = T_ref.linear().transpose() * (T.translation() - T_ref.translation());
  return e;
}

/// Covariance of a pose block in the Ceres tangent of PoseManifold ([dt_world, d_half_left]) to the
/// library convention (rotation first, right perturbation) at rotation R:
///   omega = R^T * 2 d,  v = R^T dt.
inline Matrix6d CeresTangentCovarianceToLibrary(const Matrix6d& cov_ceres,
                                                const Eigen::Matrix3d& R) {
  Matrix6d A = Matrix6d::Zero();
  A.block<3, 3>(0, 3) = 2.0 * R.transpose();
  A.block<3, 3>(3, 0) = R.transpose();
  return A * cov_ceres * A.transpose();
}

}  // namespace slam_mms::backend_internal
