// numpy <-> SDK conversions of the bindings (common.hpp): poses, trajectories and point clouds
// (split from core.cpp).

#include <cstring>
#include <limits>
#include <utility>

#include "common.hpp"

namespace slam_mms::python {

// ---- numpy <-> SDK ------------------------------------------------------------------------------

py::array_t<double> IsometryToArray(const Eigen::Isometry3d& T) {
  py::array_t<double> a({4, 4});
  auto r = a.mutable_unchecked<2>();
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) r(i, j) = T.matrix()(i, j);
  }
  return a;
}

Eigen::Isometry3d ArrayToIsometry(const py::handle& array, const char* what) {
  py::array_t<double, py::array::forcecast> a;
  try {
    a = py::array_t<double, py::array::forcecast>::ensure(array);
  } catch (py::error_already_set&) {
    a = {};
  }
  if (!a || a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) {
    throw py::value_error(std::string(what) + ": expected a 4 x 4 homogeneous matrix");
  }
  auto r = a.unchecked<2>();
  Eigen::Matrix4d M;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) M(i, j) = r(i, j);
  }
  if (M(3, 0) != 0.0 || M(3, 1) != 0.0 || M(3, 2) != 0.0 || M(3, 3) != 1.0) {
    throw py::value_error(std::string(what) + ": the bottom row must be [0, 0, 0, 1]");
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.matrix() = M;
  return T;
}

void PoseToTumRow(Timestamp stamp, const Eigen::Isometry3d& T, double* row) {
  // As io's PoseQuaternionText: normalised, canonical sign w >= 0.
  Eigen::Quaterniond q(T.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1.0;
  const Eigen::Vector3d& t = T.translation();
  const double v[8] = {stamp.seconds(), t.x(), t.y(), t.z(), q.x(), q.y(), q.z(), q.w()};
  std::memcpy(row, v, sizeof(v));
}

py::array_t<double> TrajectoryTum(const Trajectory& trajectory) {
  const auto n = static_cast<py::ssize_t>(trajectory.size());
  py::array_t<double> a({n, py::ssize_t{8}});
  double* p = a.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) {
    const StampedPose& pose = trajectory[static_cast<size_t>(i)];
    PoseToTumRow(pose.stamp, pose.T_world_body, p + 8 * i);
  }
  return a;
}

py::array_t<double> TrajectoryCovariances(const Trajectory& trajectory) {
  const auto n = static_cast<py::ssize_t>(trajectory.size());
  py::array_t<double> a({n, py::ssize_t{6}, py::ssize_t{6}});
  auto r = a.mutable_unchecked<3>();
  for (py::ssize_t k = 0; k < n; ++k) {
    const auto& cov = trajectory[static_cast<size_t>(k)].cov_T_world_body;
    for (int i = 0; i < 6; ++i) {
      for (int j = 0; j < 6; ++j) {
        r(k, i, j) = cov ? (*cov)(i, j) : std::numeric_limits<double>::quiet_NaN();
      }
    }
  }
  return a;
}

py::array_t<int64_t> TrajectoryStampsNs(const Trajectory& trajectory) {
  py::array_t<int64_t> a(static_cast<py::ssize_t>(trajectory.size()));
  int64_t* p = a.mutable_data();
  for (size_t i = 0; i < trajectory.size(); ++i) p[i] = trajectory[i].stamp.nanoseconds();
  return a;
}

py::array_t<float> CloudToXyzi(const PointCloud& cloud) {
  const auto n = static_cast<py::ssize_t>(cloud.size());
  py::array_t<float> a({n, py::ssize_t{4}});
  float* p = a.mutable_data();
  for (py::ssize_t i = 0; i < n; ++i) {
    const Eigen::Vector3f& q = cloud.points()[static_cast<size_t>(i)];
    p[4 * i + 0] = q.x();
    p[4 * i + 1] = q.y();
    p[4 * i + 2] = q.z();
    p[4 * i + 3] = cloud.intensities()[static_cast<size_t>(i)];
  }
  return a;
}

py::array FloatArray(const py::handle& obj, const char* name) {
  if (!py::isinstance<py::array>(obj)) {
    throw py::type_error(std::string(name) + ": expected a numpy array, got " +
                         std::string(py::str(py::type::handle_of(obj).attr("__name__"))));
  }
  py::array a = py::reinterpret_borrow<py::array>(obj);
  const py::dtype dt = a.dtype();
  if (!dt.is(py::dtype::of<float>()) && !dt.is(py::dtype::of<double>())) {
    throw py::type_error(std::string(name) + ": expected dtype float32 or float64, got " +
                         std::string(py::str(dt.attr("name"))));
  }
  return a;
}

namespace {

bool IsFloat32(const py::array& a) { return a.dtype().is(py::dtype::of<float>()); }

// A 1-D float array of length n as float32 (a view when it already is float32).
py::array_t<float> Column(const py::handle& obj, const char* name, py::ssize_t n) {
  py::array a = FloatArray(obj, name);
  if (a.ndim() != 1 || a.shape(0) != n) {
    throw py::value_error(std::string(name) + ": expected shape (" + std::to_string(n) +
                          ",) (one value per point), got " + std::string(py::str(a.attr("shape"))));
  }
  return py::array_t<float>::ensure(a);  // no copy for float32 (any stride); converts float64
}

}  // namespace

PointCloud CloudFromArrays(const py::handle& points, const py::handle& intensities,
                           const py::handle& times) {
  py::array p = FloatArray(points, "points");
  if (p.ndim() != 2 || (p.shape(1) != 3 && p.shape(1) != 4)) {
    std::string shape = "(";
    for (py::ssize_t i = 0; i < p.ndim(); ++i) {
      shape += (i ? ", " : "") + std::to_string(p.shape(i));
    }
    throw py::value_error("points: expected shape (N, 3) or (N, 4) [x, y, z(, intensity)], got " +
                          shape + ")");
  }
  const py::ssize_t n = p.shape(0);
  const bool has_intensity_column = p.shape(1) == 4;
  if (has_intensity_column && !intensities.is_none()) {
    throw py::value_error("intensities given twice: as the 4th column of points and as an array");
  }
  // float32 with consecutive x, y, z in each row: read in place through a strided view.
  py::array_t<float> p32;
  if (IsFloat32(p) && p.strides(1) == static_cast<py::ssize_t>(sizeof(float))) {
    p32 = py::reinterpret_borrow<py::array_t<float>>(p);
  } else {
    p32 = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(p);
  }
  // (A default-constructed py::array_t is an empty array, not a null handle: use optional.)
  std::optional<py::array_t<float>> i32, t32;
  if (!intensities.is_none()) i32 = Column(intensities, "intensities", n);
  if (!times.is_none()) t32 = Column(times, "times", n);

  PointCloudView view;
  view.xyz = p32.data();
  view.size = static_cast<size_t>(n);
  view.stride_bytes = static_cast<size_t>(p32.strides(0));
  if (has_intensity_column) {
    view.intensity = p32.data() + 3;
    view.intensity_stride_bytes = static_cast<size_t>(p32.strides(0));
  } else if (i32) {
    view.intensity = i32->data();
    view.intensity_stride_bytes = static_cast<size_t>(i32->strides(0));
  }
  if (t32) {
    view.dt_from_scan_start_s = t32->data();
    view.time_stride_bytes = static_cast<size_t>(t32->strides(0));
  }
  return PointCloud::FromView(view);
}

}  // namespace slam_mms::python
