#include "slam_mms/backend/submap_graph.hpp"

#include <ceres/problem.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <array>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <utility>

#include "backend/attitude_chain_factor.hpp"
#include "backend/backend_math.hpp"
#include "backend/ceres_solve.hpp"
#include "backend/factor_fit.hpp"
#include "backend/gnss_position_factor.hpp"
#include "backend/pose_block.hpp"
#include "backend/pose_prior_factor.hpp"
#include "backend/relative_pose_factor.hpp"
#include "core/option_error.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {

using backend_internal::ValidateCovariance;
using backend_internal::ValidatePose;

namespace {

struct Sequential {  // A factor between consecutive submaps i -> i+1.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Identity();
  bool reckon = false;
};

struct Node {
  SubmapId id = 0;
  size_t index = 0;
  int num_gnss = 0;
  std::array<double, kPoseBlockSize> pose{};
  std::vector<SubmapScanPose> scans;
};

std::string Id(SubmapId id) { return std::to_string(id); }

Status Positive(const char* field, double v) {
  if (v > 0.0) return OkStatus();
  return internal::OptionError("SubmapGraph::Options", field, v, "must be > 0");
}

}  // namespace

const char* SolveTriggerName(SolveTrigger trigger) {
  switch (trigger) {
    case SolveTrigger::kGnssReturned: return "gnss_returned";
    case SolveTrigger::kLoopClosed: return "loop_closed";
    case SolveTrigger::kFinish: return "finish";
    case SolveTrigger::kRequested: return "requested";
  }
  return "unknown";
}

Status SubmapGraph::Options::Validate() const {
  SLAM_MMS_RETURN_IF_ERROR(Positive("max_iterations", max_iterations));
  SLAM_MMS_RETURN_IF_ERROR(Positive("max_solve_time_s", max_solve_time_s));
  SLAM_MMS_RETURN_IF_ERROR(Positive("num_threads", num_threads));
  SLAM_MMS_RETURN_IF_ERROR(Positive("function_tolerance", function_tolerance));
  SLAM_MMS_RETURN_IF_ERROR(Positive("active_submaps", active_submaps));
  SLAM_MMS_RETURN_IF_ERROR(Positive("loop_candidate_distance_m", loop_candidate_distance_m));
  SLAM_MMS_RETURN_IF_ERROR(Positive("loop_min_submap_gap", loop_min_submap_gap));
  SLAM_MMS_RETURN_IF_ERROR(loop_loss.Validate().WithContext("SubmapGraph::Options::loop_loss"));
  SLAM_MMS_RETURN_IF_ERROR(gnss_loss.Validate().WithContext("SubmapGraph::Options::gnss_loss"));
  return OkStatus();
}

struct SubmapGraph::Impl {
  Options options;
  std::unique_ptr<ceres::Problem> problem;
  std::map<SubmapId, std::unique_ptr<Node>> nodes;
  std::vector<Node*> ordered;  // By index (== id order).
  int num_loops = 0;
  int num_gnss = 0;
  int last_free = 0;
  std::optional<size_t> pending_loop_from;  // Oldest node index touched by loops since last solve.
  std::map<size_t, Sequential> sequential;  // Keyed by the index of the older node.
  std::map<int, std::unique_ptr<std::array<double, 3>>> gnss_biases;
  std::vector<SubmapGraphFactor> factors;  // As added (Factors()).
  /// The residual block of each factor (same order); last_block: the one added last.
  std::vector<ceres::ResidualBlockId> factor_blocks;
  ceres::ResidualBlockId last_block = nullptr;
  void PushFactor(const SubmapGraphFactor& f) {
    factors.push_back(f);
    factor_blocks.push_back(last_block);
  }

  void Record(SubmapFactorKind kind, SubmapId a, SubmapId b, const Eigen::Isometry3d& T,
              const Matrix6d& covariance, const RobustLoss& loss = RobustLoss::None()) {
    SubmapGraphFactor f;
    f.kind = kind;
    f.a = a;
    f.b = b;
    f.T = T;
    f.covariance = covariance;
    f.loss = loss;
    PushFactor(f);
  }
  /// A new GNSS bias block `key` (>= 0, not yet added), zero, in the problem; `*sqrt_info` the
  /// square-root information of `covariance` (validated), for the factor that states it.
  StatusOr<std::array<double, 3>*> NewGnssBias(int key, const Eigen::Matrix3d& covariance,
                                               const std::string& what,
                                               Eigen::Matrix3d* sqrt_info) {
    if (key < 0)
      return InvalidArgumentError(what + ": key " + std::to_string(key) + " must be >= 0");
    if (gnss_biases.count(key) != 0) {
      return InvalidArgumentError(what + ": bias " + std::to_string(key) + " exists");
    }
    SLAM_MMS_RETURN_IF_ERROR(ValidateCovariance<3>(covariance, what));
    *sqrt_info = covariance.llt().matrixL().solve(Eigen::Matrix3d::Identity());
    auto block = std::make_unique<std::array<double, 3>>();
    block->fill(0.0);
    problem->AddParameterBlock(block->data(), 3);
    return gnss_biases.emplace(key, std::move(block)).first->second.get();
  }
  void RecordGnssBias(SubmapFactorKind kind, int key, int from_key, double transition,
                      const Eigen::Matrix3d& covariance) {
    SubmapGraphFactor f;
    f.kind = kind;
    f.a = f.b = -1;
    f.gnss_bias = key;
    f.gnss_bias_from = from_key;
    f.transition = transition * Eigen::Matrix3d::Identity();
    f.covariance = Matrix6d::Zero();
    f.covariance.topLeftCorner<3, 3>() = covariance;
    PushFactor(f);
  }

  explicit Impl(const Options& o) : options(o) {
    ceres::Problem::Options po;
    po.enable_fast_removal = false;  // The graph only grows.
    problem = std::make_unique<ceres::Problem>(po);
  }

  Node* Find(SubmapId id) const {
    auto it = nodes.find(id);
    return it == nodes.end() ? nullptr : it->second.get();
  }

  StatusOr<std::pair<Node*, Node*>> Pair(SubmapId a, SubmapId b, const char* what) const {
    Node* na = Find(a);
    Node* nb = Find(b);
    if (na == nullptr || nb == nullptr) {
      return NotFoundError(std::string("SubmapGraph::") + what + ": unknown submap " +
                           Id(na == nullptr ? a : b));
    }
    if (a == b) return InvalidArgumentError(std::string("SubmapGraph::") + what + ": a == b");
    return std::make_pair(na, nb);
  }

  Status AddBetween(SubmapId a, SubmapId b, const Eigen::Isometry3d& T_a_b,
                    const Matrix6d& covariance, const RobustLoss& loss, const char* what) {
    SLAM_MMS_RETURN_IF_ERROR(loss.Validate());
    SLAM_MMS_ASSIGN_OR_RETURN(auto nodes_ab, Pair(a, b, what));
    SLAM_MMS_ASSIGN_OR_RETURN(auto cost, RelativePoseFactor::Create(T_a_b, covariance));
    last_block =
        problem->AddResidualBlock(cost.release(), loss.NewLossFunction(),
                                  nodes_ab.first->pose.data(), nodes_ab.second->pose.data());
    return OkStatus();
  }

  // Remembers a reckon/registration factor between consecutive submaps for the loop check
  // (a reckon factor wins over a registration one).
  void RecordSequential(SubmapId a, SubmapId b, const Eigen::Isometry3d& T_a_b,
                        const Matrix6d& covariance, bool reckon) {
    const size_t ia = Find(a)->index, ib = Find(b)->index;
    if (ib != ia + 1) return;
    auto it = sequential.find(ia);
    if (it != sequential.end() && it->second.reckon && !reckon) return;
    sequential[ia] = Sequential{T_a_b, covariance, reckon};
  }

  // T_a_b and its covariance composed from the sequential factors (right perturbation:
  // T = T1 T2 -> xi = Ad(T2^-1) xi1 + xi2; inverse T^-1 -> Sigma' = Ad(T) Sigma Ad(T)^T).
  std::optional<std::pair<Eigen::Isometry3d, Matrix6d>> Chain(size_t ia, size_t ib) const {
    const size_t lo = std::min(ia, ib), hi = std::max(ia, ib);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    Matrix6d C = Matrix6d::Zero();
    for (size_t i = lo; i < hi; ++i) {
      auto it = sequential.find(i);
      if (it == sequential.end()) return std::nullopt;
      const Matrix6d Ad = se3::Adjoint(it->second.T.inverse());
      C = Ad * C * Ad.transpose() + it->second.covariance;
      T = T * it->second.T;
    }
    if (ia > ib) {
      const Matrix6d Ad = se3::Adjoint(T);
      C = Ad * C * Ad.transpose();
      T = T.inverse();
    }
    return std::make_pair(T, C);
  }

  StatusOr<LoopCheck> Check(SubmapId a, SubmapId b, const Eigen::Isometry3d& T_a_b,
                            const Matrix6d& covariance) const {
    SLAM_MMS_ASSIGN_OR_RETURN(auto nodes_ab, Pair(a, b, "CheckLoop"));
    SLAM_MMS_RETURN_IF_ERROR(ValidatePose(T_a_b, "SubmapGraph loop T_a_b"));
    SLAM_MMS_RETURN_IF_ERROR(ValidateCovariance<6>(covariance, "SubmapGraph loop"));
    LoopCheck check;
    auto chain = Chain(nodes_ab.first->index, nodes_ab.second->index);
    if (!chain) return check;
    check.chain_available = true;
    check.T_a_b_chain = chain->first;
    check.chain_covariance = chain->second;
    const Matrix6d combined = covariance + chain->second;
    const Vector6d e = backend_internal::PoseError(chain->first, T_a_b);
    check.mahalanobis_sq = e.dot(combined.ldlt().solve(e));
    return check;
  }

  // The node index from which a bounded solve frees the graph.
  size_t FreeFrom(SolveTrigger trigger) const {
    const size_t n = ordered.size();
    if (trigger == SolveTrigger::kFinish) return 0;
    const size_t window = static_cast<size_t>(options.active_submaps);
    size_t from = n > window ? n - window : 0;
    if (pending_loop_from) from = std::min(from, *pending_loop_from);
    if (trigger == SolveTrigger::kGnssReturned) {
      // Walk back: the GNSS-anchored nodes after the outage, the outage, then the last
      // GNSS-anchored node before it.
      size_t i = n;
      while (i > 0 && ordered[i - 1]->num_gnss > 0) --i;
      while (i > 0 && ordered[i - 1]->num_gnss == 0) --i;
      from = std::min(from, i > 0 ? i - 1 : 0);
    }
    return from;
  }
};

SubmapGraph::SubmapGraph(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SubmapGraph::SubmapGraph(SubmapGraph&&) noexcept = default;
SubmapGraph& SubmapGraph::operator=(SubmapGraph&&) noexcept = default;
SubmapGraph::~SubmapGraph() = default;

StatusOr<SubmapGraph> SubmapGraph::Create(const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  return SubmapGraph(std::make_unique<Impl>(options));
}

StatusOr<SubmapGraph> SubmapGraph::Create() { return Create(Options()); }

Status SubmapGraph::AddSubmap(SubmapId id, const Eigen::Isometry3d& T_world_submap) {
  Impl& m = *impl_;
  if (!m.ordered.empty() && id <= m.ordered.back()->id) {
    return InvalidArgumentError("SubmapGraph::AddSubmap: id " + Id(id) +
                                " is not greater than the last id " + Id(m.ordered.back()->id));
  }
  SLAM_MMS_RETURN_IF_ERROR(ValidatePose(T_world_submap, "SubmapGraph::AddSubmap " + Id(id)));
  auto node = std::make_unique<Node>();
  node->id = id;
  node->index = m.ordered.size();
  PoseToBlock(T_world_submap, node->pose.data());
  m.problem->AddParameterBlock(node->pose.data(), kPoseBlockSize, NewPoseManifold());
  m.ordered.push_back(node.get());
  m.nodes.emplace(id, std::move(node));
  return OkStatus();
}

Status SubmapGraph::AddScan(SubmapId id, int64_t scan_id, Timestamp stamp,
                            const Eigen::Isometry3d& T_submap_scan) {
  Node* node = impl_->Find(id);
  if (node == nullptr) return NotFoundError("SubmapGraph::AddScan: unknown submap " + Id(id));
  SLAM_MMS_RETURN_IF_ERROR(ValidatePose(T_submap_scan, "SubmapGraph::AddScan T_submap_scan"));
  SubmapScanPose s;
  s.submap = id;
  s.scan_id = scan_id;
  s.stamp = stamp;
  s.T_submap_scan = T_submap_scan;
  node->scans.push_back(s);
  return OkStatus();
}

Status SubmapGraph::SetScans(SubmapId id, const std::vector<SubmapScanPose>& scans) {
  Node* node = impl_->Find(id);
  if (node == nullptr) return NotFoundError("SubmapGraph::SetScans: unknown submap " + Id(id));
  for (const auto& s : scans) {
    SLAM_MMS_RETURN_IF_ERROR(ValidatePose(s.T_submap_scan, "SubmapGraph::SetScans T_submap_scan"));
  }
  node->scans = scans;
  for (auto& s : node->scans) s.submap = id;
  return OkStatus();
}

Status SubmapGraph::AddRegistrationFactor(SubmapId a, SubmapId b, const Eigen::Isometry3d& T_a_b,
                                          const Matrix6d& covariance, const RobustLoss& loss) {
  SLAM_MMS_RETURN_IF_ERROR(
      impl_->AddBetween(a, b, T_a_b, covariance, loss, "AddRegistrationFactor"));
  impl_->RecordSequential(a, b, T_a_b, covariance, /*reckon=*/false);
  impl_->Record(SubmapFactorKind::kRegistration, a, b, T_a_b, covariance, loss);
  return OkStatus();
}

Status SubmapGraph::AddReckonFactor(SubmapId a, SubmapId b, const Eigen::Isometry3d& T_a_b,
                                    const Matrix6d& covariance) {
  SLAM_MMS_RETURN_IF_ERROR(
      impl_->AddBetween(a, b, T_a_b, covariance, RobustLoss::None(), "AddReckonFactor"));
  impl_->RecordSequential(a, b, T_a_b, covariance, /*reckon=*/true);
  impl_->Record(SubmapFactorKind::kReckon, a, b, T_a_b, covariance);
  return OkStatus();
}

StatusOr<LoopCheck> SubmapGraph::CheckLoop(SubmapId a, SubmapId b, const Eigen::Isometry3d& T_a_b,
                                           const Matrix6d& covariance) const {
  return impl_->Check(a, b, T_a_b, covariance);
}

StatusOr<LoopCheck> SubmapGraph::AddLoopFactor(SubmapId a, SubmapId b,
                                               const Eigen::Isometry3d& T_a_b,
                                               const Matrix6d& covariance) {
  Impl& m = *impl_;
  SLAM_MMS_ASSIGN_OR_RETURN(LoopCheck check, m.Check(a, b, T_a_b, covariance));
  SLAM_MMS_RETURN_IF_ERROR(
      m.AddBetween(a, b, T_a_b, covariance, m.options.loop_loss, "AddLoopFactor"));
  const size_t oldest = std::min(m.Find(a)->index, m.Find(b)->index);
  m.pending_loop_from = std::min(m.pending_loop_from.value_or(oldest), oldest);
  ++m.num_loops;
  m.Record(SubmapFactorKind::kLoop, a, b, T_a_b, covariance);
  SLAM_MMS_LOG(kDebug) << "SubmapGraph: loop " << a << "<->" << b
                       << " d2 = " << check.mahalanobis_sq;
  return check;
}

Status SubmapGraph::AddPosePrior(SubmapId id, const Eigen::Isometry3d& T_world_submap,
                                 const Matrix6d& covariance) {
  Impl& m = *impl_;
  Node* node = m.Find(id);
  if (node == nullptr) return NotFoundError("SubmapGraph::AddPosePrior: unknown submap " + Id(id));
  SLAM_MMS_RETURN_IF_ERROR(ValidatePose(T_world_submap, "SubmapGraph::AddPosePrior"));
  SLAM_MMS_RETURN_IF_ERROR(ValidateCovariance<6>(covariance, "SubmapGraph::AddPosePrior"));
  SLAM_MMS_ASSIGN_OR_RETURN(auto cost, PosePriorFactor::Create(T_world_submap, covariance));
  m.last_block = m.problem->AddResidualBlock(cost.release(), nullptr, node->pose.data());
  m.Record(SubmapFactorKind::kPosePrior, id, id, T_world_submap, covariance);
  return OkStatus();
}

Status SubmapGraph::AddAttitudeChainFactor(SubmapId a, SubmapId b, const Eigen::Matrix3d& R_world_a,
                                           const Eigen::Matrix3d& R_world_b,
                                           const AttitudeChain& chain) {
  Impl& m = *impl_;
  SLAM_MMS_ASSIGN_OR_RETURN(auto nodes, m.Pair(a, b, "AddAttitudeChainFactor"));
  if (nodes.first->index > nodes.second->index) {
    return InvalidArgumentError("SubmapGraph::AddAttitudeChainFactor: submap " + Id(a) +
                                " was added after " + Id(b));
  }
  auto cost = AttitudeChainFactor::Create(R_world_a, R_world_b, chain.transition, chain.covariance);
  if (!cost.ok()) return cost.status().WithContext("SubmapGraph::AddAttitudeChainFactor");
  m.last_block = m.problem->AddResidualBlock(cost->release(), nullptr, nodes.first->pose.data(),
                                             nodes.second->pose.data());
  SubmapGraphFactor f;
  f.kind = SubmapFactorKind::kAttitudeChain;
  f.a = a;
  f.b = b;
  f.T.linear() = R_world_b;
  f.T_a.linear() = R_world_a;
  f.covariance = Matrix6d::Zero();
  f.covariance.topLeftCorner<3, 3>() = chain.covariance;
  f.transition = chain.transition;
  m.PushFactor(f);
  return OkStatus();
}

Status SubmapGraph::AddGnssPrior(SubmapId id, const Eigen::Vector3d& p_world_antenna,
                                 const Eigen::Matrix3d& covariance,
                                 const Eigen::Isometry3d& T_submap_body,
                                 const Eigen::Vector3d& t_body_antenna, int gnss_bias) {
  Impl& m = *impl_;
  Node* node = m.Find(id);
  if (node == nullptr) return NotFoundError("SubmapGraph::AddGnssPrior: unknown submap " + Id(id));
  std::array<double, 3>* bias = nullptr;
  if (gnss_bias >= 0) {
    auto it = m.gnss_biases.find(gnss_bias);
    if (it == m.gnss_biases.end()) {
      return NotFoundError("SubmapGraph::AddGnssPrior: unknown GNSS bias " +
                           std::to_string(gnss_bias));
    }
    bias = it->second.get();
  }
  SLAM_MMS_RETURN_IF_ERROR(ValidatePose(T_submap_body, "SubmapGraph::AddGnssPrior T_submap_body"));
  if (!p_world_antenna.allFinite() || !t_body_antenna.allFinite()) {
    return InvalidArgumentError("SubmapGraph::AddGnssPrior: position or lever arm not finite");
  }
  SLAM_MMS_RETURN_IF_ERROR(ValidateCovariance<3>(covariance, "SubmapGraph::AddGnssPrior"));
  // Eq. (24) with the antenna expressed in the submap frame: p_Nref + R_Nref * t_submap_antenna.
  const Eigen::Vector3d t_submap_antenna = T_submap_body * t_body_antenna;
  SLAM_MMS_ASSIGN_OR_RETURN(
      auto cost, GnssPositionFactor::Create(p_world_antenna, covariance, t_submap_antenna));
  if (bias != nullptr) {
    m.last_block = m.problem->AddResidualBlock(new BiasedGnssPositionFactor(std::move(cost)),
                                               m.options.gnss_loss.NewLossFunction(),
                                               node->pose.data(), bias->data());
  } else {
    m.last_block = m.problem->AddResidualBlock(
        cost.release(), m.options.gnss_loss.NewLossFunction(), node->pose.data());
  }
  ++node->num_gnss;
  ++m.num_gnss;
  SubmapGraphFactor f;
  f.kind = SubmapFactorKind::kGnss;
  f.a = f.b = id;
  f.covariance = Matrix6d::Zero();
  f.covariance.topLeftCorner<3, 3>() = covariance;
  f.p_world_antenna = p_world_antenna;
  f.T_submap_body = T_submap_body;
  f.t_body_antenna = t_body_antenna;
  f.gnss_bias = gnss_bias;
  m.PushFactor(f);
  return OkStatus();
}

Status SubmapGraph::AddGnssBias(int key, const Eigen::Matrix3d& prior_covariance) {
  Impl& m = *impl_;
  Eigen::Matrix3d sqrt_info;
  SLAM_MMS_ASSIGN_OR_RETURN(
      auto* block, m.NewGnssBias(key, prior_covariance, "SubmapGraph::AddGnssBias", &sqrt_info));
  m.last_block =
      m.problem->AddResidualBlock(new ZeroMeanPrior3Factor(sqrt_info), nullptr, block->data());
  m.RecordGnssBias(SubmapFactorKind::kGnssBias, key, -1, 0.0, prior_covariance);
  return OkStatus();
}

Status SubmapGraph::AddGnssBiasLink(int from_key, int key, double transition,
                                    const Eigen::Matrix3d& covariance) {
  Impl& m = *impl_;
  const std::string what = "SubmapGraph::AddGnssBiasLink";
  auto from = m.gnss_biases.find(from_key);
  if (from == m.gnss_biases.end()) {
    return NotFoundError(what + ": unknown GNSS bias " + std::to_string(from_key));
  }
  if (!(transition >= 0.0 && transition <= 1.0)) {
    return InvalidArgumentError(what + ": transition " + std::to_string(transition) +
                                " must be in [0, 1]");
  }
  Eigen::Matrix3d sqrt_info;
  SLAM_MMS_ASSIGN_OR_RETURN(auto* block, m.NewGnssBias(key, covariance, what, &sqrt_info));
  for (int k = 0; k < 3; ++k) (*block)[k] = transition * (*from->second)[k];
  m.last_block = m.problem->AddResidualBlock(new GnssBiasLinkFactor(transition, sqrt_info), nullptr,
                                             from->second->data(), block->data());
  m.RecordGnssBias(SubmapFactorKind::kGnssBiasLink, key, from_key, transition, covariance);
  return OkStatus();
}

StatusOr<Eigen::Vector3d> SubmapGraph::GnssBias(int key) const {
  auto it = impl_->gnss_biases.find(key);
  if (it == impl_->gnss_biases.end()) {
    return NotFoundError("SubmapGraph::GnssBias: unknown GNSS bias " + std::to_string(key));
  }
  return Eigen::Vector3d(it->second->data());
}

const std::vector<SubmapGraphFactor>& SubmapGraph::Factors() const { return impl_->factors; }

StatusOr<std::vector<SubmapGraph::FactorFit>> SubmapGraph::FitFactors() const {
  std::vector<double*> parameters;  // nodes in id order, then the GNSS biases in key order
  for (Node* n : impl_->ordered) parameters.push_back(n->pose.data());
  for (auto& [key, bias] : impl_->gnss_biases) parameters.push_back(bias->data());
  return internal::FitResidualBlocks(impl_->problem.get(), impl_->factor_blocks, parameters,
                                     impl_->options.num_threads);
}

const char* SubmapFactorKindName(SubmapFactorKind kind) {
  switch (kind) {
    case SubmapFactorKind::kRegistration: return "registration";
    case SubmapFactorKind::kReckon: return "reckon";
    case SubmapFactorKind::kLoop: return "loop";
    case SubmapFactorKind::kPosePrior: return "pose_prior";
    case SubmapFactorKind::kGnss: return "gnss";
    case SubmapFactorKind::kAttitudeChain: return "attitude_chain";
    case SubmapFactorKind::kGnssBias: return "gnss_bias";
    case SubmapFactorKind::kGnssBiasLink: return "gnss_bias_link";
  }
  return "unknown";
}

bool SubmapFactorKindFromName(const char* name, SubmapFactorKind* kind) {
  for (SubmapFactorKind k :
       {SubmapFactorKind::kRegistration, SubmapFactorKind::kReckon, SubmapFactorKind::kLoop,
        SubmapFactorKind::kPosePrior, SubmapFactorKind::kGnss, SubmapFactorKind::kAttitudeChain,
        SubmapFactorKind::kGnssBias, SubmapFactorKind::kGnssBiasLink}) {
    if (std::string(SubmapFactorKindName(k)) == name) {
      *kind = k;
      return true;
    }
  }
  return false;
}

StatusOr<SolveSummary> SubmapGraph::Solve(SolveTrigger trigger) {
  Impl& m = *impl_;
  const size_t n = m.ordered.size();
  const size_t from = m.FreeFrom(trigger);
  int num_free = 0;
  for (size_t i = 0; i < n; ++i) {
    // Without any GNSS prior the first submap is the gauge (the paper's w is then its frame).
    const bool gauge = i == 0 && m.num_gnss == 0;
    if (i >= from && !gauge) {
      m.problem->SetParameterBlockVariable(m.ordered[i]->pose.data());
      ++num_free;
    } else {
      m.problem->SetParameterBlockConstant(m.ordered[i]->pose.data());
    }
  }
  m.last_free = num_free;
  backend_internal::CeresSolveOptions so;
  so.max_iterations = m.options.max_iterations;
  so.max_solve_time_s = m.options.max_solve_time_s;
  so.num_threads = m.options.num_threads;
  so.function_tolerance = m.options.function_tolerance;
  SolveSummary summary = backend_internal::SolveProblem(m.problem.get(), so);
  if (summary.usable()) m.pending_loop_from.reset();
  SLAM_MMS_LOG(kDebug) << "SubmapGraph: solve (" << SolveTriggerName(trigger) << ") " << num_free
                       << "/" << n << " free, " << SolveTerminationName(summary.termination) << ", "
                       << summary.iterations << " iterations, " << summary.solve_time_s << " s";
  return summary;
}

std::vector<LoopCandidate> SubmapGraph::LoopCandidates(const Eigen::Vector3d& p_world,
                                                       SubmapId current) const {
  const Impl& m = *impl_;
  std::vector<LoopCandidate> out;
  if (!p_world.allFinite()) return out;
  const Node* cur = m.Find(current);
  const size_t cur_index = cur != nullptr ? cur->index : m.ordered.size();
  const size_t gap = static_cast<size_t>(m.options.loop_min_submap_gap);
  if (cur_index < gap) return out;
  for (size_t i = 0; i + gap <= cur_index; ++i) {
    const Node* node = m.ordered[i];
    const Eigen::Isometry3d T_world_submap = PoseFromBlock(node->pose.data());
    double d = (T_world_submap.translation() - p_world).norm();
    for (const auto& s : node->scans) {
      d = std::min(d, (T_world_submap * s.T_submap_scan.translation() - p_world).norm());
    }
    if (d < m.options.loop_candidate_distance_m) out.push_back({node->id, d});
  }
  std::sort(out.begin(), out.end(), [](const LoopCandidate& x, const LoopCandidate& y) {
    return x.distance_m < y.distance_m;
  });
  return out;
}

bool SubmapGraph::HasSubmap(SubmapId id) const { return impl_->Find(id) != nullptr; }

std::vector<SubmapId> SubmapGraph::SubmapIds() const {
  std::vector<SubmapId> ids;
  for (const Node* n : impl_->ordered) ids.push_back(n->id);
  return ids;
}

StatusOr<Eigen::Isometry3d> SubmapGraph::SubmapPose(SubmapId id) const {
  const Node* node = impl_->Find(id);
  if (node == nullptr) return NotFoundError("SubmapGraph::SubmapPose: unknown submap " + Id(id));
  return PoseFromBlock(node->pose.data());
}

StatusOr<Matrix6d> SubmapGraph::SubmapCovariance(SubmapId id) const {
  const Impl& m = *impl_;
  const Node* node = m.Find(id);
  if (node == nullptr) {
    return NotFoundError("SubmapGraph::SubmapCovariance: unknown submap " + Id(id));
  }
  // Over the whole graph: free every node but the gauge.
  for (Node* n : m.ordered) {
    if (n->index == 0 && m.num_gnss == 0) {
      m.problem->SetParameterBlockConstant(n->pose.data());
    } else {
      m.problem->SetParameterBlockVariable(n->pose.data());
    }
  }
  return backend_internal::PoseBlockCovariance(m.problem.get(), node->pose.data(),
                                               m.options.num_threads);
}

std::vector<SubmapScanPose> SubmapGraph::ScanPoses() const {
  std::vector<SubmapScanPose> out;
  for (const Node* n : impl_->ordered) {
    const Eigen::Isometry3d T_world_submap = PoseFromBlock(n->pose.data());
    for (SubmapScanPose s : n->scans) {
      s.T_world_scan = T_world_submap * s.T_submap_scan;  // T_w_Ni = T_w_Nref * T_Nref_Ni.
      out.push_back(s);
    }
  }
  return out;
}

int SubmapGraph::num_submaps() const { return static_cast<int>(impl_->ordered.size()); }
int SubmapGraph::num_loop_factors() const { return impl_->num_loops; }
int SubmapGraph::num_gnss_priors() const { return impl_->num_gnss; }
int SubmapGraph::last_num_free_submaps() const { return impl_->last_free; }
const SubmapGraph::Options& SubmapGraph::options() const { return impl_->options; }

}  // namespace slam_mms
