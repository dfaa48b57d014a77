#include "registration/point_icp.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <nanoflann.hpp>
#include <string>
#include <unordered_set>

#include "core/option_error.hpp"
#include "core/voxel_grid.hpp"
#include "core/worker_pool.hpp"
#include "registration/cloud_kdtree.hpp"
#include "registration/gauss_newton.hpp"
#include "registration/point_to_plane.hpp"

namespace slam_mms {
namespace {

using internal::WorkerPool;
using registration_internal::GaussNewtonSettings;
using registration_internal::HuberWeight;
using registration_internal::NormalEquations;
using registration_internal::PointToPlaneResidual;

using registration_internal::CloudAdaptor;
using KdTree = registration_internal::CloudKdTree;

Status FieldError(const std::string& field, double value, const std::string& rule) {
  return internal::OptionError("PointIcp::Options", field, value, rule);
}

}  // namespace

Status PointIcpOptions::Validate() const {
  if (!(max_correspondence_distance > 0.0))
    return FieldError("max_correspondence_distance", max_correspondence_distance, "must be > 0");
  if (num_normal_neighbors < 3)
    return FieldError("num_normal_neighbors", num_normal_neighbors, "must be >= 3");
  if (!(max_surface_variation > 0.0 && max_surface_variation <= 1.0 / 3.0 + 1e-12))
    return FieldError("max_surface_variation", max_surface_variation, "must be in (0, 1/3]");
  if (!std::isfinite(huber_delta)) return FieldError("huber_delta", huber_delta, "must be finite");
  if (max_iterations <= 0) return FieldError("max_iterations", max_iterations, "must be > 0");
  if (min_correspondences < 6)
    return FieldError("min_correspondences", min_correspondences, "must be >= 6");
  if (!(rotation_eps > 0.0)) return FieldError("rotation_eps", rotation_eps, "must be > 0");
  if (!(translation_eps > 0.0))
    return FieldError("translation_eps", translation_eps, "must be > 0");
  if (!(degeneracy_threshold > 0.0 && degeneracy_threshold < 1.0))
    return FieldError("degeneracy_threshold", degeneracy_threshold, "must be in (0, 1)");
  if (!(source_voxel_size >= 0.0) || !std::isfinite(source_voxel_size))
    return FieldError("source_voxel_size", source_voxel_size, "must be finite and >= 0");
  return OkStatus();
}

Status PointIcp::Options::Validate() const {
  SLAM_MMS_RETURN_IF_ERROR(PointIcpOptions::Validate());
  if (num_threads < 1 || num_threads > 256)
    return FieldError("num_threads", num_threads, "must be in [1, 256]");
  return OkStatus();
}

struct PointIcp::Impl {
  explicit Impl(const Options& o) : options(o), pool(o.num_threads) {
    adaptor.pts = &points;
    per_thread.resize(static_cast<size_t>(pool.size()));
  }
  Options options;
  WorkerPool pool;
  std::vector<Eigen::Vector3f> points;
  std::vector<Eigen::Vector3f> normals;
  CloudAdaptor adaptor;
  std::unique_ptr<KdTree> tree;
  std::vector<NormalEquations> per_thread;
  std::vector<Eigen::Vector3f> source;  // scratch, reused between calls

  void BuildTree() {
    tree = std::make_unique<KdTree>(3, adaptor, nanoflann::KDTreeSingleIndexAdaptorParams(10));
  }
};

PointIcp::PointIcp() : impl_(std::make_unique<Impl>(Options())) {}
PointIcp::PointIcp(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
PointIcp::~PointIcp() = default;
PointIcp::PointIcp(PointIcp&&) noexcept = default;
PointIcp& PointIcp::operator=(PointIcp&&) noexcept = default;

StatusOr<PointIcp> PointIcp::Create(const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  return PointIcp(std::make_unique<Impl>(options));
}

const PointIcp::Options& PointIcp::options() const { return impl_->options; }
size_t PointIcp::target_size() const { return impl_->points.size(); }
const std::vector<Eigen::Vector3f>& PointIcp::target_points() const { return impl_->points; }
const std::vector<Eigen::Vector3f>& PointIcp::target_normals() const { return impl_->normals; }

Status PointIcp::SetTarget(const PointCloudView& target) {
  Impl& m = *impl_;
  const size_t k = static_cast<size_t>(m.options.num_normal_neighbors);
  m.points.clear();
  m.points.reserve(target.size);
  for (size_t i = 0; i < target.size; ++i) {
    const Eigen::Vector3f p = target.Point(i);
    if (p.allFinite()) m.points.push_back(p);
  }
  if (m.points.size() < k) {
    m.points.clear();
    m.tree.reset();
    return InvalidArgumentError(
        "PointIcp::SetTarget: " + std::to_string(m.points.size()) +
        " finite target points; need >= num_normal_neighbors = " + std::to_string(k));
  }
  m.BuildTree();
  m.normals.assign(m.points.size(), Eigen::Vector3f::Zero());
  const double max_var = m.options.max_surface_variation;
  constexpr double kMinPlaneness = 0.01;
  auto job = [&](int t) {
    size_t begin, end;
    m.pool.Range(t, m.points.size(), &begin, &end);
    std::vector<uint32_t> idx(k);
    std::vector<float> d2(k);
    for (size_t i = begin; i < end; ++i) {
      const size_t n = m.tree->knnSearch(m.points[i].data(), k, idx.data(), d2.data());
      if (n < 3) continue;
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      for (size_t j = 0; j < n; ++j) mean += m.points[idx[j]].cast<double>();
      mean /= static_cast<double>(n);
      Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
      for (size_t j = 0; j < n; ++j) {
        const Eigen::Vector3d d = m.points[idx[j]].cast<double>() - mean;
        C.noalias() += d * d.transpose();
      }
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
      es.computeDirect(C);
      const Eigen::Vector3d l = es.eigenvalues();
      const double sum = l.sum();
      // Reject volumes (surface variation) and lines (a single scan ring: l1 ~ 0, normal
      // arbitrary).
      if (!(sum > 0.0) || l[0] / sum > max_var || l[1] < kMinPlaneness * l[2]) continue;
      m.normals[i] = es.eigenvectors().col(0).normalized().cast<float>();
    }
  };
  m.pool.Run(job);
  return OkStatus();
}

Status PointIcp::SetTarget(const std::vector<Eigen::Vector3f>& points,
                           const std::vector<Eigen::Vector3f>& normals) {
  Impl& m = *impl_;
  if (points.size() != normals.size())
    return InvalidArgumentError("PointIcp::SetTarget: " + std::to_string(points.size()) +
                                " points but " + std::to_string(normals.size()) + " normals");
  m.points.clear();
  m.normals.clear();
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i].allFinite() || !normals[i].allFinite()) continue;
    const float len = normals[i].norm();
    m.points.push_back(points[i]);
    m.normals.push_back(len > 1e-6f ? Eigen::Vector3f(normals[i] / len) : Eigen::Vector3f::Zero());
  }
  if (m.points.empty()) {
    m.tree.reset();
    return InvalidArgumentError("PointIcp::SetTarget: no finite target points");
  }
  m.BuildTree();
  return OkStatus();
}

StatusOr<RegistrationResult> PointIcp::Align(const PointCloudView& source,
                                             const Eigen::Isometry3d& T_target_source_init) {
  Impl& m = *impl_;
  if (!m.tree) return FailedPreconditionError("PointIcp::Align: SetTarget was not called");
  if (source.size == 0 || source.xyz == nullptr)
    return InvalidArgumentError("PointIcp::Align: empty source");
  if (!T_target_source_init.matrix().allFinite())
    return InvalidArgumentError("PointIcp::Align: T_target_source_init is not finite");

  // Source points (finite; optionally one per voxel).
  m.source.clear();
  m.source.reserve(source.size);
  const double voxel = m.options.source_voxel_size;
  if (voxel > 0.0) {
    // The first point of each cell; a finite point beyond the grid's range (2^30 - 1 voxels)
    // is kept as its own cell.
    const internal::VoxelGrid grid(voxel);
    std::unordered_set<internal::VoxelCell, internal::VoxelCellHash> occupied;
    occupied.reserve(source.size);
    for (size_t i = 0; i < source.size; ++i) {
      const Eigen::Vector3f p = source.Point(i);
      if (!p.allFinite()) continue;
      internal::VoxelCell cell;
      if (!grid.CellOf(p, &cell) || occupied.insert(cell).second) m.source.push_back(p);
    }
  } else {
    for (size_t i = 0; i < source.size; ++i) {
      const Eigen::Vector3f p = source.Point(i);
      if (p.allFinite()) m.source.push_back(p);
    }
  }

  GaussNewtonSettings s;
  s.max_iterations = m.options.max_iterations;
  s.min_correspondences = static_cast<size_t>(m.options.min_correspondences);
  s.rotation_eps_rad = m.options.rotation_eps;
  s.translation_eps_m = m.options.translation_eps;
  s.degeneracy_threshold = m.options.degeneracy_threshold;
  s.freeze_degenerate_directions = m.options.freeze_degenerate_directions;
  const float max_d2 = static_cast<float>(m.options.max_correspondence_distance *
                                          m.options.max_correspondence_distance);
  const double huber = m.options.huber_delta;

  auto build = [&](const Eigen::Isometry3d& T, NormalEquations* eq) {
    const Eigen::Matrix3d R = T.linear();
    const Eigen::Vector3d t = T.translation();
    const Eigen::Matrix3f Rf = R.cast<float>();
    const Eigen::Vector3f tf = t.cast<float>();
    auto job = [&](int th) {
      NormalEquations& local = m.per_thread[static_cast<size_t>(th)];
      local.SetZero();
      size_t begin, end;
      m.pool.Range(th, m.source.size(), &begin, &end);
      Vector6d J;
      for (size_t i = begin; i < end; ++i) {
        const Eigen::Vector3f q = Rf * m.source[i] + tf;
        uint32_t idx;
        float d2;
        ++local.candidates;
        if (m.tree->knnSearch(q.data(), 1, &idx, &d2) != 1 || d2 > max_d2) continue;
        const Eigen::Vector3f& n = m.normals[idx];
        if (n.squaredNorm() < 0.5f) continue;
        const Eigen::Vector3d p_s = m.source[i].cast<double>();
        const double r =
            PointToPlaneResidual<double>(R, t, p_s, Eigen::Vector3d(m.points[idx].cast<double>()),
                                         Eigen::Vector3d(n.cast<double>()), &J);
        local.Add(J, r, HuberWeight(r, huber), p_s);
      }
    };
    m.pool.Run(job);
    for (const auto& local : m.per_thread) *eq += local;
  };
  return registration_internal::RunGaussNewton(s, T_target_source_init, build);
}

}  // namespace slam_mms
