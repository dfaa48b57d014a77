// ReferenceTrajectory: uniform cubic B-splines fitted by regularised least squares.
#include "slam_mms/sim/reference_trajectory.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "slam_mms/core/lie.hpp"

namespace slam_mms::sim {
namespace {

// Basis of the uniform cubic B-spline and its first two derivatives with respect to u in [0, 1].
void Basis(double u, double b[4], double db[4], double ddb[4]) {
  const double u2 = u * u, u3 = u2 * u, w = 1.0 - u;
  b[0] = w * w * w / 6.0;
  b[1] = (3.0 * u3 - 6.0 * u2 + 4.0) / 6.0;
  b[2] = (-3.0 * u3 + 3.0 * u2 + 3.0 * u + 1.0) / 6.0;
  b[3] = u3 / 6.0;
  db[0] = -w * w / 2.0;
  db[1] = (3.0 * u2 - 4.0 * u) / 2.0;
  db[2] = (-3.0 * u2 + 2.0 * u + 1.0) / 2.0;
  db[3] = u2 / 2.0;
  ddb[0] = w;
  ddb[1] = 3.0 * u - 2.0;
  ddb[2] = -3.0 * u + 1.0;
  ddb[3] = u;
}

Eigen::Matrix3d Rx(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).matrix(); }
Eigen::Matrix3d Ry(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).matrix(); }
Eigen::Matrix3d Rz(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).matrix(); }

}  // namespace

Status ReferenceTrajectory::FitOptions::Validate() const {
  auto positive = [](double v, const char* name) -> Status {
    if (!(v > 0.0) || !std::isfinite(v)) {
      std::ostringstream s;
      s << "ReferenceTrajectory::FitOptions::" << name << " = " << v << "; must be > 0";
      return InvalidArgumentError(s.str());
    }
    return OkStatus();
  };
  SLAM_MMS_RETURN_IF_ERROR(positive(knot_spacing_s, "knot_spacing_s"));
  SLAM_MMS_RETURN_IF_ERROR(positive(position_sigma_m, "position_sigma_m"));
  SLAM_MMS_RETURN_IF_ERROR(positive(angle_sigma_rad, "angle_sigma_rad"));
  SLAM_MMS_RETURN_IF_ERROR(positive(velocity_sigma_mps, "velocity_sigma_mps"));
  SLAM_MMS_RETURN_IF_ERROR(positive(accel_density, "accel_density"));
  SLAM_MMS_RETURN_IF_ERROR(positive(angular_accel_density, "angular_accel_density"));
  return OkStatus();
}

StatusOr<ReferenceTrajectory> ReferenceTrajectory::Fit(Timestamp epoch,
                                                       const std::vector<PoseSample>& samples,
                                                       const FitOptions& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  if (samples.size() < 4) {
    return InvalidArgumentError("ReferenceTrajectory::Fit: " + std::to_string(samples.size()) +
                                " samples; need at least 4");
  }
  for (size_t i = 0; i < samples.size(); ++i) {
    if (!samples[i].p_world.allFinite() || !samples[i].rpy_rad.allFinite() ||
        !std::isfinite(samples[i].t_s) || !(samples[i].position_sigma_m >= 0.0) ||
        !std::isfinite(samples[i].position_sigma_m) ||
        (samples[i].has_velocity && !samples[i].v_world_mps.allFinite())) {
      return InvalidArgumentError("ReferenceTrajectory::Fit: sample " + std::to_string(i) +
                                  " is not finite");
    }
    if (i > 0 && !(samples[i].t_s > samples[i - 1].t_s)) {
      return InvalidArgumentError("ReferenceTrajectory::Fit: sample times must increase (sample " +
                                  std::to_string(i) + ")");
    }
  }
  const double dt = options.knot_spacing_s;
  const double t0 = samples.front().t_s;
  const double span = samples.back().t_s - t0;
  const int segs = static_cast<int>(std::ceil(span / dt - 1e-9));
  if (segs < 3) {
    return InvalidArgumentError("ReferenceTrajectory::Fit: samples span " + std::to_string(span) +
                                " s; need more than 3 knot intervals");
  }
  const int n = segs + 3;

  // Unwrapped yaw.
  std::vector<Eigen::Matrix<double, 6, 1>> y(samples.size());
  double yaw_prev = samples.front().rpy_rad.z();
  for (size_t i = 0; i < samples.size(); ++i) {
    y[i].head<3>() = samples[i].p_world;
    y[i].segment<2>(3) = samples[i].rpy_rad.head<2>();
    double yaw = samples[i].rpy_rad.z();
    if (i > 0) yaw = yaw_prev + std::remainder(yaw - yaw_prev, 2.0 * M_PI);
    y[i](5) = yaw;
    yaw_prev = yaw;
  }

  ReferenceTrajectory traj;
  traj.epoch_ = epoch;
  traj.t0_s_ = t0;
  traj.dt_s_ = dt;
  traj.num_segments_ = segs;
  traj.control_.assign(n, Eigen::Matrix<double, 6, 1>::Zero());

  // Data terms, scaled by the group's sigma^2 (a sample at the group's sigma weighs 1): the angles
  // and positions share the design, the positions add their own weights and the velocity rows
  // (derivative of the basis / dt). Regularisation (second differences of the control points ~
  // acceleration * dt^2, white-noise acceleration prior) differs per group only by weight.
  const double sp = options.position_sigma_m;
  const double wv = (sp / options.velocity_sigma_mps) * (sp / options.velocity_sigma_mps);
  std::vector<Eigen::Triplet<double>> angle_trip, pos_trip;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(n, 6);
  angle_trip.reserve(samples.size() * 16);
  pos_trip.reserve(samples.size() * 16);
  for (size_t i = 0; i < samples.size(); ++i) {
    const PoseSample& sample = samples[i];
    const double x = (sample.t_s - t0) / dt;
    const int seg = std::clamp(static_cast<int>(std::floor(x)), 0, segs - 1);
    double b[4], db[4], ddb[4];
    Basis(x - seg, b, db, ddb);
    const double sigma_i = sample.position_sigma_m > 0.0 ? sample.position_sigma_m : sp;
    const double w = (sp / sigma_i) * (sp / sigma_i);
    for (int a = 0; a < 4; ++a) {
      for (int c = 0; c < 4; ++c) {
        angle_trip.emplace_back(seg + a, seg + c, b[a] * b[c]);
        pos_trip.emplace_back(seg + a, seg + c, w * b[a] * b[c]);
        if (sample.has_velocity) {
          pos_trip.emplace_back(seg + a, seg + c, wv * db[a] * db[c] / (dt * dt));
        }
      }
      rhs.row(seg + a).head<3>() += w * b[a] * y[i].head<3>().transpose();
      if (sample.has_velocity) {
        rhs.row(seg + a).head<3>() += wv * db[a] / dt * sample.v_world_mps.transpose();
      }
      rhs.row(seg + a).tail<3>() += b[a] * y[i].tail<3>().transpose();
    }
  }
  std::vector<Eigen::Triplet<double>> reg_trip;
  for (int k = 1; k + 1 < n; ++k) {
    const int idx[3] = {k - 1, k, k + 1};
    const double wr[3] = {1.0, -2.0, 1.0};
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 3; ++c) reg_trip.emplace_back(idx[a], idx[c], wr[a] * wr[c]);
  }
  Eigen::SparseMatrix<double> reg(n, n);
  reg.setFromTriplets(reg_trip.begin(), reg_trip.end());
  // Cost: sum (B c - y)^2 / sigma^2 + sum (D2 c / dt^2)^2 dt / q^2. Multiply by sigma^2.
  for (int group = 0; group < 2; ++group) {
    const double sigma = group == 0 ? options.position_sigma_m : options.angle_sigma_rad;
    const double q = group == 0 ? options.accel_density : options.angular_accel_density;
    const double lambda = sigma * sigma / (q * q * dt * dt * dt);
    const std::vector<Eigen::Triplet<double>>& trip = group == 0 ? pos_trip : angle_trip;
    Eigen::SparseMatrix<double> data(n, n);
    data.setFromTriplets(trip.begin(), trip.end());
    Eigen::SparseMatrix<double> A = data + lambda * reg;
    // A tiny ridge keeps the system definite where samples are missing at the ends.
    for (int k = 0; k < n; ++k) A.coeffRef(k, k) += 1e-9;
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(A);
    if (solver.info() != Eigen::Success) {
      return InternalError("ReferenceTrajectory::Fit: factorisation failed");
    }
    for (int ch = 3 * group; ch < 3 * group + 3; ++ch) {
      const Eigen::VectorXd c = solver.solve(rhs.col(ch));
      for (int k = 0; k < n; ++k) traj.control_[k](ch) = c(k);
    }
  }
  return traj;
}

StatusOr<ReferenceTrajectory> ReferenceTrajectory::Restricted(double from_s, double to_s) const {
  const double b = std::max(from_s, start_s()), e = std::min(to_s, end_s());
  if (!(e > b)) {
    std::ostringstream s;
    s << "ReferenceTrajectory::Restricted: [" << from_s << ", " << to_s << "] s leaves nothing of ["
      << start_s() << ", " << end_s() << "] s";
    return InvalidArgumentError(s.str());
  }
  const int first =
      std::clamp(static_cast<int>(std::floor((b - t0_s_) / dt_s_ + 1e-9)), 0, num_segments_ - 1);
  const int last =
      std::clamp(static_cast<int>(std::ceil((e - t0_s_) / dt_s_ - 1e-9)), first + 1, num_segments_);
  ReferenceTrajectory out;
  out.epoch_ = epoch_;
  out.t0_s_ = t0_s_ + dt_s_ * first;
  out.dt_s_ = dt_s_;
  out.num_segments_ = last - first;
  out.control_.assign(control_.begin() + first, control_.begin() + last + 3);
  return out;
}

BodyState ReferenceTrajectory::Evaluate(double t_s) const {
  BodyState s;
  if (num_segments_ <= 0) return s;
  const double x = (std::clamp(t_s, start_s(), end_s()) - t0_s_) / dt_s_;
  const int seg = std::clamp(static_cast<int>(std::floor(x)), 0, num_segments_ - 1);
  double b[4], db[4], ddb[4];
  Basis(x - seg, b, db, ddb);
  Eigen::Matrix<double, 6, 1> v = Eigen::Matrix<double, 6, 1>::Zero(), dv = v, ddv = v;
  for (int a = 0; a < 4; ++a) {
    v += b[a] * control_[seg + a];
    dv += db[a] * control_[seg + a];
    ddv += ddb[a] * control_[seg + a];
  }
  dv /= dt_s_;
  ddv /= dt_s_ * dt_s_;
  const double roll = v(3), pitch = v(4), yaw = v(5);
  const Eigen::Matrix3d R_x = Rx(roll), R_y = Ry(pitch), R_z = Rz(yaw);
  s.T_world_body.linear() = R_z * R_y * R_x;
  s.T_world_body.translation() = v.head<3>();
  s.v_world_mps = dv.head<3>();
  s.a_world_mps2 = ddv.head<3>();
  s.rpy_rad = v.tail<3>();
  // R = Rz Ry Rx  =>  omega_body = [droll,0,0] + Rx^T [0,dpitch,0] + (Ry Rx)^T [0,0,dyaw].
  s.omega_body_radps = Eigen::Vector3d(dv(3), 0.0, 0.0) +
                       R_x.transpose() * Eigen::Vector3d(0.0, dv(4), 0.0) +
                       (R_y * R_x).transpose() * Eigen::Vector3d(0.0, 0.0, dv(5));
  return s;
}

Eigen::Vector3d ReferenceTrajectory::SpecificForceBody(const BodyState& state,
                                                       double gravity_mps2) {
  const Eigen::Vector3d g_world(0.0, 0.0, -gravity_mps2);
  return state.T_world_body.linear().transpose() * (state.a_world_mps2 - g_world);
}

double ReferenceTrajectory::PathLength(double step_s) const {
  double length = 0.0;
  Eigen::Vector3d prev = Pose(start_s()).translation();
  for (double t = start_s() + step_s; t <= end_s() + 1e-9; t += step_s) {
    const Eigen::Vector3d p = Pose(t).translation();
    length += (p - prev).norm();
    prev = p;
  }
  return length;
}

}  // namespace slam_mms::sim
