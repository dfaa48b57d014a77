#include "backend/sliding_window_graph.hpp"

#include <ceres/problem.h>
#include <ceres/solver.h>

#include <algorithm>
#include <array>
#include <map>
#include <set>
#include <string>

#include "backend/backend_math.hpp"
#include "backend/ceres_solve.hpp"
#include "backend/marginalization.hpp"
#include "backend/pose_block.hpp"
#include "backend/pose_prior_factor.hpp"
#include "backend/relative_pose_factor.hpp"
#include "core/option_error.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {

using backend_internal::PoseError;
using backend_internal::ValidateCovariance;
using backend_internal::ValidatePose;

namespace {

struct State {
  StateId id = 0;
  bool keep = false;
  bool fixed = false;  // Left the window in ExitMode::kFix: held constant until unconnected.
  bool has_velocity = false;
  bool has_bias = false;
  std::array<double, kPoseBlockSize> pose{};
  std::array<double, kVelocityBlockSize> velocity{};
  std::array<double, kBiasBlockSize> bias{};
};

enum class RecordType { kPrior, kRelative, kCustom, kMarginal };

struct FactorRecord {
  ceres::ResidualBlockId rb = nullptr;
  RecordType type = RecordType::kCustom;
  FactorKind kind = FactorKind::kMotion;  // kRelative only.
  StateId a = 0, b = 0;                   // kRelative only.
  Eigen::Isometry3d T_a_b = Eigen::Isometry3d::Identity();
  Matrix6d covariance = Matrix6d::Identity();
};

std::string Id(StateId id) { return std::to_string(id); }

}  // namespace

Status SlidingWindowOptions::Validate() const {
  if (window_size <= 0) {
    return internal::OptionError("SlidingWindowGraph::Options", "window_size", window_size,
                                 "must be > 0");
  }
  if (max_iterations <= 0) {
    return internal::OptionError("SlidingWindowGraph::Options", "max_iterations", max_iterations,
                                 "must be > 0");
  }
  if (!(max_solve_time_s > 0.0)) {
    return internal::OptionError("SlidingWindowGraph::Options", "max_solve_time_s",
                                 max_solve_time_s, "must be > 0");
  }
  if (!(function_tolerance > 0.0)) {
    return internal::OptionError("SlidingWindowGraph::Options", "function_tolerance",
                                 function_tolerance, "must be > 0");
  }
  if (!(consistency_gate_chi2 > 0.0)) {
    return internal::OptionError("SlidingWindowGraph::Options", "consistency_gate_chi2",
                                 consistency_gate_chi2, "must be > 0");
  }
  if (!(marginalization_eigen_threshold >= 0.0)) {
    return internal::OptionError("SlidingWindowGraph::Options", "marginalization_eigen_threshold",
                                 marginalization_eigen_threshold, "must be >= 0");
  }
  return OkStatus();
}

Status SlidingWindowGraph::Options::Validate() const {
  SLAM_MMS_RETURN_IF_ERROR(SlidingWindowOptions::Validate());
  if (num_threads <= 0) {
    return internal::OptionError("SlidingWindowGraph::Options", "num_threads", num_threads,
                                 "must be > 0");
  }
  return OkStatus();
}

struct SlidingWindowGraph::Impl {
  Options options;
  std::unique_ptr<ceres::Problem> problem;
  std::map<StateId, std::unique_ptr<State>> states;
  std::map<const double*, StateId> block_owner;
  std::map<FactorId, FactorRecord> factors;
  FactorId next_factor_id = 0;
  std::optional<StateId> last_added;
  ConsistencyStats stats;
  int num_marginalized = 0;

  explicit Impl(const Options& o) : options(o) {
    ceres::Problem::Options po;
    po.enable_fast_removal = true;  // States and factors leave the window all the time.
    problem = std::make_unique<ceres::Problem>(po);
  }

  State* Find(StateId id) {
    auto it = states.find(id);
    return it == states.end() ? nullptr : it->second.get();
  }
  const State* Find(StateId id) const {
    auto it = states.find(id);
    return it == states.end() ? nullptr : it->second.get();
  }

  StatusOr<double*> Block(const StateBlockRef& ref) {
    State* s = Find(ref.state);
    if (s == nullptr) return NotFoundError("unknown state id " + Id(ref.state));
    switch (ref.block) {
      case StateBlock::kPose: return s->pose.data();
      case StateBlock::kVelocity:
        if (!s->has_velocity) {
          return InvalidArgumentError("state " + Id(ref.state) + " has no velocity block");
        }
        return s->velocity.data();
      case StateBlock::kBias:
        if (!s->has_bias) {
          return InvalidArgumentError("state " + Id(ref.state) + " has no bias block");
        }
        return s->bias.data();
    }
    return InternalError("unknown StateBlock");
  }

  std::vector<double*> BlocksOf(State& s) {
    std::vector<double*> b = {s.pose.data()};
    if (s.has_velocity) b.push_back(s.velocity.data());
    if (s.has_bias) b.push_back(s.bias.data());
    return b;
  }

  FactorId AddRecord(FactorRecord r) {
    const FactorId id = next_factor_id++;
    factors.emplace(id, std::move(r));
    return id;
  }

  // Drops the records whose residual block is no longer in the problem.
  void PruneRecords(const std::set<ceres::ResidualBlockId>& removed) {
    for (auto it = factors.begin(); it != factors.end();) {
      it = removed.count(it->second.rb) != 0 ? factors.erase(it) : std::next(it);
    }
  }

  std::set<ceres::ResidualBlockId> ResidualsOf(const std::vector<double*>& blocks) const {
    std::set<ceres::ResidualBlockId> out;
    for (double* p : blocks) {
      std::vector<ceres::ResidualBlockId> rbs;
      problem->GetResidualBlocksForParameterBlock(p, &rbs);
      out.insert(rbs.begin(), rbs.end());
    }
    return out;
  }

  void EraseState(State& s) {
    const std::vector<double*> blocks = BlocksOf(s);
    const std::set<ceres::ResidualBlockId> rb_set = ResidualsOf(blocks);
    // The factors go first, in the order they were added: RemoveParameterBlock would remove them
    // in the order of Ceres's set of them (their addresses), and each removal moves the program's
    // last residual block into the gap, so the Jacobian's row order, and with it the last bits of
    // every later solve, would depend on where the heap put the factors (two runs of one drive
    // differed by 4e-11 m).
    for (const auto& [fid, r] : factors) {
      if (rb_set.count(r.rb) != 0) problem->RemoveResidualBlock(r.rb);
    }
    PruneRecords(rb_set);
    for (double* p : blocks) {
      problem->RemoveParameterBlock(p);
      block_owner.erase(p);
    }
    states.erase(s.id);
  }

  Status Marginalize(State& s) {
    const std::vector<double*> blocks = BlocksOf(s);
    const std::set<ceres::ResidualBlockId> rb_set = ResidualsOf(blocks);
    // In the order the factors were added, not the set's (their addresses): the marginal prior's
    // sums, and so every later solve and covariance, must not depend on where the heap put them.
    std::vector<ceres::ResidualBlockId> rbs;
    for (const auto& [fid, r] : factors) {
      if (rb_set.count(r.rb) != 0) rbs.push_back(r.rb);
    }
    if (rbs.size() != rb_set.size()) {
      return InternalError("SlidingWindowGraph: a factor of the leaving state has no record");
    }
    std::set<double*> removed;
    for (double* p : blocks) {
      if (!problem->IsParameterBlockConstant(p)) removed.insert(p);
    }
    SLAM_MMS_ASSIGN_OR_RETURN(
        auto prior, backend_internal::MarginalizeBlocks(*problem, rbs, removed,
                                                        options.marginalization_eigen_threshold));
    EraseState(s);
    ++num_marginalized;
    if (prior) {
      std::vector<double*> params = prior->parameter_pointers();
      FactorRecord r;
      r.type = RecordType::kMarginal;
      r.rb = problem->AddResidualBlock(prior.release(), nullptr, params);
      AddRecord(r);
    }
    return OkStatus();
  }

  void FixAndCollect(State& s) {
    for (double* p : BlocksOf(s)) problem->SetParameterBlockConstant(p);
    s.fixed = true;
    // A fixed state whose every factor touches only constant blocks no longer matters.
    std::vector<StateId> to_erase;
    for (auto& [id, st] : states) {
      if (!st->fixed) continue;
      bool connected = false;
      for (auto* rb : ResidualsOf(BlocksOf(*st))) {
        std::vector<double*> params;
        problem->GetParameterBlocksForResidualBlock(rb, &params);
        for (double* p : params) connected |= !problem->IsParameterBlockConstant(p);
      }
      if (!connected) to_erase.push_back(id);
    }
    for (StateId id : to_erase) EraseState(*Find(id));
  }

  Status Leave(State& s) {
    if (options.exit_mode == ExitMode::kMarginalize) return Marginalize(s);
    FixAndCollect(s);
    return OkStatus();
  }

  // The kMotion prediction of T_a_b: a direct factor a->b, or a chain through consecutive states.
  std::optional<MotionPrediction> PredictFromMotionFactors(StateId a, StateId b) const {
    auto direct = [&](StateId from, StateId to) -> std::optional<MotionPrediction> {
      std::optional<MotionPrediction> best;
      for (const auto& [fid, r] : factors) {  // Latest (highest id) wins.
        if (r.type == RecordType::kRelative && r.kind == FactorKind::kMotion && r.a == from &&
            r.b == to) {
          best = MotionPrediction{r.T_a_b, r.covariance};
        }
      }
      return best;
    };
    if (auto d = direct(a, b)) return d;
    if (b <= a) return std::nullopt;
    MotionPrediction acc;  // Identity, zero covariance.
    acc.covariance.setZero();
    auto it = states.find(a);
    while (it != states.end() && it->first != b) {
      auto next = std::next(it);
      if (next == states.end() || next->first > b) return std::nullopt;
      auto step = direct(it->first, next->first);
      if (!step) return std::nullopt;
      // T = T1 T2, xi = Ad(T2^-1) xi1 + xi2.
      const Matrix6d Ad = se3::Adjoint(step->T_a_b.inverse());
      acc.covariance = Ad * acc.covariance * Ad.transpose() + step->covariance;
      acc.T_a_b = acc.T_a_b * step->T_a_b;
      it = next;
    }
    if (it == states.end()) return std::nullopt;
    return acc;
  }
};

SlidingWindowGraph::SlidingWindowGraph(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SlidingWindowGraph::SlidingWindowGraph(SlidingWindowGraph&&) noexcept = default;
SlidingWindowGraph& SlidingWindowGraph::operator=(SlidingWindowGraph&&) noexcept = default;
SlidingWindowGraph::~SlidingWindowGraph() = default;

StatusOr<SlidingWindowGraph> SlidingWindowGraph::Create(const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  return SlidingWindowGraph(std::make_unique<Impl>(options));
}

StatusOr<SlidingWindowGraph> SlidingWindowGraph::Create() { return Create(Options()); }

Status SlidingWindowGraph::AddState(StateId id, const StateInit& init) {
  Impl& m = *impl_;
  if (m.last_added && id <= *m.last_added) {
    return InvalidArgumentError("SlidingWindowGraph::AddState: id " + Id(id) +
                                " is not greater than the last id " + Id(*m.last_added));
  }
  SLAM_MMS_RETURN_IF_ERROR(
      ValidatePose(init.T_frame_body, "SlidingWindowGraph::AddState " + Id(id)));
  if (init.v_frame && !init.v_frame->allFinite()) {
    return InvalidArgumentError("SlidingWindowGraph::AddState " + Id(id) + ": velocity not finite");
  }
  if (init.imu_bias && !init.imu_bias->allFinite()) {
    return InvalidArgumentError("SlidingWindowGraph::AddState " + Id(id) + ": bias not finite");
  }
  auto s = std::make_unique<State>();
  s->id = id;
  s->keep = init.keep;
  PoseToBlock(init.T_frame_body, s->pose.data());
  m.problem->AddParameterBlock(s->pose.data(), kPoseBlockSize, NewPoseManifold());
  m.block_owner[s->pose.data()] = id;
  if (init.v_frame) {
    s->has_velocity = true;
    Eigen::Map<Eigen::Vector3d>(s->velocity.data()) = *init.v_frame;
    m.problem->AddParameterBlock(s->velocity.data(), kVelocityBlockSize);
    m.block_owner[s->velocity.data()] = id;
  }
  if (init.imu_bias) {
    s->has_bias = true;
    Eigen::Map<Vector6d>(s->bias.data()) = *init.imu_bias;
    m.problem->AddParameterBlock(s->bias.data(), kBiasBlockSize);
    m.block_owner[s->bias.data()] = id;
  }
  m.states.emplace(id, std::move(s));
  m.last_added = id;
  return OkStatus();
}

StatusOr<FactorId> SlidingWindowGraph::AddPosePrior(StateId id, const Eigen::Isometry3d& T,
                                                    const Matrix6d& covariance,
                                                    const RobustLoss& loss) {
  Impl& m = *impl_;
  SLAM_MMS_RETURN_IF_ERROR(loss.Validate());
  SLAM_MMS_ASSIGN_OR_RETURN(double* block, m.Block({id, StateBlock::kPose}));
  SLAM_MMS_ASSIGN_OR_RETURN(auto cost, PosePriorFactor::Create(T, covariance));
  FactorRecord r;
  r.type = RecordType::kPrior;
  r.rb = m.problem->AddResidualBlock(cost.release(), loss.NewLossFunction(), block);
  return m.AddRecord(r);
}

StatusOr<FactorOutcome> SlidingWindowGraph::AddRelativePoseFactor(
    StateId a, StateId b, const Eigen::Isometry3d& T_a_b, const Matrix6d& covariance,
    FactorKind kind, const RobustLoss& loss, const std::optional<MotionPrediction>& prediction) {
  Impl& m = *impl_;
  SLAM_MMS_RETURN_IF_ERROR(loss.Validate());
  if (a == b) {
    return InvalidArgumentError("SlidingWindowGraph::AddRelativePoseFactor: a == b == " + Id(a));
  }
  SLAM_MMS_ASSIGN_OR_RETURN(double* block_a, m.Block({a, StateBlock::kPose}));
  SLAM_MMS_ASSIGN_OR_RETURN(double* block_b, m.Block({b, StateBlock::kPose}));
  SLAM_MMS_RETURN_IF_ERROR(ValidatePose(T_a_b, "SlidingWindowGraph::AddRelativePoseFactor"));
  SLAM_MMS_RETURN_IF_ERROR(
      ValidateCovariance<6>(covariance, "SlidingWindowGraph::AddRelativePoseFactor"));

  FactorOutcome outcome;
  Matrix6d cov = covariance;
  if (kind == FactorKind::kRegistration) {
    std::optional<MotionPrediction> pred = prediction;
    if (pred) {
      SLAM_MMS_RETURN_IF_ERROR(ValidatePose(pred->T_a_b, "MotionPrediction::T_a_b"));
      SLAM_MMS_RETURN_IF_ERROR(ValidateCovariance<6>(pred->covariance, "MotionPrediction"));
    } else {
      pred = m.PredictFromMotionFactors(a, b);
    }
    if (!pred) {
      ++m.stats.unchecked;
    } else {
      // Graham et al. 2015: does the registration agree with the motion prediction?
      const Vector6d e = PoseError(pred->T_a_b, T_a_b);
      const Matrix6d S = covariance + pred->covariance;
      outcome.consistency_checked = true;
      outcome.mahalanobis_sq = e.dot(S.ldlt().solve(e));
      ++m.stats.checked;
      if (outcome.mahalanobis_sq <= m.options.consistency_gate_chi2) {
        ++m.stats.passed;
      } else if (!pred->enforce) {
        outcome.consistent = false;
        ++m.stats.taken_inconsistent;
      } else {
        outcome.consistent = false;
        if (m.options.inconsistency_action == InconsistencyAction::kReject) {
          ++m.stats.rejected;
          SLAM_MMS_LOG(kDebug) << "SlidingWindowGraph: registration " << a << "->" << b
                               << " rejected, d2 = " << outcome.mahalanobis_sq;
          return outcome;
        }
        ++m.stats.down_weighted;
        outcome.covariance_scale = outcome.mahalanobis_sq / m.options.consistency_gate_chi2;
        cov *= outcome.covariance_scale;
      }
    }
  }
  SLAM_MMS_ASSIGN_OR_RETURN(auto cost, RelativePoseFactor::Create(T_a_b, cov));
  FactorRecord r;
  r.type = RecordType::kRelative;
  r.kind = kind;
  r.a = a;
  r.b = b;
  r.T_a_b = T_a_b;
  r.covariance = cov;
  r.rb = m.problem->AddResidualBlock(cost.release(), loss.NewLossFunction(), block_a, block_b);
  outcome.id = m.AddRecord(r);
  return outcome;
}

StatusOr<FactorId> SlidingWindowGraph::AddCostFunction(std::unique_ptr<ceres::CostFunction> cost,
                                                       const std::vector<StateBlockRef>& blocks,
                                                       const RobustLoss& loss) {
  Impl& m = *impl_;
  SLAM_MMS_RETURN_IF_ERROR(loss.Validate());
  if (!cost) return InvalidArgumentError("SlidingWindowGraph::AddCostFunction: null cost");
  if (cost->num_residuals() <= 0) {
    return InvalidArgumentError("SlidingWindowGraph::AddCostFunction: no residuals");
  }
  const auto& sizes = cost->parameter_block_sizes();
  if (sizes.size() != blocks.size()) {
    return InvalidArgumentError("SlidingWindowGraph::AddCostFunction: the cost function has " +
                                std::to_string(sizes.size()) + " parameter blocks, " +
                                std::to_string(blocks.size()) + " given");
  }
  std::vector<double*> params;
  for (size_t i = 0; i < blocks.size(); ++i) {
    SLAM_MMS_ASSIGN_OR_RETURN(double* p, m.Block(blocks[i]));
    const int expected = m.problem->ParameterBlockSize(p);
    if (sizes[i] != expected) {
      return InvalidArgumentError("SlidingWindowGraph::AddCostFunction: block " +
                                  std::to_string(i) + " has size " + std::to_string(sizes[i]) +
                                  ", the state block has " + std::to_string(expected));
    }
    if (std::find(params.begin(), params.end(), p) != params.end()) {
      return InvalidArgumentError("SlidingWindowGraph::AddCostFunction: block " +
                                  std::to_string(i) + " given twice");
    }
    params.push_back(p);
  }
  FactorRecord r;
  r.type = RecordType::kCustom;
  r.rb = m.problem->AddResidualBlock(cost.release(), loss.NewLossFunction(), params);
  return m.AddRecord(r);
}

Status SlidingWindowGraph::RemoveFactor(FactorId id) {
  Impl& m = *impl_;
  auto it = m.factors.find(id);
  if (it == m.factors.end()) return NotFoundError("SlidingWindowGraph: unknown factor " + Id(id));
  m.problem->RemoveResidualBlock(it->second.rb);
  m.factors.erase(it);
  return OkStatus();
}

Status SlidingWindowGraph::SetBlockConstant(StateBlockRef ref, bool constant) {
  Impl& m = *impl_;
  SLAM_MMS_ASSIGN_OR_RETURN(double* p, m.Block(ref));
  if (m.Find(ref.state)->fixed) {
    return FailedPreconditionError("SlidingWindowGraph: state " + Id(ref.state) +
                                   " has left the window");
  }
  if (constant) {
    m.problem->SetParameterBlockConstant(p);
  } else {
    m.problem->SetParameterBlockVariable(p);
  }
  return OkStatus();
}

StatusOr<SolveSummary> SlidingWindowGraph::Solve() {
  Impl& m = *impl_;
  backend_internal::CeresSolveOptions so;
  so.max_iterations = m.options.max_iterations;
  so.max_solve_time_s = m.options.max_solve_time_s;
  so.num_threads = m.options.num_threads;
  so.function_tolerance = m.options.function_tolerance;
  SolveSummary summary = backend_internal::SolveProblem(m.problem.get(), so);
  if (summary.termination == SolveTermination::kFailure) {
    SLAM_MMS_LOG(kWarning) << "SlidingWindowGraph: solve failed: " << summary.message;
  }
  // The window update runs after every solve, so marginalization linearises at the best estimate.
  for (;;) {
    int free_states = 0;
    State* oldest = nullptr;
    for (auto& [id, s] : m.states) {
      if (s->keep || s->fixed) continue;
      if (oldest == nullptr) oldest = s.get();
      ++free_states;
    }
    if (free_states <= m.options.window_size || oldest == nullptr) break;
    SLAM_MMS_RETURN_IF_ERROR(m.Leave(*oldest));
  }
  return summary;
}

Status SlidingWindowGraph::RemoveState(StateId id) {
  State* s = impl_->Find(id);
  if (s == nullptr)
    return NotFoundError("SlidingWindowGraph::RemoveState: unknown state " + Id(id));
  if (s->fixed) {
    impl_->EraseState(*s);
    return OkStatus();
  }
  return impl_->Leave(*s);
}

bool SlidingWindowGraph::HasState(StateId id) const { return impl_->Find(id) != nullptr; }

std::vector<StateId> SlidingWindowGraph::StateIds() const {
  std::vector<StateId> ids;
  for (const auto& [id, s] : impl_->states) ids.push_back(id);
  return ids;
}

StatusOr<Eigen::Isometry3d> SlidingWindowGraph::Pose(StateId id) const {
  const State* s = impl_->Find(id);
  if (s == nullptr) return NotFoundError("SlidingWindowGraph::Pose: unknown state " + Id(id));
  return PoseFromBlock(s->pose.data());
}

StatusOr<Eigen::Vector3d> SlidingWindowGraph::Velocity(StateId id) const {
  const State* s = impl_->Find(id);
  if (s == nullptr) return NotFoundError("SlidingWindowGraph::Velocity: unknown state " + Id(id));
  if (!s->has_velocity) return FailedPreconditionError("state " + Id(id) + " has no velocity");
  return Eigen::Vector3d(Eigen::Map<const Eigen::Vector3d>(s->velocity.data()));
}

StatusOr<Vector6d> SlidingWindowGraph::ImuBias(StateId id) const {
  const State* s = impl_->Find(id);
  if (s == nullptr) return NotFoundError("SlidingWindowGraph::ImuBias: unknown state " + Id(id));
  if (!s->has_bias) return FailedPreconditionError("state " + Id(id) + " has no bias");
  return Vector6d(Eigen::Map<const Vector6d>(s->bias.data()));
}

Status SlidingWindowGraph::SetPose(StateId id, const Eigen::Isometry3d& T) {
  State* s = impl_->Find(id);
  if (s == nullptr) return NotFoundError("SlidingWindowGraph::SetPose: unknown state " + Id(id));
  SLAM_MMS_RETURN_IF_ERROR(ValidatePose(T, "SlidingWindowGraph::SetPose"));
  PoseToBlock(T, s->pose.data());
  return OkStatus();
}

StatusOr<Matrix6d> SlidingWindowGraph::PoseCovariance(StateId id) const {
  const Impl& m = *impl_;
  const State* s = m.Find(id);
  if (s == nullptr)
    return NotFoundError("SlidingWindowGraph::PoseCovariance: unknown state " + Id(id));
  return backend_internal::PoseBlockCovariance(m.problem.get(), s->pose.data(),
                                               m.options.num_threads);
}

const ConsistencyStats& SlidingWindowGraph::consistency_stats() const { return impl_->stats; }
int SlidingWindowGraph::num_factors() const { return static_cast<int>(impl_->factors.size()); }
int SlidingWindowGraph::num_marginalized_states() const { return impl_->num_marginalized; }
const SlidingWindowGraph::Options& SlidingWindowGraph::options() const { return impl_->options; }

}  // namespace slam_mms
