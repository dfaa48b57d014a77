#pragma once
// Shared helpers of the _slam_mms extension: Status -> Python exceptions, numpy <-> Eigen/SDK
// conversions, and the registration functions of each binding area (one .cpp per area).
//
// GIL rules (see docs/python.md): every call that may run for long or may log from worker threads
// releases the GIL (py::gil_scoped_release) before entering the library and reacquires it only to
// build Python objects. Python callables called from C++ (result callbacks, progress) acquire the
// GIL themselves and never let a Python exception cross into library code: it is kept and raised
// when the binding call returns.

#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <Eigen/Geometry>
#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <type_traits>

#include "slam_mms/core/point_cloud.hpp"
#include "slam_mms/core/sensor_data.hpp"
#include "slam_mms/core/status.hpp"
#include "slam_mms/core/trajectory.hpp"

namespace slam_mms::python {

namespace py = pybind11;

/// A GnssFix from the Python arguments (GnssFix(...) and MappingSystem.add_gnss take the same).
inline GnssFix MakeGnssFix(int64_t stamp_ns, double lat, double lon, double h, double sh, double sv,
                           GnssFixType type, int sats) {
  GnssFix f;
  f.stamp = Timestamp::FromNanoseconds(stamp_ns);
  f.latitude_deg = lat;
  f.longitude_deg = lon;
  f.height_m = h;
  f.sigma_horizontal_m = sh;
  f.sigma_vertical_m = sv;
  f.type = type;
  f.num_satellites = sats;
  return f;
}

/// Raises the Python exception of a non-ok Status: InvalidArgument -> ValueError, NotFound ->
/// FileNotFoundError, OutOfRange -> IndexError, others -> slam_mms.Error (a RuntimeError with
/// `.code`). The message is the Status message (which names the field, file or option).
[[noreturn]] void ThrowStatus(const Status& status);
inline void ThrowIfError(const Status& status) {
  if (!status.ok()) ThrowStatus(status);
}
template <typename T>
T ValueOrThrow(StatusOr<T>&& s) {
  if (!s.ok()) ThrowStatus(s.status());
  return std::move(s).value();
}

/// Keeps the first Python exception raised by a callback that ran inside library code (under a
/// reacquired GIL) so the binding can raise it once the library call has returned.
class PendingError {
 public:
  /// Call with the GIL held, inside `catch (py::error_already_set& e)`.
  void Keep(py::error_already_set& e);
  bool has() const { return has_; }
  /// Re-raises the kept exception (GIL held); no-op without one.
  void RaiseIfAny();

 private:
  bool has_ = false;
  py::object type_, value_, trace_;
};

// ---- numpy <-> SDK ------------------------------------------------------------------------------

/// 4 x 4 homogeneous matrix of an isometry.
py::array_t<double> IsometryToArray(const Eigen::Isometry3d& T);
/// An isometry from a 4 x 4 array (ValueError naming `what` for a wrong shape or bottom row).
Eigen::Isometry3d ArrayToIsometry(const py::handle& array, const char* what);

/// One TUM row "t_s x y z qx qy qz qw", the quaternion as the TUM writer computes it (normalised,
/// w >= 0) so that rows equal the numbers of a TUM file slam_mms writes.
void PoseToTumRow(Timestamp stamp, const Eigen::Isometry3d& T, double* row);
/// N x 8 TUM rows, N x 6 x 6 covariances (NaN where a pose has none), N stamps [ns].
py::array_t<double> TrajectoryTum(const Trajectory& trajectory);
py::array_t<double> TrajectoryCovariances(const Trajectory& trajectory);
py::array_t<int64_t> TrajectoryStampsNs(const Trajectory& trajectory);

/// N x 4 float32 array [x, y, z, intensity] of a cloud (copied).
py::array_t<float> CloudToXyzi(const PointCloud& cloud);

/// A PointCloud from numpy: points N x 3 or N x 4 (4th column = intensity) float32 or float64;
/// optional intensities (N,) and per-point time offsets from scan start [s] (N,). float32 inputs
/// are read through a strided PointCloudView (no intermediate copy); float64 inputs are converted.
/// TypeError for a wrong dtype, ValueError for a wrong shape or length, naming the argument.
PointCloud CloudFromArrays(const py::handle& points, const py::handle& intensities,
                           const py::handle& times);
/// `obj` as a numpy array of float32 or float64 (any shape), or a TypeError naming `name`.
py::array FloatArray(const py::handle& obj, const char* name);

// ---- the log sink (core.cpp) --------------------------------------------------------------------

/// Delivers the library messages queued by the sink to the Python handler (GIL held).
void FlushLogQueue();

/// Runs `f` with the GIL released, then delivers the log messages it produced.
template <typename F>
auto WithoutGil(F&& f) -> decltype(f()) {
  if constexpr (std::is_void_v<decltype(f())>) {
    {
      py::gil_scoped_release release;
      f();
    }
    FlushLogQueue();
  } else {
    std::optional<decltype(f())> result;
    {
      py::gil_scoped_release release;
      result.emplace(f());
    }
    FlushLogQueue();
    return std::move(*result);
  }
}

/// Registration of each area (module.cpp calls them in this order).
void RegisterCore(py::module_& m);           // core.cpp: errors, enums, value types, logging
void RegisterOptions(py::module_& m);        // options.cpp: every Options struct
void RegisterMappingSystem(py::module_& m);  // mapping_system.cpp: MappingSystem, run_drive
void RegisterReaders(py::module_& m);        // readers.cpp: DriveReader and its adaptors
void RegisterEval(py::module_& m);           // eval.cpp: ATE, relative error, entropy, report
void RegisterSim(py::module_& m);            // sim.cpp: simulate_drive
void RegisterApp(py::module_& m);            // app.cpp: slam_mms_run itself (run_app)

}  // namespace slam_mms::python
