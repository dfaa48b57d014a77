#pragma once
// The least-squares problem of CalibrateExtrinsics (extrinsic_calibrator.hpp): the POS as a
// continuous trajectory, the scans kept for it, their de-skew, point-to-plane associations with
// partner scans and the Huber-weighted normal equations over the 7 parameters and the POS's
// position corrections (knots, ExtrinsicCalibrationOptions::estimate_pos_drift). Private to the
// library (src/drive).
//
// Thread safety: CalibrationProblem is used from one thread; it runs its loops on its own pool.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <atomic>
#include <memory>
#include <vector>

#include "core/worker_pool.hpp"
#include "registration/cloud_kdtree.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/timestamp.hpp"
#include "slam_mms/drive/extrinsic_calibrator.hpp"

namespace slam_mms::calib_internal {

using Vector7d = Eigen::Matrix<double, 7, 1>;
using Matrix7d = Eigen::Matrix<double, 7, 7>;
using Eigen::MatrixXd;
using Eigen::VectorXd;

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
    out.v_world = (1.0 - a) * s0.v_world_mps + a * s1.v_world_mps;
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

using registration_internal::CloudAdaptor;
using KdTree = registration_internal::CloudKdTree;

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
  // The POS position correction at the scan (world): (1 - knot_frac) x knot + knot_frac x knot+1.
  int knot = 0;
  double knot_frac = 0.0;
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
};

// One point of scan a against the plane (c, n) of partner scan b, both in their lidar frames.
struct Association {
  int a = 0, b = 0;
  Eigen::Vector3d q, c, n;
};

// Per-scan voxel subsample in the lidar frame (first point of each voxel in scan order).
void Subsample(const Scan& scan, const ExtrinsicCalibrationOptions& o, CalScan* out);

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

/// p - p0 as [phi (left, body axes), dt_xyz, dtime].
Vector7d Difference(const Params& p, const Params& p0);
/// p <- p [+] d (rotation re-orthonormalised).
void Apply(const Vector7d& d, Params* p);

class CalibrationProblem {
 public:
  // Sets the knots of the POS correction over the scans' span (none where
  // !o.estimate_pos_drift).
  CalibrationProblem(std::vector<CalScan> scans, const PosTrack& pos,
                     const ExtrinsicCalibrationOptions& o, int num_threads);

  std::vector<CalScan>& scans() { return scans_; }
  const std::vector<CalScan>& scans() const { return scans_; }

  // Knots of the POS correction, and the size of the full parameter vector:
  // [the 7 of Params, knot 0 (x, y, z world), knot 1, ...].
  int num_knots() const { return num_knots_; }
  int dim() const { return 7 + 3 * num_knots_; }
  // Each scan's shift from the knots (3 x num_knots values).
  void SetShifts(const VectorXd& knots);
  // The knots' prior information (random walk and gauge, see the options), dim() x dim(), zero
  // in the first 7 rows and columns.
  MatrixXd KnotPrior() const;

  // Poses at scan starts for the time offset of `p`.
  void UpdatePoses(const Params& p);

  // De-skews every scan with the POS into its lidar frame at t_start and rebuilds its tree.
  void Deskew(const Params& p);

  // Point-to-plane associations at `p` with residual gate `gate`.
  std::vector<Association> Associate(const Params& p, double gate) const;

  // Residual and its Jacobian over [phi, dt_xyz, dtime] (see the header comment); `nw` (may be
  // null): the plane normal in world, the residual's gradient in scan a's shift (-nw in b's).
  double Residual(const Association& s, const Params& p, Vector7d* J,
                  Eigen::Vector3d* nw = nullptr) const;

  struct Normal {
    explicit Normal(int dim = 7) : H(MatrixXd::Zero(dim, dim)), g(VectorXd::Zero(dim)) {}
    MatrixXd H;
    VectorXd g;
    double wrr = 0.0, w = 0.0;  // sum of w r^2, sum of w
    size_t n = 0;
    Normal& operator+=(const Normal& o) {
      H += o.H;
      g += o.g;
      wrr += o.wrr;
      w += o.w;
      n += o.n;
      return *this;
    }
  };
  // Huber-weighted normal equations, per jackknife block.
  std::vector<Normal> Accumulate(const std::vector<Association>& as, const Params& p,
                                 int blocks) const;

  double Rms(const std::vector<Association>& as, const Params& p) const;

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
  int num_knots_ = 0;
};

// H + prior with the rows and columns of the fixed parameters (free[i] false, i < 7) replaced by
// identity.
MatrixXd WithPriorAndFixed(const MatrixXd& H, const MatrixXd& prior,
                           const std::array<bool, 7>& free);
// Solves (H + prior) d = -(g + prior x offset_from_prior) over the free parameters.
VectorXd SolveStep(const MatrixXd& H, const VectorXd& g, const VectorXd& offset_from_prior,
                   const MatrixXd& prior, const std::array<bool, 7>& free);

}  // namespace slam_mms::calib_internal
