#include "drive/extrinsic_calibration_problem.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_set>

#include "core/voxel_grid.hpp"
#include "registration/point_to_plane.hpp"
#include "slam_mms/core/lie.hpp"

namespace slam_mms::calib_internal {

void Subsample(const Scan& scan, const ExtrinsicCalibrationOptions& o, CalScan* out) {
  std::unordered_set<internal::VoxelCell, internal::VoxelCellHash> seen;
  const auto& pts = scan.cloud.points();
  const auto& tau = scan.cloud.time_offsets_s();
  const bool have_tau = tau.size() == pts.size();
  const internal::VoxelGrid grid(o.voxel_m);
  std::vector<size_t> keep;
  for (size_t i = 0; i < pts.size(); ++i) {
    const Eigen::Vector3f& p = pts[i];
    const double r = p.norm();
    if (!(r >= o.min_range_m && r <= o.max_range_m)) continue;
    internal::VoxelCell cell;  // the first point of each voxel (in range: r <= max_range_m)
    if (grid.CellOf(p, &cell) && seen.insert(cell).second) keep.push_back(i);
  }
  const size_t m = static_cast<size_t>(o.max_points_per_scan);
  const double step = keep.size() > m ? static_cast<double>(keep.size()) / m : 1.0;
  for (double f = 0.0; f < keep.size() && out->raw.size() < m; f += step) {
    const size_t i = keep[static_cast<size_t>(f)];
    out->raw.push_back(pts[i]);
    out->tau.push_back(have_tau ? tau[i] : 0.0f);
  }
}

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

CalibrationProblem::CalibrationProblem(std::vector<CalScan> scans, const PosTrack& pos,
                                       const ExtrinsicCalibrationOptions& o, int num_threads)
    : scans_(std::move(scans)), pos_(pos), o_(o), pool_(std::max(1, num_threads)) {
  if (!o.estimate_pos_drift || scans_.empty()) return;
  const double t0 = scans_.front().t_start;
  double t1 = t0;
  for (const CalScan& s : scans_) t1 = std::max(t1, s.t_start + s.duration);
  const double step = o.pos_drift_knot_interval_s;
  num_knots_ = static_cast<int>(std::floor((t1 - t0) / step)) + 2;
  for (CalScan& s : scans_) {
    const double u = (s.t_start + 0.5 * s.duration - t0) / step;
    s.knot = std::clamp(static_cast<int>(std::floor(u)), 0, num_knots_ - 2);
    s.knot_frac = std::clamp(u - s.knot, 0.0, 1.0);
  }
}

void CalibrationProblem::SetShifts(const VectorXd& knots) {
  for (CalScan& s : scans_) {
    s.shift = num_knots_ == 0 ? Eigen::Vector3d::Zero()
                              : Eigen::Vector3d((1.0 - s.knot_frac) * knots.segment<3>(3 * s.knot) +
                                                s.knot_frac * knots.segment<3>(3 * s.knot + 3));
  }
}

MatrixXd CalibrationProblem::KnotPrior() const {
  MatrixXd P = MatrixXd::Zero(dim(), dim());
  if (num_knots_ == 0) return P;
  const double dt = o_.pos_drift_knot_interval_s;
  const double tau = o_.pos_error_correlation_s;
  const double t0 = scans_.front().t_start;
  constexpr double kGaugeSigmaM = 1.0;
  constexpr double kMinSigmaM = 1e-4;
  // sum_j w_j (sum_k c_jk x_k)^2 over the knots' x, y and z alike.
  const auto add = [&](const std::vector<std::pair<int, double>>& c, double sigma) {
    const double w = 1.0 / std::pow(std::max(sigma, kMinSigmaM), 2);
    for (const auto& [ka, ca] : c) {
      for (const auto& [kb, cb] : c) {
        P.block<3, 3>(7 + 3 * ka, 7 + 3 * kb).diagonal().array() += w * ca * cb;
      }
    }
  };
  for (int k = 0; k < num_knots_; ++k) {
    add({{k, 1.0}}, kGaugeSigmaM);
    // The POS's stated sigma s about the knot, its error a Gauss-Markov process of s and tau
    // whose rate is one of v = s sqrt(2 / tau) (at most the velocity cap) and tau (the
    // options): first differences of v dt, second differences of v sqrt(2 dt / tau) dt.
    const double s = pos_.At(t0 + k * dt).pos_sigma_m;
    const double v = std::min(s * std::sqrt(2.0 / tau), o_.pos_max_velocity_error_mps);
    if (k + 1 < num_knots_) add({{k, -1.0}, {k + 1, 1.0}}, v * dt);
    if (k >= 1 && k + 1 < num_knots_) {
      add({{k - 1, 1.0}, {k, -2.0}, {k + 1, 1.0}}, v * std::sqrt(2.0 * dt / tau) * dt);
    }
  }
  return P;
}

void CalibrationProblem::UpdatePoses(const Params& p) {
  for (CalScan& s : scans_) s.pose = pos_.At(s.t_start + p.time);
}

void CalibrationProblem::Deskew(const Params& p) {
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
    s.tree = std::make_unique<KdTree>(3, s.adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    s.tree->buildIndex();
  });
}

std::vector<Association> CalibrationProblem::Associate(const Params& p, double gate) const {
  const Eigen::Isometry3d X = p.X();
  std::vector<std::vector<Association>> per_scan(scans_.size());
  const int k = o_.num_neighbours;
  const float max_d2 =
      static_cast<float>(o_.max_neighbour_distance_m * o_.max_neighbour_distance_m);
  // Each scan's lidar frame in world (POS, extrinsic, POS correction) and its inverse, once per
  // call rather than per query point.
  std::vector<Eigen::Isometry3d> W(scans_.size()), W_inv(scans_.size());
  for (size_t i = 0; i < scans_.size(); ++i) {
    W[i] = scans_[i].pose.T_world_body * X;
    W[i].translation() += scans_[i].shift;
    W_inv[i] = W[i].inverse();
  }
  ParallelFor(scans_.size(), [&](size_t ia) {
    const CalScan& a = scans_[ia];
    if (a.partners.empty()) return;
    const Eigen::Isometry3d& Wa = W[ia];
    std::vector<uint32_t> idx(k);
    std::vector<float> d2(k);
    int round = 0;
    for (size_t j = 0; j < a.q.size(); j += static_cast<size_t>(o_.query_stride)) {
      for (int m = 0; m < o_.partners_per_point; ++m) {
        const int ib = a.partners[(round++) % a.partners.size()];
        const CalScan& b = scans_[ib];
        const Eigen::Isometry3d Mba = W_inv[ib] * Wa;
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

double CalibrationProblem::Residual(const Association& s, const Params& p, Vector7d* J,
                                    Eigen::Vector3d* nw_out) const {
  const CalScan& a = scans_[s.a];
  const CalScan& b = scans_[s.b];
  const Eigen::Matrix3d& Ra = a.pose.T_world_body.linear();
  const Eigen::Matrix3d& Rb = b.pose.T_world_body.linear();
  const Eigen::Vector3d Rq = p.R * s.q, Rc = p.R * s.c, Rn = p.R * s.n;
  const Eigen::Vector3d wa = Ra * (Rq + p.t) + a.pose.T_world_body.translation();
  const Eigen::Vector3d wb = Rb * (Rc + p.t) + b.pose.T_world_body.translation();
  const Eigen::Vector3d nw = Rb * Rn;
  const Eigen::Vector3d d = wa - wb + a.shift - b.shift;
  if (nw_out != nullptr) *nw_out = nw;
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

std::vector<CalibrationProblem::Normal> CalibrationProblem::Accumulate(
    const std::vector<Association>& as, const Params& p, int blocks) const {
  const int nt = pool_.num_threads();
  const int n = dim();
  std::vector<std::vector<Normal>> part(nt, std::vector<Normal>(blocks, Normal(n)));
  pool_.Run([&](int t) {
    size_t begin, end;
    pool_.Range(t, as.size(), &begin, &end);
    Vector7d J;
    Eigen::Vector3d nw;
    // The residual's gradient, sparse: the 7, then up to two knots of each scan's shift.
    std::array<int, 19> idx;
    std::array<double, 19> val;
    for (size_t i = begin; i < end; ++i) {
      const double r = Residual(as[i], p, &J, &nw);
      const double w = registration_internal::HuberWeight(r, o_.huber_m);
      int m = 0;
      for (int k = 0; k < 7; ++k) {
        idx[m] = k;
        val[m++] = J(k);
      }
      if (num_knots_ > 0) {
        for (const auto& [scan, sign] : {std::pair{as[i].a, 1.0}, std::pair{as[i].b, -1.0}}) {
          const CalScan& sc = scans_[scan];
          for (int axis = 0; axis < 3; ++axis) {
            idx[m] = 7 + 3 * sc.knot + axis;
            val[m++] = sign * (1.0 - sc.knot_frac) * nw(axis);
            idx[m] = 7 + 3 * (sc.knot + 1) + axis;
            val[m++] = sign * sc.knot_frac * nw(axis);
          }
        }
      }
      Normal& nrm = part[t][blocks == 1 ? 0 : scans_[as[i].a].block];
      for (int u = 0; u < m; ++u) {
        const double wu = w * val[u];
        nrm.g(idx[u]) += wu * r;
        for (int v = 0; v < m; ++v) nrm.H(idx[u], idx[v]) += wu * val[v];
      }
      nrm.wrr += w * r * r;
      nrm.w += w;
      ++nrm.n;
    }
  });
  std::vector<Normal> out(blocks, Normal(n));
  for (int t = 0; t < nt; ++t) {
    for (int b = 0; b < blocks; ++b) {
      out[b] += part[t][b];
    }
  }
  return out;
}

double CalibrationProblem::Rms(const std::vector<Association>& as, const Params& p) const {
  double s = 0.0;
  for (const Association& a : as) s += std::pow(Residual(a, p, nullptr), 2);
  return as.empty() ? 0.0 : std::sqrt(s / as.size());
}

MatrixXd WithPriorAndFixed(const MatrixXd& H, const MatrixXd& prior,
                           const std::array<bool, 7>& free) {
  MatrixXd A = H + prior;
  for (int i = 0; i < 7; ++i) {
    if (free[i]) continue;
    A.row(i).setZero();
    A.col(i).setZero();
    A(i, i) = 1.0;
  }
  return A;
}

VectorXd SolveStep(const MatrixXd& H, const VectorXd& g, const VectorXd& offset_from_prior,
                   const MatrixXd& prior, const std::array<bool, 7>& free) {
  VectorXd b = -g - prior * offset_from_prior;
  for (int i = 0; i < 7; ++i) {
    if (!free[i]) b(i) = 0.0;
  }
  return WithPriorAndFixed(H, prior, free).ldlt().solve(b);
}

}  // namespace slam_mms::calib_internal
