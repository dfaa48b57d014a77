#include "backend/marginalization.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <map>
#include <string>

#include "slam_mms/core/lie.hpp"

namespace slam_mms::backend_internal {

namespace {

using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// x [-] x_lin in the Ceres tangent, and its Jacobian (tangent x ambient) with respect to x.
void MinusAndJacobian(const LinearizedBlock& b, const double* x, double* delta, RowMatrix* J) {
  if (!b.is_pose) {
    for (int i = 0; i < b.ambient_size; ++i) delta[i] = x[i] - b.x_lin[static_cast<size_t>(i)];
    if (J != nullptr) J->setIdentity(b.tangent_size, b.ambient_size);
    return;
  }
  for (int i = 0; i < 3; ++i) delta[i] = x[i] - b.x_lin[static_cast<size_t>(i)];
  const Eigen::Quaterniond q_raw(Eigen::Map<const Eigen::Quaterniond>(x + 3));
  const double n = q_raw.norm();
  const Eigen::Quaterniond q = q_raw.normalized();
  const Eigen::Quaterniond q_lin =
      Eigen::Quaterniond(Eigen::Map<const Eigen::Quaterniond>(b.x_lin.data() + 3)).normalized();
  // Ceres EigenQuaternionManifold: q = [cos|d|, sin|d| d/|d|] * q_lin, i.e. R = Exp(2 d) R_lin.
  const Eigen::Vector3d phi = so3::Log(Eigen::Matrix3d((q * q_lin.conjugate()).toRotationMatrix()));
  Eigen::Map<Eigen::Vector3d>(delta + 3) = 0.5 * phi;
  if (J == nullptr) return;
  J->setZero(6, 7);
  J->block<3, 3>(0, 0).setIdentity();
  // d(0.5 Log(R R_lin^T)) / dq = Jl^-1(phi) [q_w I + Hat(q_v), -q_v] / |q|.
  Eigen::Matrix<double, 3, 4> N;
  N.leftCols<3>() = q.w() * Eigen::Matrix3d::Identity() + so3::Hat(q.vec());
  N.col(3) = -q.vec();
  J->block<3, 4>(3, 3) = so3::LeftJacobianInverse(phi) * N / n;
}

}  // namespace

MarginalPriorFactor::MarginalPriorFactor(std::vector<LinearizedBlock> blocks, Eigen::MatrixXd S,
                                         Eigen::VectorXd e0)
    : blocks_(std::move(blocks)), S_(std::move(S)), e0_(std::move(e0)) {
  for (const auto& b : blocks_) mutable_parameter_block_sizes()->push_back(b.ambient_size);
  set_num_residuals(static_cast<int>(S_.rows()));
}

std::vector<double*> MarginalPriorFactor::parameter_pointers() const {
  std::vector<double*> p;
  for (const auto& b : blocks_) p.push_back(b.param);
  return p;
}

bool MarginalPriorFactor::Evaluate(double const* const* parameters, double* residuals,
                                   double** jacobians) const {
  const int n = static_cast<int>(S_.cols());
  Eigen::VectorXd dx(n);
  std::vector<RowMatrix> J(blocks_.size());
  int offset = 0;
  for (size_t k = 0; k < blocks_.size(); ++k) {
    const bool want = jacobians != nullptr && jacobians[k] != nullptr;
    MinusAndJacobian(blocks_[k], parameters[k], dx.data() + offset, want ? &J[k] : nullptr);
    offset += blocks_[k].tangent_size;
  }
  if (!dx.allFinite()) return false;
  Eigen::Map<Eigen::VectorXd>(residuals, S_.rows()) = S_ * dx + e0_;
  if (jacobians == nullptr) return true;
  offset = 0;
  for (size_t k = 0; k < blocks_.size(); ++k) {
    if (jacobians[k] != nullptr) {
      Eigen::Map<RowMatrix>(jacobians[k], S_.rows(), blocks_[k].ambient_size) =
          S_.middleCols(offset, blocks_[k].tangent_size) * J[k];
    }
    offset += blocks_[k].tangent_size;
  }
  return true;
}

StatusOr<std::unique_ptr<MarginalPriorFactor>> MarginalizeBlocks(
    const ceres::Problem& problem, const std::vector<ceres::ResidualBlockId>& residual_blocks,
    const std::set<double*>& removed, double eigen_threshold) {
  // Tangent layout: removed blocks first, then kept blocks, in first-seen order.
  std::vector<double*> order_removed, order_kept;
  std::map<double*, int> seen;
  for (auto* rb : residual_blocks) {
    std::vector<double*> params;
    problem.GetParameterBlocksForResidualBlock(rb, &params);
    for (double* p : params) {
      if (seen.count(p) != 0 || problem.IsParameterBlockConstant(p)) continue;
      seen[p] = 0;
      (removed.count(p) != 0 ? order_removed : order_kept).push_back(p);
    }
  }
  if (order_kept.empty()) return std::unique_ptr<MarginalPriorFactor>();
  std::map<double*, int> offset;
  int m = 0;
  for (double* p : order_removed) {
    offset[p] = m;
    m += problem.ParameterBlockTangentSize(p);
  }
  int k = 0;
  for (double* p : order_kept) {
    offset[p] = m + k;
    k += problem.ParameterBlockTangentSize(p);
  }
  const int n = m + k;
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(n);
  for (auto* rb : residual_blocks) {
    std::vector<double*> params;
    problem.GetParameterBlocksForResidualBlock(rb, &params);
    const int rows = problem.GetCostFunctionForResidualBlock(rb)->num_residuals();
    std::vector<RowMatrix> jac(params.size());
    std::vector<double*> jac_ptrs(params.size(), nullptr);
    for (size_t i = 0; i < params.size(); ++i) {
      if (problem.IsParameterBlockConstant(params[i])) continue;
      jac[i].resize(rows, problem.ParameterBlockTangentSize(params[i]));
      jac_ptrs[i] = jac[i].data();
    }
    Eigen::VectorXd r(rows);
    double cost = 0.0;
    if (!problem.EvaluateResidualBlock(rb, /*apply_loss_function=*/true, &cost, r.data(),
                                       jac_ptrs.data())) {
      return InternalError("marginalization: a factor could not be evaluated");
    }
    if (!r.allFinite()) return InternalError("marginalization: a factor evaluated to NaN");
    for (size_t i = 0; i < params.size(); ++i) {
      if (jac_ptrs[i] == nullptr) continue;
      const int oi = offset.at(params[i]);
      const int si = static_cast<int>(jac[i].cols());
      g.segment(oi, si) += jac[i].transpose() * r;
      for (size_t j = 0; j < params.size(); ++j) {
        if (jac_ptrs[j] == nullptr) continue;
        const int oj = offset.at(params[j]);
        H.block(oi, oj, si, jac[j].cols()) += jac[i].transpose() * jac[j];
      }
    }
  }
  if (!H.allFinite() || !g.allFinite()) return InternalError("marginalization: NaN in H or b");

  // Schur complement with a pseudo-inverse of H_mm (directions the factors leave unobserved).
  Eigen::MatrixXd Hs = H.bottomRightCorner(k, k);
  Eigen::VectorXd gs = g.tail(k);
  if (m > 0) {
    const Eigen::MatrixXd Hmm = 0.5 * (H.topLeftCorner(m, m) + H.topLeftCorner(m, m).transpose());
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Hmm);
    const double max_ev = std::max(es.eigenvalues().maxCoeff(), 0.0);
    Eigen::VectorXd inv_ev = Eigen::VectorXd::Zero(m);
    for (int i = 0; i < m; ++i) {
      const double ev = es.eigenvalues()[i];
      if (ev > std::max(eigen_threshold * max_ev, 1e-300)) inv_ev[i] = 1.0 / ev;
    }
    const Eigen::MatrixXd Hmm_pinv =
        es.eigenvectors() * inv_ev.asDiagonal() * es.eigenvectors().transpose();
    const Eigen::MatrixXd Hkm = H.bottomLeftCorner(k, m);
    Hs -= Hkm * Hmm_pinv * Hkm.transpose();
    gs -= Hkm * Hmm_pinv * g.head(m);
  }
  Hs = 0.5 * (Hs + Hs.transpose());
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(Hs);
  const double max_ev = std::max(es.eigenvalues().maxCoeff(), 0.0);
  Eigen::VectorXd sqrt_ev = Eigen::VectorXd::Zero(k), inv_sqrt_ev = Eigen::VectorXd::Zero(k);
  for (int i = 0; i < k; ++i) {
    const double ev = es.eigenvalues()[i];
    if (ev > std::max(eigen_threshold * max_ev, 1e-300)) {
      sqrt_ev[i] = std::sqrt(ev);
      inv_sqrt_ev[i] = 1.0 / sqrt_ev[i];
    }
  }
  // H* = V L V^T = S^T S with S = sqrt(L) V^T; S^T e0 = b*  <=  e0 = sqrt(L)^-1 V^T b*.
  Eigen::MatrixXd S = sqrt_ev.asDiagonal() * es.eigenvectors().transpose();
  Eigen::VectorXd e0 = inv_sqrt_ev.asDiagonal() * (es.eigenvectors().transpose() * gs);
  if (!S.allFinite() || !e0.allFinite()) return InternalError("marginalization: NaN prior");

  std::vector<LinearizedBlock> blocks;
  for (double* p : order_kept) {
    LinearizedBlock b;
    b.param = p;
    b.ambient_size = problem.ParameterBlockSize(p);
    b.tangent_size = problem.ParameterBlockTangentSize(p);
    b.is_pose = problem.GetManifold(p) != nullptr;
    if (b.is_pose && (b.ambient_size != 7 || b.tangent_size != 6)) {
      return InternalError("marginalization: a block with a manifold is not a pose block");
    }
    b.x_lin.assign(p, p + b.ambient_size);
    blocks.push_back(std::move(b));
  }
  return std::make_unique<MarginalPriorFactor>(std::move(blocks), std::move(S), std::move(e0));
}

}  // namespace slam_mms::backend_internal
