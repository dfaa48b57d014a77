#include "slam_mms/pipeline/extrinsic_calibrator.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <nanoflann.hpp>
#include <string>
#include <unordered_set>

#include "core/worker_pool.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {
namespace {

using Vector7d = Eigen::Matrix<double, 7, 1>;
using Matrix7d = Eigen::Matrix<double, 7, 7>;

Status FieldError(const std::string& field, double value, const std::string& rule) {
  return InvalidArgumentError("ExtrinsicCalibrationOptions::" + field + " = " +
                              std::to_string(value) + "; " + rule);
}

// ---- The POS as a continuous trajectory ---------------------------------------------------------

// T_world_body(t), its linear and angular velocity in world, and its position sigma, from the
// POS states (linear interpolation of position and velocity, geodesic of attitude).
class PosTrack {
 public:
  PosTrack(const std::vector<InsState>& states, Timestamp t0) : states_(states) {
    t_.reserve(states.size());
    for (const InsState& s : states) t_.push_back(s.stamp.SecondsSince(t0));
  }
  double begin() const { return t_.front(); }
  double end() const { return t_.back(); }

  struct Sample {
    Eigen::Isometry3d T_world_body = Eigen::Isometry3d::Identity();
    Eigen::Vector3d omega_world = Eigen::Vector3d::Zero();  // [rad/s]
    Eigen::Vector3d v_world = Eigen::Vector3d::Zero();      // [m/s]
    double pos_sigma_m = 0.0;
    Eigen::Vector3d att_sigma_rad = Eigen::Vector3d::Zero();  // about the body axes
  };
  Sample At(double t) const {
    const size_t n = t_.size();
    size_t k = static_cast<size_t>(std::upper_bound(t_.begin(), t_.end(), t) - t_.begin());
    k = std::clamp<size_t>(k, 1, n - 1) - 1;  // interval [k, k+1]
    const double dt = t_[k + 1] - t_[k];
    const double a = std::clamp((t - t_[k]) / dt, 0.0, 1.0);
    const InsState& s0 = states_[k];
    const InsState& s1 = states_[k + 1];
    const Eigen::Matrix3d R0 = s0.T_world_body.linear();
    const Eigen::Vector3d w = so3::Log(Eigen::Matrix3d(s1.T_world_body.linear() * R0.transpose()));
    Sample out;
    out.T_world_body.linear() = so3::Exp(Eigen::Vector3d(a * w)) * R0;
    out.T_world_body.translation() =
        (1.0 - a) * s0.T_world_body.translation() + a * s1.T_world_body.translation();
    out.omega_world = w / dt;
    out.v_world = (s1.T_world_body.translation() - s0.T_world_body.translation()) / dt;
    const InsState& near = a < 0.5 ? s0 : s1;
    out.pos_sigma_m = std::sqrt(near.cov_T_world_body.block<3, 3>(3, 3).diagonal().maxCoeff());
    out.att_sigma_rad = near.cov_T_world_body.diagonal().head<3>().cwiseMax(0.0).cwiseSqrt();
    return out;
  }

 private:
  const std::vector<InsState>& states_;
  std::vector<double> t_;
};

// ---- Scans -------------------------------------------------------------------------------------

struct CloudAdaptor {
  const std::vector<Eigen::Vector3f>* pts = nullptr;
  size_t kdtree_get_point_count() const { return pts->size(); }
  float kdtree_get_pt(size_t i, size_t d) const { return (*pts)[i][static_cast<int>(d)]; }
  template <class BBox>
  bool kdtree_get_bbox(BBox& /*bb*/) const {
    return false;
  }
};
using KdTree = nanoflann::KDTreeSingleIndexAdaptor<
    nanoflann::L2_Simple_Adaptor<float, CloudAdaptor, float, uint32_t>, CloudAdaptor, 3, uint32_t>;

struct CalScan {
  double t_start = 0.0;  // LiDAR stamp of the first firing, seconds from t0 (LiDAR clock)
  double duration = 0.0;
  std::vector<Eigen::Vector3f> raw;  // lidar frame, not de-skewed
  std::vector<float> tau;            // per point, from t_start
  std::vector<Eigen::Vector3f> q;    // de-skewed into the lidar frame at t_start
  CloudAdaptor adaptor;
  std::unique_ptr<KdTree> tree;
  std::vector<int> partners;
  PosTrack::Sample pose;  // body at t_start + dt
  int block = 0;          // jackknife block
};

// One point of scan a against the plane (c, n) of partner scan b, both in their lidar frames.
struct Association {
  int a = 0, b = 0;
  Eigen::Vector3d q, c, n;
};

// Per-scan voxel subsample in the lidar frame (first point of each voxel in scan order).
void Subsample(const Scan& scan, const ExtrinsicCalibrationOptions& o, CalScan* out) {
  std::unordered_set<uint64_t> seen;
  const auto& pts = scan.cloud.points();
  const auto& tau = scan.cloud.time_offsets_s();
  const bool have_tau = tau.size() == pts.size();
  const double inv = 1.0 / o.voxel_m;
  std::vector<size_t> keep;
  for (size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3f& p = pts[i];
    const double r = p.norm();
    if (!(r >= o.min_range_m && r <= o.max_range_m)) continue;
    const auto key = [&](int d) {
      return static_cast<uint64_t>(static_cast<int64_t>(std::floor(p[d] * inv)) + (1 << 20)) &
             0x1FFFFF;
    };
    const uint64_t k = key(0) | (key(1) << 21) | (key(2) << 42);
    if (seen.insert(k).second) keep.push_back(i);
  }
  const size_t m = static_cast<size_t>(o.max_points_per_scan);
  const double step = keep.size() > m ? static_cast<double>(keep.size()) / m : 1.0;
  for (double f = 0.0; f < keep.size() && out->raw.size() < m; f += step) {
    const size_t i = keep[static_cast<size_t>(f)];
    out->raw.push_back(pts[i]);
    out->tau.push_back(have_tau ? tau[i] : 0.0f);
  }
}

// The 7-vector of a correction: [phi (left rotation about body axes), dt_xyz, dtime].
struct Params {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();  // R_body_lidar
  Eigen::Vector3d t = Eigen::Vector3d::Zero();      // t_body_lidar
  double time = 0.0;                                // lidar_time_offset_s
  Eigen::Isometry3d X() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = R;
    T.translation() = t;
    return T;
  }
};

Vector7d Difference(const Params& p, const Params& p0) {
  Vector7d d;
  d.head<3>() = so3::Log(Eigen::Matrix3d(p.R * p0.R.transpose()));
  d.segment<3>(3) = p.t - p0.t;
  d(6) = p.time - p0.time;
  return d;
}

void Apply(const Vector7d& d, Params* p) {
  p->R = so3::Exp(Eigen::Vector3d(d.head<3>())) * p->R;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(p->R, Eigen::ComputeFullU | Eigen::ComputeFullV);
  p->R = svd.matrixU() * svd.matrixV().transpose();
  p->t += d.segment<3>(3);
  p->time += d(6);
}

class Calibrator {
 public:
  Calibrator(std::vector<CalScan> scans, const PosTrack& pos, const ExtrinsicCalibrationOptions& o)
      : scans_(std::move(scans)), pos_(pos), o_(o), pool_(std::max(1, o.num_threads)) {}

  std::vector<CalScan>& scans() { return scans_; }

  // Poses at scan starts for the time offset of `p`.
  void UpdatePoses(const Params& p) {
    for (CalScan& s : scans_) s.pose = pos_.At(s.t_start + p.time);
  }

  // De-skews every scan with the POS into its lidar frame at t_start and rebuilds its tree.
  void Deskew(const Params& p) {
    const Eigen::Isometry3d X = p.X();
    const Eigen::Isometry3d Xinv = X.inverse();
    ParallelFor(scans_.size(), [&](size_t i) {
      CalScan& s = scans_[i];
      constexpr int kKnots = 20;
      Eigen::Isometry3d A[kKnots + 1];
      const Eigen::Isometry3d P0inv = pos_.At(s.t_start + p.time).T_world_body.inverse();
      const double d = std::max(s.duration, 1e-6);
      for (int k = 0; k <= kKnots; ++k) {
        A[k] = Xinv * P0inv * pos_.At(s.t_start + p.time + d * k / kKnots).T_world_body * X;
      }
      s.q.resize(s.raw.size());
      for (size_t j = 0; j < s.raw.size(); ++j) {
        const double u = std::clamp(static_cast<double>(s.tau[j]) / d, 0.0, 1.0) * kKnots;
        const int k = std::min(static_cast<int>(u), kKnots - 1);
        const double a = u - k;
        const Eigen::Matrix3d R = (1.0 - a) * A[k].linear() + a * A[k + 1].linear();
        const Eigen::Vector3d t = (1.0 - a) * A[k].translation() + a * A[k + 1].translation();
        s.q[j] = (R * s.raw[j].cast<double>() + t).cast<float>();
      }
      s.adaptor.pts = &s.q;
      s.tree =
          std::make_unique<KdTree>(3, s.adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(10));
      s.tree->buildIndex();
    });
  }

  // Point-to-plane associations at `p` with residual gate `gate`.
  std::vector<Association> Associate(const Params& p, double gate) const {
    const Eigen::Isometry3d X = p.X();
    std::vector<std::vector<Association>> per_scan(scans_.size());
    const int k = o_.num_neighbours;
    const float max_d2 =
        static_cast<float>(o_.max_neighbour_distance_m * o_.max_neighbour_distance_m);
    ParallelFor(scans_.size(), [&](size_t ia) {
      const CalScan& a = scans_[ia];
      if (a.partners.empty()) return;
      const Eigen::Isometry3d Wa = a.pose.T_world_body * X;
      std::vector<uint32_t> idx(k);
      std::vector<float> d2(k);
      int round = 0;
      for (size_t j = 0; j < a.q.size(); j += static_cast<size_t>(o_.query_stride)) {
        for (int m = 0; m < o_.partners_per_point; ++m) {
          const int ib = a.partners[(round++) % a.partners.size()];
          const CalScan& b = scans_[ib];
          const Eigen::Isometry3d Mba = (b.pose.T_world_body * X).inverse() * Wa;
          const Eigen::Vector3d qb = Mba * a.q[j].cast<double>();
          const Eigen::Vector3f qf = qb.cast<float>();
          if (b.tree->knnSearch(qf.data(), k, idx.data(), d2.data()) != static_cast<size_t>(k))
            continue;
          if (d2[k - 1] > max_d2) continue;
          Eigen::Vector3d c = Eigen::Vector3d::Zero();
          for (int i = 0; i < k; ++i) c += b.q[idx[i]].cast<double>();
          c /= k;
          Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
          for (int i = 0; i < k; ++i) {
            const Eigen::Vector3d e = b.q[idx[i]].cast<double>() - c;
            C += e * e.transpose();
          }
          C /= k;
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
          const Eigen::Vector3d ev = es.eigenvalues();
          if (ev(0) > o_.max_plane_thickness_m * o_.max_plane_thickness_m) continue;
          if (ev(1) < 4.0 * ev(0) || ev(1) < 1e-4) continue;
          const Eigen::Vector3d n = es.eigenvectors().col(0);
          if (std::abs(n.dot(qb - c)) > gate) continue;
          per_scan[ia].push_back({static_cast<int>(ia), ib, a.q[j].cast<double>(), c, n});
        }
      }
    });
    std::vector<Association> all;
    for (auto& v : per_scan) all.insert(all.end(), v.begin(), v.end());
    return all;
  }

  // Residual and its Jacobian over [phi, dt_xyz, dtime] (see the header comment).
  double Residual(const Association& s, const Params& p, Vector7d* J) const {
    const CalScan& a = scans_[s.a];
    const CalScan& b = scans_[s.b];
    const Eigen::Matrix3d& Ra = a.pose.T_world_body.linear();
    const Eigen::Matrix3d& Rb = b.pose.T_world_body.linear();
    const Eigen::Vector3d Rq = p.R * s.q, Rc = p.R * s.c, Rn = p.R * s.n;
    const Eigen::Vector3d wa = Ra * (Rq + p.t) + a.pose.T_world_body.translation();
    const Eigen::Vector3d wb = Rb * (Rc + p.t) + b.pose.T_world_body.translation();
    const Eigen::Vector3d nw = Rb * Rn;
    const Eigen::Vector3d d = wa - wb;
    if (J != nullptr) {
      const Eigen::Vector3d na = Ra.transpose() * nw, nb = Rb.transpose() * nw;
      J->head<3>() = Rq.cross(na) - Rc.cross(nb) + Rn.cross(Rb.transpose() * d);
      J->segment<3>(3) = na - nb;
      const Eigen::Vector3d wa_dot =
          a.pose.omega_world.cross(wa - a.pose.T_world_body.translation()) + a.pose.v_world;
      const Eigen::Vector3d wb_dot =
          b.pose.omega_world.cross(wb - b.pose.T_world_body.translation()) + b.pose.v_world;
      (*J)(6) = nw.dot(wa_dot - wb_dot) + b.pose.omega_world.cross(nw).dot(d);
    }
    return nw.dot(d);
  }

  struct Normal {
    Matrix7d H = Matrix7d::Zero();
    Vector7d g = Vector7d::Zero();
    double wrr = 0.0, w = 0.0;
    size_t n = 0;
  };
  // Huber-weighted normal equations, per jackknife block.
  std::vector<Normal> Accumulate(const std::vector<Association>& as, const Params& p,
                                 int blocks) const {
    const int nt = pool_.num_threads();
    std::vector<std::vector<Normal>> part(nt, std::vector<Normal>(blocks));
    pool_.Run([&](int t) {
      size_t begin, end;
      pool_.Range(t, as.size(), &begin, &end);
      Vector7d J;
      for (size_t i = begin; i < end; ++i) {
        const double r = Residual(as[i], p, &J);
        const double ar = std::abs(r);
        const double w = ar <= o_.huber_m ? 1.0 : o_.huber_m / ar;
        Normal& nrm = part[t][blocks == 1 ? 0 : scans_[as[i].a].block];
        nrm.H.selfadjointView<Eigen::Lower>().rankUpdate(J, w);
        nrm.g += w * r * J;
        nrm.wrr += w * r * r;
        nrm.w += w;
        ++nrm.n;
      }
    });
    std::vector<Normal> out(blocks);
    for (int t = 0; t < nt; ++t) {
      for (int b = 0; b < blocks; ++b) {
        out[b].H += part[t][b].H;
        out[b].g += part[t][b].g;
        out[b].wrr += part[t][b].wrr;
        out[b].w += part[t][b].w;
        out[b].n += part[t][b].n;
      }
    }
    for (Normal& nrm : out) nrm.H = nrm.H.selfadjointView<Eigen::Lower>();
    return out;
  }

  double Rms(const std::vector<Association>& as, const Params& p) const {
    double s = 0.0;
    for (const Association& a : as) s += std::pow(Residual(a, p, nullptr), 2);
    return as.empty() ? 0.0 : std::sqrt(s / as.size());
  }

 private:
  template <typename Fn>
  void ParallelFor(size_t n, Fn&& fn) const {
    std::atomic<size_t> next{0};
    pool_.Run([&](int) {
      for (size_t i = next++; i < n; i = next++) fn(i);
    });
  }

  std::vector<CalScan> scans_;
  const PosTrack& pos_;
  const ExtrinsicCalibrationOptions& o_;
  mutable internal::WorkerPool pool_;
};

// Solves (H + prior) d = -(g + prior gradient) over the free parameters.
Vector7d SolveStep(const Matrix7d& H, const Vector7d& g, const Vector7d& offset_from_prior,
                   const Vector7d& prior_info, const std::array<bool, 7>& free) {
  Matrix7d A = H;
  Vector7d b = -g;
  for (int i = 0; i < 7; ++i) {
    A(i, i) += prior_info(i);
    b(i) -= prior_info(i) * offset_from_prior(i);
  }
  for (int i = 0; i < 7; ++i) {
    if (free[i]) continue;
    A.row(i).setZero();
    A.col(i).setZero();
    A(i, i) = 1.0;
    b(i) = 0.0;
  }
  return A.ldlt().solve(b);
}

}  // namespace

const char* ExtrinsicParameterName(int i) {
  static const char* kNames[7] = {"roll", "pitch", "yaw", "x", "y", "z", "time_offset"};
  return i >= 0 && i < 7 ? kNames[i] : "?";
}

Eigen::Matrix3d RotationFromRpy(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy(2), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy(1), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy(0), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Vector3d RpyFromRotation(const Eigen::Matrix3d& R) {
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  return Eigen::Vector3d(std::atan2(R(2, 1), R(2, 2)), pitch, std::atan2(R(1, 0), R(0, 0)));
}

Status ExtrinsicCalibrationOptions::Validate() const {
  if (max_scans < 10) return FieldError("max_scans", max_scans, "must be >= 10");
  if (!(min_range_m >= 0.0 && max_range_m > min_range_m))
    return FieldError("max_range_m", max_range_m, "must be > min_range_m >= 0");
  if (!(voxel_m > 0.0)) return FieldError("voxel_m", voxel_m, "must be > 0");
  if (max_points_per_scan < 100)
    return FieldError("max_points_per_scan", max_points_per_scan, "must be >= 100");
  if (query_stride < 1) return FieldError("query_stride", query_stride, "must be >= 1");
  for (double s : partner_separations_s) {
    if (!(s > 0.0)) return FieldError("partner_separations_s", s, "each must be > 0");
  }
  if (partners_per_point < 1)
    return FieldError("partners_per_point", partners_per_point, "must be >= 1");
  if (num_neighbours < 4) return FieldError("num_neighbours", num_neighbours, "must be >= 4");
  if (!(max_neighbour_distance_m > 0.0))
    return FieldError("max_neighbour_distance_m", max_neighbour_distance_m, "must be > 0");
  if (!(max_plane_thickness_m > 0.0))
    return FieldError("max_plane_thickness_m", max_plane_thickness_m, "must be > 0");
  if (!(final_gate_m > 0.0 && initial_gate_m >= final_gate_m))
    return FieldError("initial_gate_m", initial_gate_m, "must be >= final_gate_m > 0");
  if (!(huber_m > 0.0)) return FieldError("huber_m", huber_m, "must be > 0");
  if (max_rounds < 1) return FieldError("max_rounds", max_rounds, "must be >= 1");
  if (gauss_newton_steps_per_round < 1)
    return FieldError("gauss_newton_steps_per_round", gauss_newton_steps_per_round, "must be >= 1");
  if (!(max_pos_sigma_m > 0.0))
    return FieldError("max_pos_sigma_m", max_pos_sigma_m, "must be > 0");
  if (!(prior_sigma_rpy_rad.minCoeff() > 0.0 && prior_sigma_xyz_m.minCoeff() > 0.0 &&
        prior_sigma_time_s > 0.0) ||
      !prior_sigma_rpy_rad.allFinite() || !prior_sigma_xyz_m.allFinite())
    return FieldError("prior_sigma_*", prior_sigma_time_s, "every prior sigma must be > 0, finite");
  if (!(min_prior_reduction >= 1.0))
    return FieldError("min_prior_reduction", min_prior_reduction, "must be >= 1");
  if (jackknife_blocks < 2) return FieldError("jackknife_blocks", jackknife_blocks, "must be >= 2");
  if (num_threads < 1) return FieldError("num_threads", num_threads, "must be >= 1");
  return OkStatus();
}

StatusOr<ExtrinsicCalibration> CalibrateExtrinsics(const DriveReader& reader,
                                                   const std::vector<InsState>& pos,
                                                   const Eigen::Isometry3d& T_body_lidar_initial,
                                                   double time_offset_initial_s,
                                                   const ExtrinsicCalibrationOptions& o,
                                                   const std::atomic<bool>* stop) {
  const auto t_wall = std::chrono::steady_clock::now();
  SLAM_MMS_RETURN_IF_ERROR(o.Validate());
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

  // ---- Scans: evenly spaced, inside the POS span with margin, POS good there.
  const size_t n = reader.NumScans();
  const double margin = 3.0 * o.prior_sigma_time_s + 0.2;
  std::vector<size_t> candidates;
  for (size_t i = 0; i < n; ++i) {
    const double ts = reader.ScanStart(i).SecondsSince(t0) + time_offset_initial_s;
    const double te = reader.ScanEnd(i).SecondsSince(t0) + time_offset_initial_s;
    if (ts - margin < track.begin() || te + margin > track.end()) continue;
    if (track.At(ts).pos_sigma_m > o.max_pos_sigma_m) {
      ++result.scans_skipped_pos;
      continue;
    }
    candidates.push_back(i);
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
        " usable scans (need 10; scans outside the POS span or with POS sigma above " +
        std::to_string(o.max_pos_sigma_m) +
        " m are not used: " + std::to_string(result.scans_skipped_pos) + " so)");
  }
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> v;
    for (const Eigen::Vector3d& a : att_sigmas) v.push_back(a(axis));
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    result.pos_attitude_sigma_rad(axis) = v[v.size() / 2];
  }
  const double span = scans.back().t_start - scans.front().t_start;
  for (CalScan& s : scans) {
    s.block = std::min(o.jackknife_blocks - 1,
                       static_cast<int>((s.t_start - scans.front().t_start) / std::max(span, 1e-9) *
                                        o.jackknife_blocks));
  }

  // ---- Partners (from the POS at the initial time offset).
  {
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
          const size_t b = static_cast<size_t>(std::lower_bound(when.begin(), when.end(), target) -
                                               when.begin());
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

  Calibrator cal(std::move(scans), track, o);
  result.scans_used = static_cast<int>(cal.scans().size());
  Params initial;
  initial.R = R0;
  initial.t = T_body_lidar_initial.translation();
  initial.time = time_offset_initial_s;
  Vector7d prior_info;
  prior_info << o.prior_sigma_rpy_rad.cwiseInverse().cwiseAbs2(),
      o.prior_sigma_xyz_m.cwiseInverse().cwiseAbs2(),
      1.0 / (o.prior_sigma_time_s * o.prior_sigma_time_s);
  std::array<bool, 7> free{};
  for (int i = 0; i < 3; ++i) free[i] = o.estimate_rotation;
  for (int i = 3; i < 6; ++i) free[i] = o.estimate_translation;
  free[6] = o.estimate_time_offset;

  // One solve from `start` with the free set; returns the associations of its last round.
  const auto solve = [&](Params* p, const std::array<bool, 7>& fr, int rounds,
                         std::vector<Association>* last) -> Status {
    for (int round = 0; round < rounds; ++round) {
      if (stop != nullptr && stop->load()) {
        return FailedPreconditionError("CalibrateExtrinsics: stopped");
      }
      const double f = rounds > 1 ? std::min(1.0, round / 4.0) : 1.0;
      const double gate = o.initial_gate_m * std::pow(o.final_gate_m / o.initial_gate_m, f);
      cal.UpdatePoses(*p);
      cal.Deskew(*p);
      *last = cal.Associate(*p, gate);
      if (last->size() < 100) {
        return FailedPreconditionError("CalibrateExtrinsics: " + std::to_string(last->size()) +
                                       " point-to-plane associations (need 100): the scans do not "
                                       "overlap or the initial extrinsic is far off");
      }
      double step_norm = 0.0;
      for (int it = 0; it < o.gauss_newton_steps_per_round; ++it) {
        cal.UpdatePoses(*p);
        const std::vector<Calibrator::Normal> nb = cal.Accumulate(*last, *p, 1);
        // Data weighted by the residual variance, so that the prior has its stated weight.
        const double s2 = std::max(nb[0].wrr / std::max(1.0, nb[0].n - 7.0), 1e-6);
        const Vector7d d =
            SolveStep(nb[0].H / s2, nb[0].g / s2, Difference(*p, initial), prior_info, fr);
        Apply(d, p);
        step_norm = std::max(
            {d.head<3>().norm() / 1e-5, d.segment<3>(3).norm() / 1e-4, std::abs(d(6)) / 1e-5});
      }
      result.rounds = round + 1;
      result.converged = f >= 1.0 && step_norm < 1.0;
      if (result.converged) break;
    }
    cal.UpdatePoses(*p);
    return OkStatus();
  };

  // RMS at the initial value (final gate).
  cal.UpdatePoses(initial);
  cal.Deskew(initial);
  result.rms_initial_m = cal.Rms(cal.Associate(initial, o.final_gate_m), initial);

  Params p = initial;
  std::vector<Association> last;
  SLAM_MMS_RETURN_IF_ERROR(solve(&p, free, o.max_rounds, &last));

  // Sigmas: formal and jackknife over time blocks, from the normal equations at the solution.
  const auto sigmas = [&](const Params& at, const std::array<bool, 7>& fr, Vector7d* formal,
                          Vector7d* jack) {
    const std::vector<Calibrator::Normal> blocks = cal.Accumulate(last, at, o.jackknife_blocks);
    Calibrator::Normal all;
    for (const auto& b : blocks) {
      all.H += b.H;
      all.g += b.g;
      all.wrr += b.wrr;
      all.w += b.w;
      all.n += b.n;
    }
    const double dof = std::max<double>(1.0, static_cast<double>(all.n) - 7.0);
    const double s2 = all.wrr / dof;
    const Vector7d off = Difference(at, initial);
    Matrix7d A = all.H / s2;
    for (int i = 0; i < 7; ++i) A(i, i) += prior_info(i);
    for (int i = 0; i < 7; ++i) {
      if (fr[i]) continue;
      A.row(i).setZero();
      A.col(i).setZero();
      A(i, i) = 1.0;
    }
    const Matrix7d cov = A.inverse();
    for (int i = 0; i < 7; ++i) (*formal)(i) = fr[i] ? std::sqrt(std::max(0.0, cov(i, i))) : 0.0;
    std::vector<Vector7d> loo;
    for (const auto& b : blocks) {
      if (b.n == 0) continue;
      loo.push_back(SolveStep((all.H - b.H) / s2, (all.g - b.g) / s2, off, prior_info, fr));
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
  };
  Vector7d formal, jack;
  sigmas(p, free, &formal, &jack);
  result.formal_sigma = formal;
  result.jackknife_sigma = jack;
  Vector7d prior_sigma;
  prior_sigma << o.prior_sigma_rpy_rad, o.prior_sigma_xyz_m, o.prior_sigma_time_s;
  Vector7d max_sigma;
  max_sigma << Eigen::Vector3d::Constant(o.max_sigma_rpy_rad),
      Eigen::Vector3d::Constant(o.max_sigma_xyz_m), o.max_sigma_time_s;
  std::array<bool, 7> observable{};
  bool all_observable = true;
  for (int i = 0; i < 7; ++i) {
    const double s = std::max(formal(i), jack(i));
    observable[i] = free[i] && s <= max_sigma(i) && s * o.min_prior_reduction <= prior_sigma(i);
    if (free[i] && !observable[i]) all_observable = false;
  }
  if (!all_observable) {
    // Hold the unobservable ones at their initial values and solve the others again.
    std::array<bool, 7> fr = observable;
    const Vector7d off = Difference(p, initial);
    Params q = initial;
    Eigen::Vector3d keep_rot = off.head<3>();
    for (int i = 0; i < 3; ++i) {
      if (!fr[i]) keep_rot(i) = 0.0;
      if (fr[3 + i]) q.t(i) = p.t(i);
    }
    q.R = so3::Exp(keep_rot) * initial.R;
    if (fr[6]) q.time = p.time;
    if (std::any_of(fr.begin(), fr.end(), [](bool b) { return b; })) {
      SLAM_MMS_RETURN_IF_ERROR(solve(&q, fr, std::max(3, o.max_rounds / 2), &last));
    }
    p = q;
    Vector7d f2, j2;
    sigmas(p, fr, &f2, &j2);
    formal = f2;
    jack = j2;
  }
  result.observable = observable;
  {
    // Held rotation axes exactly at the initial value in the reported (roll, pitch, yaw) terms
    // (the steps kept them at zero to first order only).
    Eigen::Vector3d rpy = RpyFromRotation(p.R * initial.R.transpose());
    bool changed = false;
    for (int i = 0; i < 3; ++i) {
      if (!observable[i] && rpy(i) != 0.0) {
        rpy(i) = 0.0;
        changed = true;
      }
    }
    if (changed) p.R = RotationFromRpy(rpy) * initial.R;
  }
  const Vector7d corr = Difference(p, initial);
  result.T_body_lidar_estimated = p.X();
  result.time_offset_s = p.time;
  result.correction_rpy_rad = RpyFromRotation(p.R * initial.R.transpose());
  result.correction_xyz_m = corr.segment<3>(3);
  for (int i = 0; i < 3; ++i) {
    result.sigma_rpy_rad(i) =
        observable[i] ? std::hypot(std::max(formal(i), jack(i)), result.pos_attitude_sigma_rad(i))
                      : 0.0;
    result.sigma_xyz_m(i) = observable[3 + i] ? std::max(formal(3 + i), jack(3 + i)) : 0.0;
  }
  result.sigma_time_s = observable[6] ? std::max(formal(6), jack(6)) : 0.0;
  result.residuals = last.size();
  cal.Deskew(p);
  result.rms_final_m = cal.Rms(cal.Associate(p, o.final_gate_m), p);
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_wall).count();
  return result;
}

}  // namespace slam_mms
