#include "slam_mms/drive/extrinsic_calibrator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "drive/extrinsic_calibration_problem.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {
namespace {

using namespace calib_internal;

// The median (upper for an even count) of `v`; 0 for none.
double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// The scans used (see the header): evenly spaced, inside the POS span, where the POS is as good
// as usual; each subsampled, its time block set. Fills the scan counts and the POS attitude sigma.
StatusOr<std::vector<CalScan>> SelectScans(const DriveReader& reader, const PosTrack& track,
                                           Timestamp t0, double time_offset_initial_s,
                                           const ExtrinsicCalibrationOptions& o,
                                           ExtrinsicCalibration* out) {
  ExtrinsicCalibration& result = *out;
  const size_t n = reader.NumScans();
  // Scans (shifted by the initial offset) inside the POS span by a small margin; a later offset
  // estimate beyond it holds the end pose (PosTrack::At clamps).
  const double margin = 0.05;
  std::vector<size_t> candidates;
  std::vector<double> pos_sigmas;
  for (size_t i = 0; i < n; ++i) {
    const double ts = reader.ScanStart(i).SecondsSince(t0) + time_offset_initial_s;
    const double te = reader.ScanEnd(i).SecondsSince(t0) + time_offset_initial_s;
    if (ts - margin < track.begin() || te + margin > track.end()) continue;
    pos_sigmas.push_back(track.At(ts).pos_sigma_m);
    candidates.push_back(i);
  }
  {
    // The POS where it is as good as usual on this drive: not in outages, where it drifts.
    const double gate = std::min(o.max_pos_sigma_m, o.max_pos_sigma_ratio * Median(pos_sigmas));
    std::vector<size_t> kept;
    for (size_t k = 0; k < candidates.size(); ++k) {
      if (pos_sigmas[k] <= gate) {
        kept.push_back(candidates[k]);
      } else {
        ++result.scans_skipped_pos;
      }
    }
    candidates = std::move(kept);
  }
  const size_t want = std::min(candidates.size(), static_cast<size_t>(o.max_scans));
  std::vector<CalScan> scans;
  std::vector<Eigen::Vector3d> att_sigmas;
  for (size_t k = 0; k < want; ++k) {
    const size_t i = candidates[k * candidates.size() / want];
    StatusOr<Scan> scan = reader.ReadScan(i);
    if (!scan.ok()) {
      SLAM_MMS_LOG(kWarning) << "CalibrateExtrinsics: " << scan.status().ToString()
                             << " (scan skipped)";
      ++result.scans_skipped_unreadable;
      continue;
    }
    CalScan s;
    s.t_start = scan->stamp_start.SecondsSince(t0);
    att_sigmas.push_back(track.At(s.t_start + time_offset_initial_s).att_sigma_rad);
    s.duration = scan->DurationSeconds();
    Subsample(*scan, o, &s);
    if (s.raw.size() < 50) continue;
    scans.push_back(std::move(s));
  }
  if (scans.size() < 10) {
    return FailedPreconditionError(
        "CalibrateExtrinsics: " + std::to_string(scans.size()) +
        " usable scans (need 10; scans outside the POS span or with a POS sigma above " +
        std::to_string(o.max_pos_sigma_m) + " m or " + std::to_string(o.max_pos_sigma_ratio) +
        " x its median are not used: " + std::to_string(result.scans_skipped_pos) +
        " so; median POS sigma " + std::to_string(Median(pos_sigmas)) + " m)");
  }
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> v;
    for (const Eigen::Vector3d& a : att_sigmas) v.push_back(a(axis));
    result.pos_attitude_sigma_rad(axis) = Median(std::move(v));
  }
  const double span = scans.back().t_start - scans.front().t_start;
  for (CalScan& s : scans) {
    s.block = std::min(o.jackknife_blocks - 1,
                       static_cast<int>((s.t_start - scans.front().t_start) / std::max(span, 1e-9) *
                                        o.jackknife_blocks));
  }

  return scans;
}

// Partners of every scan (from the POS at the initial time offset) and the drive's heading change.
void AssignPartners(const PosTrack& track, double time_offset_initial_s,
                    const ExtrinsicCalibrationOptions& o, std::vector<CalScan>* scans_io,
                    ExtrinsicCalibration* out) {
  std::vector<CalScan>& scans = *scans_io;
  ExtrinsicCalibration& result = *out;
  std::vector<Eigen::Vector3d> where(scans.size());
  std::vector<double> when(scans.size());
  double heading = 0.0, last_yaw = 0.0;
  for (size_t i = 0; i < scans.size(); ++i) {
    const PosTrack::Sample s = track.At(scans[i].t_start + time_offset_initial_s);
    where[i] = s.T_world_body.translation();
    when[i] = scans[i].t_start;
    const Eigen::Matrix3d R = s.T_world_body.linear();
    const double yaw = std::atan2(R(1, 0), R(0, 0));
    if (i > 0) heading += std::abs(std::remainder(yaw - last_yaw, 2.0 * M_PI));
    last_yaw = yaw;
  }
  result.total_heading_change_rad = heading;
  for (size_t a = 0; a < scans.size(); ++a) {
    std::vector<int> p;
    const auto add = [&](size_t b) {
      if (b == a || (where[b] - where[a]).norm() > o.max_partner_distance_m) return;
      if (std::find(p.begin(), p.end(), static_cast<int>(b)) == p.end())
        p.push_back(static_cast<int>(b));
    };
    for (double sep : o.partner_separations_s) {
      for (double sign : {-1.0, 1.0}) {
        const double target = when[a] + sign * sep;
        const size_t b =
            static_cast<size_t>(std::lower_bound(when.begin(), when.end(), target) - when.begin());
        size_t best = b < scans.size() ? b : scans.size() - 1;
        if (b > 0 && (b == scans.size() || target - when[b - 1] < when[b] - target)) best = b - 1;
        if (std::abs(when[best] - target) < 0.5 * sep) add(best);
      }
    }
    std::vector<std::pair<double, size_t>> revisits;
    for (size_t b = 0; b < scans.size(); ++b) {
      if (std::abs(when[b] - when[a]) < o.revisit_min_separation_s) continue;
      const double d = (where[b] - where[a]).norm();
      if (d <= o.revisit_max_distance_m) revisits.emplace_back(d, b);
    }
    std::sort(revisits.begin(), revisits.end());
    for (int r = 0; r < std::min<int>(o.max_revisit_partners, revisits.size()); ++r)
      add(revisits[r].second);
    scans[a].partners = std::move(p);
  }
}

// The Gauss-Newton rounds and the sigmas about the prior `initial`, over the 7 parameters and the
// knots of the POS correction (CalibrationProblem::dim(); the knots' prior mean is zero).
class Solver {
 public:
  Solver(CalibrationProblem* cal, const Params& initial, const ExtrinsicCalibrationOptions& o,
         const std::atomic<bool>* stop)
      : cal_(*cal), initial_(initial), o_(o), stop_(stop), prior_(cal->KnotPrior()) {
    Vector7d info;
    info << o.prior_sigma_rpy_rad.cwiseInverse().cwiseAbs2(),
        o.prior_sigma_xyz_m.cwiseInverse().cwiseAbs2(),
        1.0 / (o.prior_sigma_time_s * o.prior_sigma_time_s);
    prior_.diagonal().head<7>() += info;
    knots_ = VectorXd::Zero(3 * cal->num_knots());
    cal_.SetShifts(knots_);
  }

  const VectorXd& knots() const { return knots_; }

  // Rounds of re-de-skew, re-association and Gauss-Newton steps from *p over the free set `fr`
  // (the knots always free); `last` gets the associations of the last round.
  Status Solve(Params* p, const std::array<bool, 7>& fr, int rounds, std::vector<Association>* last,
               ExtrinsicCalibration* result) {
    for (int round = 0; round < rounds; ++round) {
      if (stop_ != nullptr && stop_->load()) {
        return FailedPreconditionError("CalibrateExtrinsics: stopped");
      }
      const double f = rounds > 1 ? std::min(1.0, round / 4.0) : 1.0;
      const double gate = o_.initial_gate_m * std::pow(o_.final_gate_m / o_.initial_gate_m, f);
      cal_.UpdatePoses(*p);
      cal_.Deskew(*p);
      *last = cal_.Associate(*p, gate);
      if (last->size() < 100) {
        return FailedPreconditionError("CalibrateExtrinsics: " + std::to_string(last->size()) +
                                       " point-to-plane associations (need 100): the scans do not "
                                       "overlap or the initial extrinsic is far off");
      }
      double step_norm = 0.0;
      for (int it = 0; it < o_.gauss_newton_steps_per_round; ++it) {
        const std::vector<CalibrationProblem::Normal> nb = cal_.Accumulate(*last, *p, 1);
        // Data weighted by the residual variance, so that the prior has its stated weight.
        const double s2 = std::max(nb[0].wrr / std::max(1.0, nb[0].n - 7.0), 1e-6);
        const VectorXd d = SolveStep(nb[0].H / s2, nb[0].g / s2, Offset(*p), prior_, fr);
        Apply(d.head<7>(), p);
        knots_ += d.tail(knots_.size());
        cal_.UpdatePoses(*p);
        cal_.SetShifts(knots_);
        step_norm = std::max(
            {d.head<3>().norm() / 1e-5, d.segment<3>(3).norm() / 1e-4, std::abs(d(6)) / 1e-5});
      }
      result->rounds = round + 1;
      result->converged = f >= 1.0 && step_norm < 1.0;
      if (result->converged) break;
    }
    return OkStatus();
  }

  // Formal and jackknife (over time blocks) sigmas of the 7 from the normal equations at `at`
  // (the knots marginalised), and the systematic floor.
  void Sigmas(const Params& at, const std::array<bool, 7>& fr, const std::vector<Association>& last,
              Vector7d* formal, Vector7d* jack, Vector7d* floor) const {
    const std::vector<CalibrationProblem::Normal> blocks =
        cal_.Accumulate(last, at, o_.jackknife_blocks);
    CalibrationProblem::Normal all(cal_.dim());
    for (const auto& b : blocks) all += b;
    const double dof = std::max<double>(1.0, static_cast<double>(all.n) - 7.0);
    const double s2 = all.wrr / dof;
    const VectorXd off = Offset(at);
    const MatrixXd cov = WithPriorAndFixed(all.H / s2, prior_, fr).inverse();
    for (int i = 0; i < 7; ++i) (*formal)(i) = fr[i] ? std::sqrt(std::max(0.0, cov(i, i))) : 0.0;
    // The systematic floor: a parameter whose unit change moves the residuals by `sensitivity`
    // (weighted RMS; the part the POS correction cannot take: the Schur complement onto the 7)
    // cannot be known better than systematic_error_m / sensitivity, however many residuals there
    // are.
    Matrix7d S = all.H.topLeftCorner<7, 7>();
    const int nk = cal_.dim() - 7;
    if (nk > 0) {
      const MatrixXd Hkk = all.H.bottomRightCorner(nk, nk) + s2 * prior_.bottomRightCorner(nk, nk);
      const MatrixXd Hkp = all.H.bottomLeftCorner(nk, 7);
      S -= Hkp.transpose() * Hkk.ldlt().solve(Hkp);
    }
    for (int i = 0; i < 7; ++i) {
      const double sensitivity = std::sqrt(std::max(0.0, S(i, i)) / std::max(all.w, 1e-12));
      (*floor)(i) = fr[i] ? o_.systematic_error_m / std::max(sensitivity, 1e-12) : 0.0;
    }
    std::vector<Vector7d> loo;
    for (const auto& b : blocks) {
      if (b.n == 0) continue;
      loo.push_back(SolveStep((all.H - b.H) / s2, (all.g - b.g) / s2, off, prior_, fr).head<7>());
    }
    jack->setZero();
    if (loo.size() >= 2) {
      Vector7d mean = Vector7d::Zero();
      for (const auto& d : loo) mean += d;
      mean /= loo.size();
      for (const auto& d : loo) jack->array() += (d - mean).array().square();
      const double k = static_cast<double>(loo.size());
      *jack = (*jack * (k - 1.0) / k).cwiseSqrt();
    }
  }

 private:
  // The parameters' offset from the prior mean: [p - initial, knots].
  VectorXd Offset(const Params& p) const {
    VectorXd off(cal_.dim());
    off.head<7>() = Difference(p, initial_);
    off.tail(knots_.size()) = knots_;
    return off;
  }

  CalibrationProblem& cal_;
  const Params initial_;
  const ExtrinsicCalibrationOptions& o_;
  const std::atomic<bool>* stop_;
  MatrixXd prior_;
  VectorXd knots_;
};

// kTravelDirection: the POS's mean heading error from its own velocity (see the header).
struct TravelReference {
  bool found = false;
  double eps_z = 0.0;  // [rad]
  double sigma = 0.0;  // its standard error and the travel allowance [rad]
  int samples = 0;
};

TravelReference EstimateTravelReference(const CalibrationProblem& cal, const PosTrack& track,
                                        const ExtrinsicCalibrationOptions& o, double time_offset) {
  // The POS's mean heading error from its own velocity in its body frame (v_body =
  // v (1, -eps_z, eps_y) for an attitude error R_est = R_true Exp(eps)), per time block; the map
  // placed the scans with R_est, so the extrinsic in the true body frame is Exp(eps) X. Heading
  // only: the vertical velocity of a GNSS/INS is too noisy for pitch (0.03-0.27 deg off on the
  // simulated drives), while its roll and pitch, levelled by gravity, are good.
  std::vector<double> block_sum(o.jackknife_blocks, 0.0);
  std::vector<int> block_n(o.jackknife_blocks, 0);
  for (const CalScan& sc : cal.scans()) {
    const PosTrack::Sample smp = track.At(sc.t_start + time_offset);
    const double speed = smp.v_world.norm();
    if (speed < o.travel_min_speed_mps ||
        std::abs(smp.omega_world.z()) > o.travel_max_yaw_rate_radps) {
      continue;
    }
    const Eigen::Vector3d vb = smp.T_world_body.linear().transpose() * smp.v_world;
    block_sum[sc.block] -= std::atan2(vb.y(), vb.x());
    ++block_n[sc.block];
  }
  std::vector<double> means;
  double total = 0.0;
  TravelReference ref;
  for (int b = 0; b < o.jackknife_blocks; ++b) {
    if (block_n[b] == 0) continue;
    means.push_back(block_sum[b] / block_n[b]);
    total += block_sum[b];
    ref.samples += block_n[b];
  }
  if (means.size() < 2) {
    SLAM_MMS_LOG(kWarning) << "CalibrateExtrinsics: too few straight stretches above "
                           << o.travel_min_speed_mps
                           << " m/s for the travel-direction attitude reference; the POS "
                              "attitude is the reference";
    return ref;
  }
  ref.found = true;
  ref.eps_z = total / ref.samples;
  double var = 0.0;
  for (const double m : means) var += (m - ref.eps_z) * (m - ref.eps_z);
  const double sem = std::sqrt(var / static_cast<double>(means.size() * (means.size() - 1)));
  ref.sigma = std::hypot(sem, o.travel_sigma_rad);
  return ref;
}

// Moves the applied yaw (and the applied lever arm components it turns) to the travel frame.
void ApplyTravelReference(const TravelReference& ref, const std::array<bool, 7>& applied,
                          Params* p_io, ExtrinsicCalibration* out) {
  Params& p = *p_io;
  ExtrinsicCalibration& result = *out;
  result.travel_samples = ref.samples;
  if (!ref.found) return;
  result.travel_correction_rad = Eigen::Vector3d(0.0, 0.0, ref.eps_z);
  result.attitude_reference = "travel_direction";
  result.pos_attitude_sigma_rad(2) = ref.sigma;
  Eigen::Vector3d e = result.travel_correction_rad;
  if (!applied[2]) e(2) = 0.0;
  const Eigen::Matrix3d Re = so3::Exp(e);
  p.R = Re * p.R;
  if (applied[3] || applied[4] || applied[5]) {
    const Eigen::Vector3d t_rot = Re * p.t;
    for (int i = 0; i < 3; ++i) {
      if (applied[3 + i]) p.t(i) = t_rot(i);
    }
  }
}

// ExtrinsicCalibration's pos_drift_* from the knots (3 per knot, `interval` [s] apart).
void SummarisePosDrift(const VectorXd& knots, double interval, ExtrinsicCalibration* out) {
  const int nk = static_cast<int>(knots.size() / 3);
  if (nk == 0) return;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), rate2 = Eigen::Vector3d::Zero();
  for (int i = 0; i < nk; ++i) mean += knots.segment<3>(3 * i) / nk;
  for (int i = 0; i < nk; ++i) {
    out->pos_drift_max_m = std::max(out->pos_drift_max_m, (knots.segment<3>(3 * i) - mean).norm());
    if (i + 1 < nk) rate2 += (knots.segment<3>(3 * i + 3) - knots.segment<3>(3 * i)).cwiseAbs2();
  }
  out->pos_drift_knots = nk;
  out->pos_drift_rate_rms_mps = (rate2 / std::max(1, nk - 1)).cwiseSqrt() / interval;
}

}  // namespace

const char* ExtrinsicParameterName(int i) {
  static const char* kNames[7] = {"roll", "pitch", "yaw", "x", "y", "z", "time_offset"};
  return i >= 0 && i < 7 ? kNames[i] : "?";
}

StatusOr<ExtrinsicCalibration> CalibrateExtrinsics(const DriveReader& reader,
                                                   const std::vector<InsState>& pos,
                                                   const Eigen::Isometry3d& T_body_lidar_initial,
                                                   double time_offset_initial_s,
                                                   const ExtrinsicCalibrationOptions& o,
                                                   const std::atomic<bool>* stop, int num_threads) {
  const auto t_wall = std::chrono::steady_clock::now();
  SLAM_MMS_RETURN_IF_ERROR(o.Validate());
  if (num_threads < 1) {
    return InvalidArgumentError(
        "CalibrateExtrinsics: num_threads = " + std::to_string(num_threads) + "; must be >= 1");
  }
  const Eigen::Matrix3d R0 = T_body_lidar_initial.linear();
  if (!T_body_lidar_initial.matrix().allFinite() ||
      (R0.transpose() * R0 - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() > 1e-6 ||
      R0.determinant() < 0.0 || !std::isfinite(time_offset_initial_s)) {
    return InvalidArgumentError("CalibrateExtrinsics: the initial T_body_lidar is not rigid");
  }
  if (pos.size() < 2) return InvalidArgumentError("CalibrateExtrinsics: fewer than 2 POS states");
  for (size_t i = 1; i < pos.size(); ++i) {
    if (!(pos[i - 1].stamp < pos[i].stamp)) {
      return InvalidArgumentError("CalibrateExtrinsics: POS stamps not increasing at state " +
                                  std::to_string(i));
    }
  }
  const Timestamp t0 = pos.front().stamp;
  const PosTrack track(pos, t0);
  ExtrinsicCalibration result;
  result.T_body_lidar_initial = T_body_lidar_initial;
  result.time_offset_initial_s = time_offset_initial_s;

  SLAM_MMS_ASSIGN_OR_RETURN(std::vector<CalScan> scans,
                            SelectScans(reader, track, t0, time_offset_initial_s, o, &result));
  AssignPartners(track, time_offset_initial_s, o, &scans, &result);

  CalibrationProblem cal(std::move(scans), track, o, num_threads);
  result.scans_used = static_cast<int>(cal.scans().size());
  Params initial;
  initial.R = R0;
  initial.t = T_body_lidar_initial.translation();
  initial.time = time_offset_initial_s;
  std::array<bool, 7> free{};
  for (int i = 0; i < 3; ++i) free[i] = o.estimate_rotation;
  for (int i = 3; i < 6; ++i) free[i] = o.estimate_translation;
  free[6] = o.estimate_time_offset;
  Solver solver(&cal, initial, o, stop);

  // RMS at the initial value (final gate).
  cal.UpdatePoses(initial);
  cal.Deskew(initial);
  result.rms_initial_m = cal.Rms(cal.Associate(initial, o.final_gate_m), initial);

  Params p = initial;
  std::vector<Association> last;
  SLAM_MMS_RETURN_IF_ERROR(solver.Solve(&p, free, o.max_rounds, &last, &result));

  Vector7d formal, jack, floor;
  solver.Sigmas(p, free, last, &formal, &jack, &floor);
  result.formal_sigma = formal;
  result.jackknife_sigma = jack;
  result.systematic_sigma = floor;
  Vector7d prior_sigma;
  prior_sigma << o.prior_sigma_rpy_rad, o.prior_sigma_xyz_m, o.prior_sigma_time_s;
  Vector7d max_sigma;
  max_sigma << Eigen::Vector3d::Constant(o.max_sigma_rpy_rad),
      Eigen::Vector3d::Constant(o.max_sigma_xyz_m), o.max_sigma_time_s;
  TravelReference travel;
  if (o.attitude_reference == ExtrinsicCalibrationOptions::AttitudeReference::kTravelDirection) {
    travel = EstimateTravelReference(cal, track, o, p.time);
  }
  std::array<bool, 7> observable{}, applied{};
  bool all_applied = true;
  {
    // The correction of the first solve over its sigma (rotations in the reported roll, pitch,
    // yaw terms, with the attitude reference's sigma; the yaw in the travel frame with that one's).
    Vector7d corr;
    corr << RollPitchYaw(p.R * initial.R.transpose()), p.t - initial.t, p.time - initial.time;
    Eigen::Vector3d reference_sigma = result.pos_attitude_sigma_rad;
    if (travel.found) {
      corr(2) += travel.eps_z;
      reference_sigma(2) = travel.sigma;
    }
    const Vector7d data_sigma = formal.cwiseMax(jack).cwiseMax(floor);
    for (int i = 0; i < 7; ++i) {
      const double s = data_sigma(i);
      observable[i] = free[i] && s <= max_sigma(i) && s * o.min_prior_reduction <= prior_sigma(i);
      const double total = i < 3 ? std::hypot(s, reference_sigma(i)) : s;
      result.significance(i) = free[i] ? std::abs(corr(i)) / std::max(total, 1e-12) : 0.0;
      applied[i] = observable[i] && result.significance(i) >= o.min_significance;
      if (free[i] && !applied[i]) all_applied = false;
    }
  }
  if (!all_applied) {
    // Hold the others at their initial values and solve the applied ones again.
    std::array<bool, 7> fr = applied;
    const Vector7d off = Difference(p, initial);
    Params q = initial;
    Eigen::Vector3d keep_rot = off.head<3>();
    for (int i = 0; i < 3; ++i) {
      if (!fr[i]) keep_rot(i) = 0.0;
      if (fr[3 + i]) q.t(i) = p.t(i);
    }
    q.R = so3::Exp(keep_rot) * initial.R;
    if (fr[6]) q.time = p.time;
    // (The knots again too: they took what the held ones leave.)
    if (cal.num_knots() > 0 || std::any_of(fr.begin(), fr.end(), [](bool b) { return b; })) {
      SLAM_MMS_RETURN_IF_ERROR(solver.Solve(&q, fr, std::max(3, o.max_rounds / 2), &last, &result));
    }
    p = q;
    Vector7d f2, j2, s2;
    solver.Sigmas(p, fr, last, &f2, &j2, &s2);
    formal = f2;
    jack = j2;
    floor = s2;
  }
  result.observable = observable;
  result.applied = applied;
  SummarisePosDrift(solver.knots(), o.pos_drift_knot_interval_s, &result);
  cal.Deskew(p);
  result.rms_final_m = cal.Rms(cal.Associate(p, o.final_gate_m), p);
  if (o.attitude_reference == ExtrinsicCalibrationOptions::AttitudeReference::kTravelDirection) {
    ApplyTravelReference(travel, applied, &p, &result);
  }
  {
    // Held rotation axes exactly at the initial value in the reported (roll, pitch, yaw) terms
    // (the steps kept them at zero to first order only).
    Eigen::Vector3d rpy = RollPitchYaw(p.R * initial.R.transpose());
    bool changed = false;
    for (int i = 0; i < 3; ++i) {
      if (!applied[i] && rpy(i) != 0.0) {
        rpy(i) = 0.0;
        changed = true;
      }
    }
    if (changed) p.R = FromRollPitchYaw(rpy(0), rpy(1), rpy(2)) * initial.R;
  }
  const Vector7d corr = Difference(p, initial);
  result.T_body_lidar_estimated = p.X();
  result.time_offset_s = p.time;
  result.correction_rpy_rad = RollPitchYaw(p.R * initial.R.transpose());
  result.correction_xyz_m = corr.segment<3>(3);
  const Vector7d data_sigma = formal.cwiseMax(jack).cwiseMax(floor);
  for (int i = 0; i < 3; ++i) {
    result.sigma_rpy_rad(i) =
        applied[i] ? std::hypot(data_sigma(i), result.pos_attitude_sigma_rad(i)) : 0.0;
    result.sigma_xyz_m(i) = applied[3 + i] ? data_sigma(3 + i) : 0.0;
  }
  result.sigma_time_s = applied[6] ? data_sigma(6) : 0.0;
  result.residuals = last.size();
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_wall).count();
  return result;
}

}  // namespace slam_mms
