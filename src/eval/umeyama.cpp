#include "slam_mms/eval/umeyama.hpp"

#include <Eigen/SVD>
#include <string>

namespace slam_mms::eval {

Eigen::Isometry3d SimilarityTransform::Rigid() const {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

StatusOr<SimilarityTransform> UmeyamaAlignment(const std::vector<Eigen::Vector3d>& src,
                                               const std::vector<Eigen::Vector3d>& dst,
                                               bool with_scale) {
  if (src.size() != dst.size()) {
    return InvalidArgumentError("UmeyamaAlignment: " + std::to_string(src.size()) +
                                " source points but " + std::to_string(dst.size()) +
                                " destination points; they must correspond one to one");
  }
  const size_t n = src.size();
  if (n < 3) {
    return InvalidArgumentError("UmeyamaAlignment: " + std::to_string(n) +
                                " point pairs; at least 3 are needed");
  }
  Eigen::Vector3d mu_src = Eigen::Vector3d::Zero();
  Eigen::Vector3d mu_dst = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < n; ++i) {
    if (!src[i].allFinite() || !dst[i].allFinite()) {
      return InvalidArgumentError("UmeyamaAlignment: point pair " + std::to_string(i) +
                                  " is not finite");
    }
    mu_src += src[i];
    mu_dst += dst[i];
  }
  mu_src /= static_cast<double>(n);
  mu_dst /= static_cast<double>(n);

  // Umeyama eqs (38)-(42): Sigma = 1/n sum (dst - mu_dst)(src - mu_src)^T.
  Eigen::Matrix3d sigma = Eigen::Matrix3d::Zero();
  double var_src = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d a = src[i] - mu_src;
    sigma += (dst[i] - mu_dst) * a.transpose();
    var_src += a.squaredNorm();
  }
  sigma /= static_cast<double>(n);
  var_src /= static_cast<double>(n);

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d d = svd.singularValues();
  // Rank < 2 (collinear or coincident points): the rotation about the line is free.
  if (!(d(0) > 0.0) || d(1) <= 1e-10 * d(0)) {
    return InvalidArgumentError(
        "UmeyamaAlignment: degenerate point configuration (points collinear or coincident); the "
        "rotation is not determined");
  }
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) S(2, 2) = -1.0;

  SimilarityTransform out;
  out.R = svd.matrixU() * S * svd.matrixV().transpose();
  out.scale = with_scale ? (d.asDiagonal() * S).trace() / var_src : 1.0;
  out.t = mu_dst - out.scale * out.R * mu_src;
  return out;
}

}  // namespace slam_mms::eval
