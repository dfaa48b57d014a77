#pragma once
// SubmapGraphFactor: one factor of the level-2 graph as it was added (SubmapGraph::Factors()), so
// that a finished drive's graph can be written out and rebuilt elsewhere (the multi-drive
// adjustment replays every drive's factors into one graph).
//
// Thread safety: value type.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

#include "slam_mms/backend/robust_loss.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms {

using SubmapId = int64_t;

enum class SubmapFactorKind {
  kRegistration,  ///< F_Reg: T_a_b from map-to-map registration (robust loss `loss`).
  kReckon,        ///< F_Reckon: T_a_b from the serial scan-to-map chain.
  kLoop,          ///< F_Loop: T_a_b of a verified loop (the graph's loop_loss).
  kPosePrior,     ///< A 6-DoF prior T_world_submap on submap a.
  kGnss,          ///< F_GNSS: p_world_antenna on submap a (3x3 covariance in the top-left block).
  /// Attitudes measured on submaps a and b with correlated errors (SubmapGraph::
  /// AddAttitudeChainFactor): R_world_b in T, R_world_a in T_a, the chain's covariance Q in the
  /// top-left 3x3 block (the rest zero), its transition A in `transition`.
  kAttitudeChain,
  /// A GNSS bias `gnss_bias` with a zero-mean prior (SubmapGraph::AddGnssBias), its covariance in
  /// the top-left 3x3 block [m^2]; no submap (a = b = -1).
  kGnssBias,
  /// A GNSS bias `gnss_bias` that follows bias `gnss_bias_from` (SubmapGraph::AddGnssBiasLink):
  /// b = phi b_from + w, phi on the diagonal of `transition`, Cov(w) in the top-left 3x3 block
  /// [m^2]; no submap (a = b = -1).
  kGnssBiasLink,
};

/// "registration", "reckon", "loop", "pose_prior", "gnss", "attitude_chain", "gnss_bias",
/// "gnss_bias_link".
const char* SubmapFactorKindName(SubmapFactorKind kind);
/// The kind of a name of SubmapFactorKindName; false where unknown.
bool SubmapFactorKindFromName(const char* name, SubmapFactorKind* kind);

struct SubmapGraphFactor {
  SubmapFactorKind kind = SubmapFactorKind::kReckon;
  SubmapId a = 0;  ///< The (older) submap; the only one of priors and GNSS factors.
  SubmapId b = 0;  ///< The newer submap of relative factors; unused by priors.
  /// T_a_b (relative factors) or T_world_submap (pose prior).
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  /// Rotation first (relative factors, pose prior); GNSS: the antenna position's 3x3 covariance
  /// in the top-left block [m^2], the rest zero.
  Matrix6d covariance = Matrix6d::Identity();
  RobustLoss loss;  ///< kRegistration: the loss it was added with.
  // kGnss only:
  Eigen::Vector3d p_world_antenna = Eigen::Vector3d::Zero();
  Eigen::Isometry3d T_submap_body = Eigen::Isometry3d::Identity();
  Eigen::Vector3d t_body_antenna = Eigen::Vector3d::Zero();
  /// kGnss: the GNSS bias (SubmapGraph::AddGnssBias) the fix shares, -1: none; kGnssBias,
  /// kGnssBiasLink: the bias added.
  int gnss_bias = -1;
  int gnss_bias_from = -1;  ///< kGnssBiasLink: the bias it follows.
  // kAttitudeChain only:
  Eigen::Isometry3d T_a = Eigen::Isometry3d::Identity();  ///< Its rotation: R_world_a measured.
  /// kAttitudeChain: A of eps_b = A eps_a + w; kGnssBiasLink: phi I.
  Eigen::Matrix3d transition = Eigen::Matrix3d::Zero();
};

}  // namespace slam_mms
