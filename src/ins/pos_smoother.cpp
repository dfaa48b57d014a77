#include "ins/pos_smoother.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <string>

#include "ins/ins_filter_impl.hpp"  // the error-state layout and PoseCovariance
#include "slam_mms/core/lie.hpp"

namespace slam_mms {
namespace {

// The parts of the filter's state beside InsState: the GNSS bias and the IMU-to-vehicle
// misalignment.
struct Auxiliary {
  Eigen::Vector3d bn = Eigen::Vector3d::Zero();
  Eigen::Vector2d m = Eigen::Vector2d::Zero();
  Eigen::Vector2d l = Eigen::Vector2d::Zero();
};

// a [-] b in the filter's error definition (a = b [+] d).
InsErrorVector BoxMinus(const InsState& a, const Auxiliary& aux_a, const InsState& b,
                        const Auxiliary& aux_b) {
  InsErrorVector d;
  d.segment<3>(kP) = a.T_world_body.translation() - b.T_world_body.translation();
  d.segment<3>(kV) = a.v_world_mps - b.v_world_mps;
  d.segment<3>(kTh) = so3::Log(b.T_world_body.linear().transpose() * a.T_world_body.linear());
  d.segment<3>(kBa) = a.accel_bias_mps2 - b.accel_bias_mps2;
  d.segment<3>(kBg) = a.gyro_bias_radps - b.gyro_bias_radps;
  d.segment<3>(kBn) = aux_a.bn - aux_b.bn;
  d.segment<2>(kM) = aux_a.m - aux_b.m;
  d.segment<2>(kL) = aux_a.l - aux_b.l;
  return d;
}

InsState BoxPlus(const InsState& x, const InsErrorVector& d) {
  InsState s = x;
  const Eigen::Matrix3d R = x.T_world_body.linear() * so3::Exp(d.segment<3>(kTh));
  s.T_world_body =
      MakeIsometry(Eigen::Quaterniond(R).normalized(), x.T_world_body.translation() + d.head<3>());
  s.v_world_mps += d.segment<3>(kV);
  s.accel_bias_mps2 += d.segment<3>(kBa);
  s.gyro_bias_radps += d.segment<3>(kBg);
  return s;
}

bool FiniteState(const InsState& s) {
  return s.T_world_body.matrix().allFinite() && s.v_world_mps.allFinite() &&
         s.accel_bias_mps2.allFinite() && s.gyro_bias_radps.allFinite();
}

}  // namespace

Status PosSmoother::Options::Validate() const {
  SLAM_MMS_RETURN_IF_ERROR(ins.Validate());
  for (size_t i = 0; i < gnss_outages.size(); ++i) {
    const auto& [start, duration] = gnss_outages[i];
    if (!std::isfinite(start) || !(duration > 0.0) || !std::isfinite(duration)) {
      return InvalidArgumentError("PosSmoother::Options::gnss_outages[" + std::to_string(i) +
                                  "] = (" + std::to_string(start) + ", " +
                                  std::to_string(duration) +
                                  "); start must be finite and duration > 0");
    }
  }
  if (origin && (!(std::abs(origin->latitude_deg) <= 90.0) ||
                 !(std::abs(origin->longitude_deg) <= 180.0) || !std::isfinite(origin->height_m))) {
    return InvalidArgumentError("PosSmoother::Options::origin is outside the WGS-84 range");
  }
  return OkStatus();
}

StatusOr<std::vector<InsState>> PosSmoother::Smooth(const std::vector<InsFilterStep>& steps) {
  return Smooth(steps, nullptr);
}

StatusOr<std::vector<InsState>> PosSmoother::Smooth(const std::vector<InsFilterStep>& steps,
                                                    std::vector<InsErrorMatrix>* P_smoothed) {
  const size_t n = steps.size();
  if (n == 0) return InvalidArgumentError("PosSmoother::Smooth: no recorded step");
  for (size_t k = 0; k < n; ++k) {
    const InsFilterStep& s = steps[k];
    if (k > 0 && !(steps[k - 1].stamp < s.stamp)) {
      return InvalidArgumentError("PosSmoother::Smooth: step " + std::to_string(k) +
                                  " is not after the previous one");
    }
    if (!FiniteState(s.prior) || !FiniteState(s.posterior) || !s.P_prior.allFinite() ||
        !s.P_posterior.allFinite() || !s.F.allFinite() || !s.gnss_bias_prior.allFinite() ||
        !s.gnss_bias_posterior.allFinite() || !s.vehicle_misalignment_prior.allFinite() ||
        !s.vehicle_misalignment_posterior.allFinite() ||
        !s.vehicle_lateral_model_prior.allFinite() ||
        !s.vehicle_lateral_model_posterior.allFinite()) {
      return InvalidArgumentError("PosSmoother::Smooth: step " + std::to_string(k) +
                                  " holds a non-finite state, covariance or transition");
    }
  }
  std::vector<InsState> xs(n);
  std::vector<Auxiliary> aux(n);
  const auto prior_aux = [](const InsFilterStep& s) {
    return Auxiliary{s.gnss_bias_prior, s.vehicle_misalignment_prior,
                     s.vehicle_lateral_model_prior};
  };
  const auto posterior_aux = [](const InsFilterStep& s) {
    return Auxiliary{s.gnss_bias_posterior, s.vehicle_misalignment_posterior,
                     s.vehicle_lateral_model_posterior};
  };
  std::vector<InsErrorMatrix> Ps(n);
  xs[n - 1] = steps[n - 1].posterior;
  aux[n - 1] = posterior_aux(steps[n - 1]);
  Ps[n - 1] = steps[n - 1].P_posterior;
  for (size_t k = n - 1; k-- > 0;) {
    const InsFilterStep& cur = steps[k];
    const InsFilterStep& next = steps[k + 1];
    // C^T = (P_{k+1}^-)^-1 F_{k+1} P_k^+, solved on the diagonally scaled covariance (its entries
    // span ~12 orders of magnitude: m^2 against (rad/s)^2).
    const InsErrorVector d = next.P_prior.diagonal();
    if (!(d.minCoeff() > 0.0)) {
      return InvalidArgumentError("PosSmoother::Smooth: step " + std::to_string(k + 1) +
                                  " has an a-priori covariance that is not positive definite");
    }
    const InsErrorVector s = d.cwiseSqrt().cwiseInverse();
    const InsErrorMatrix P_scaled = s.asDiagonal() * next.P_prior * s.asDiagonal();
    const Eigen::LLT<InsErrorMatrix> llt(P_scaled);
    if (llt.info() != Eigen::Success) {
      return InvalidArgumentError("PosSmoother::Smooth: step " + std::to_string(k + 1) +
                                  " has an a-priori covariance that is not positive definite");
    }
    const InsErrorMatrix Ct =
        s.asDiagonal() * llt.solve(s.asDiagonal() * (next.F * cur.P_posterior));
    const InsErrorMatrix C = Ct.transpose();
    const InsErrorVector dx = C * BoxMinus(xs[k + 1], aux[k + 1], next.prior, prior_aux(next));
    InsErrorMatrix P = cur.P_posterior + C * (Ps[k + 1] - next.P_prior) * Ct;
    Ps[k] = 0.5 * (P + P.transpose());
    xs[k] = BoxPlus(cur.posterior, dx);
    aux[k] = posterior_aux(cur);
    aux[k].bn += dx.segment<3>(kBn);
    aux[k].m += dx.segment<2>(kM);
    aux[k].l += dx.segment<2>(kL);
  }
  for (size_t k = 0; k < n; ++k) {
    xs[k].stamp = steps[k].stamp;
    xs[k].cov_T_world_body = PoseCovariance(Ps[k], xs[k].T_world_body.linear());
  }
  if (P_smoothed != nullptr) *P_smoothed = std::move(Ps);
  return xs;
}

StatusOr<PosSmoother::Result> PosSmoother::Run(const Options& options,
                                               const std::vector<ImuSample>& imu,
                                               const std::vector<GnssFix>& gnss,
                                               const std::optional<InsState>& initial) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (!initial) {
    return FailedPreconditionError(
        "PosSmoother::Run: no initial attitude and velocity (the forward filter starts from an "
        "initial state, e.g. the drive's first OXTS record or initial_state.csv)");
  }
  InsFilter::Options fo = options.ins;
  fo.record_steps = true;
  SLAM_MMS_ASSIGN_OR_RETURN(InsFilter filter, InsFilter::Create(fo));
  GnssPrior& prior = filter.mutable_gnss_prior();
  if (options.origin) SLAM_MMS_RETURN_IF_ERROR(prior.SetOrigin(*options.origin));
  if (options.outage_reference) prior.SetReferenceTime(*options.outage_reference);
  for (const auto& [start, duration] : options.gnss_outages) {
    SLAM_MMS_RETURN_IF_ERROR(prior.AddOutageWindow(start, duration));
  }
  SLAM_MMS_RETURN_IF_ERROR(filter.InitializeAttitude(
      Eigen::Quaterniond(initial->T_world_body.linear()), initial->v_world_mps, initial->stamp,
      options.initial_sigma_rpy_rad));
  // Time-ordered merge, IMU first at equal stamps (as RunDrive feeds MappingSystem).
  size_t i = 0, j = 0;
  while (i < imu.size() || j < gnss.size()) {
    if (j >= gnss.size() || (i < imu.size() && imu[i].stamp <= gnss[j].stamp)) {
      const Status s = filter.AddImu(imu[i]);
      if (!s.ok()) return s.WithContext("PosSmoother::Run: IMU sample " + std::to_string(i));
      ++i;
    } else {
      if (j > 0 && !(gnss[j - 1].stamp < gnss[j].stamp)) {
        return InvalidArgumentError("PosSmoother::Run: GNSS fix " + std::to_string(j) +
                                    " is not after the previous one");
      }
      const StatusOr<GnssDecisionResult> r = filter.AddGnss(gnss[j]);
      if (!r.ok()) {
        return r.status().WithContext("PosSmoother::Run: GNSS fix " + std::to_string(j));
      }
      ++j;
    }
  }
  if (!filter.initialized() || filter.Steps().empty()) {
    return FailedPreconditionError(
        "PosSmoother::Run: no usable GNSS fix started the forward filter");
  }
  Result result;
  const std::vector<InsFilterStep>& steps = filter.Steps();
  result.forward.reserve(steps.size());
  for (const InsFilterStep& s : steps) result.forward.push_back(s.posterior);
  SLAM_MMS_ASSIGN_OR_RETURN(result.smoothed, Smooth(steps));
  result.origin = prior.origin();
  result.availability = prior.AvailabilityIntervals();
  result.gnss_used = prior.num_used() + prior.num_downweighted();
  return result;
}

}  // namespace slam_mms
