// Core bindings: Status errors, enums, value types (GeodeticPoint, ImuSample,
// GnssFix, InsState, Scan, Trajectory) and the log sink that feeds Python's logging.

#include <condition_variable>
#include <deque>
#include <utility>

#include "common.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/ins/gnss_prior.hpp"
#include "slam_mms/io/trajectory_io.hpp"
#include "slam_mms/version.hpp"

namespace slam_mms::python {
namespace {

py::object& ErrorType() {
  static py::object* type = new py::object();  // leaked: lives as long as the interpreter
  return *type;
}

}  // namespace

void ThrowStatus(const Status& status) {
  const std::string& message = status.message();
  switch (status.code()) {
    case StatusCode::kInvalidArgument: throw py::value_error(message);
    case StatusCode::kNotFound:
      PyErr_SetString(PyExc_FileNotFoundError, message.c_str());
      throw py::error_already_set();
    case StatusCode::kOutOfRange: throw py::index_error(message);
    default: {
      py::object error = ErrorType()(status.ToString());
      error.attr("code") = StatusCodeName(status.code());
      PyErr_SetObject(ErrorType().ptr(), error.ptr());
      throw py::error_already_set();
    }
  }
}

void PendingError::Keep(py::error_already_set& e) {
  if (has_) return;  // the first one is the cause; later ones follow from it
  has_ = true;
  type_ = e.type();
  value_ = e.value();
  trace_ = e.trace();
}

void PendingError::RaiseIfAny() {
  if (!has_) return;
  has_ = false;
  PyErr_Restore(type_.release().ptr(), value_.release().ptr(), trace_.release().ptr());
  throw py::error_already_set();
}

// ---- the log sink -------------------------------------------------------------------------------
//
// The library calls the sink from any thread, under its own log mutex. The sink never touches
// Python: it only appends to a queue (its own mutex, never held while waiting for anything), so
// no lock order with the GIL exists. The queue is delivered to Python's logging (GIL held) by
// FlushLogQueue, called when a GIL-releasing binding returns, and by a Python daemon thread
// (slam_mms._logging) blocked in _drain_log with the GIL released, so messages logged during a
// long finish() or run_drive() appear while it runs.

namespace {

struct LogQueue {
  std::mutex mu;
  std::condition_variable cv;
  std::deque<std::pair<int, std::string>> messages;
  bool stopped = false;
  size_t dropped = 0;
};
constexpr size_t kMaxQueuedMessages = 100000;

LogQueue& Queue() {
  static LogQueue* q = new LogQueue();  // leaked: worker threads may log during shutdown
  return *q;
}
py::object*& EmitFunction() {
  static py::object* f = nullptr;
  return f;
}

void Sink(LogLevel level, const std::string& message) {
  LogQueue& q = Queue();
  {
    std::lock_guard<std::mutex> lock(q.mu);
    if (q.messages.size() >= kMaxQueuedMessages) {
      ++q.dropped;
      return;
    }
    q.messages.emplace_back(static_cast<int>(level), message);
  }
  q.cv.notify_one();
}

std::deque<std::pair<int, std::string>> TakeAll() {
  LogQueue& q = Queue();
  std::lock_guard<std::mutex> lock(q.mu);
  std::deque<std::pair<int, std::string>> out;
  out.swap(q.messages);
  if (q.dropped > 0) {
    out.emplace_back(static_cast<int>(LogLevel::kWarning),
                     std::to_string(q.dropped) + " log messages dropped (queue full)");
    q.dropped = 0;
  }
  return out;
}

// Python logging levels of the library's levels.
int PythonLevel(int level) {
  switch (static_cast<LogLevel>(level)) {
    case LogLevel::kDebug: return 10;
    case LogLevel::kInfo: return 20;
    case LogLevel::kWarning: return 30;
    case LogLevel::kError: return 40;
  }
  return 30;
}

void Emit(const std::deque<std::pair<int, std::string>>& messages) {
  py::object* emit = EmitFunction();
  if (emit == nullptr) return;
  for (const auto& [level, text] : messages) {
    try {
      (*emit)(PythonLevel(level), text);
    } catch (py::error_already_set& e) {
      e.discard_as_unraisable("slam_mms log handler");
    }
  }
}

}  // namespace

void FlushLogQueue() {
  if (EmitFunction() == nullptr) return;
  Emit(TakeAll());
}

void RegisterCore(py::module_& m) {
  m.attr("__version__") = SLAM_MMS_VERSION_STRING;
  ErrorType() = py::reinterpret_borrow<py::object>(PyErr_NewExceptionWithDoc(
      "slam_mms._slam_mms.Error",
      "A slam_mms Status that is not a bad argument, a missing file or an "
      "out-of-range index (DATA_LOSS, FAILED_PRECONDITION, INTERNAL, "
      "...); `code` holds the status code name.",
      PyExc_RuntimeError, nullptr));
  m.attr("Error") = ErrorType();

  // ---- logging ----
  py::enum_<LogLevel>(m, "LogLevel", "Library log levels (Python levels 10, 20, 30, 40).")
      .value("DEBUG", LogLevel::kDebug)
      .value("INFO", LogLevel::kInfo)
      .value("WARNING", LogLevel::kWarning)
      .value("ERROR", LogLevel::kError);
  m.def(
      "_install_log_sink",
      [](py::object emit) {
        py::object*& f = EmitFunction();
        delete f;
        f = new py::object(std::move(emit));
        {
          std::lock_guard<std::mutex> lock(Queue().mu);
          Queue().stopped = false;
        }
        SetLogSink(&Sink);
      },
      py::arg("emit"),
      "Installs the library log sink; emit(level: int, message: str) receives each message.");
  m.def(
      "_remove_log_sink",
      []() {
        SetLogSink(nullptr);
        FlushLogQueue();
        {
          std::lock_guard<std::mutex> lock(Queue().mu);
          Queue().stopped = true;
        }
        Queue().cv.notify_all();
        py::object*& f = EmitFunction();
        delete f;
        f = nullptr;
      },
      "Removes the sink (messages are dropped again) and ends _drain_log.");
  m.def(
      "_drain_log",
      [](double timeout_s) {
        std::deque<std::pair<int, std::string>> messages;
        bool stopped = false;
        {
          py::gil_scoped_release release;
          LogQueue& q = Queue();
          std::unique_lock<std::mutex> lock(q.mu);
          q.cv.wait_for(lock, std::chrono::duration<double>(timeout_s),
                        [&] { return q.stopped || !q.messages.empty(); });
          stopped = q.stopped;
        }
        if (!stopped) FlushLogQueue();
        return !stopped;
      },
      py::arg("timeout_s"),
      "Waits (GIL released) for queued messages and delivers them; False once the sink is "
      "removed.");
  m.def("flush_log", &FlushLogQueue,
        "Delivers the library messages logged so far by other threads to the Python handler now.");
  m.def(
      "set_min_log_level", [](LogLevel level) { SetMinLogLevel(level); }, py::arg("level"),
      "Messages below this level are not even formatted by the library (default INFO).");
  m.def("min_log_level", &MinLogLevel);
  m.def(
      "_log",
      [](LogLevel level, const std::string& message) { WithoutGil([&] { Log(level, message); }); },
      py::arg("level"), py::arg("message"),
      "Sends one message through the library's log path (for tests).");

  // ---- enums ----
  py::enum_<GnssFixType>(m, "GnssFixType", "GNSS solution quality, worst to best.")
      .value("NONE", GnssFixType::kNone)
      .value("SINGLE", GnssFixType::kSingle)
      .value("DIFFERENTIAL", GnssFixType::kDifferential)
      .value("RTK_FLOAT", GnssFixType::kRtkFloat)
      .value("RTK_FIXED", GnssFixType::kRtkFixed);
  py::enum_<GnssAvailability>(m, "GnssAvailability")
      .value("VALID", GnssAvailability::kValid)
      .value("DEGRADED", GnssAvailability::kDegraded)
      .value("OUTAGE", GnssAvailability::kOutage);

  // ---- value types ----
  py::class_<GeodeticPoint>(m, "GeodeticPoint", "A WGS-84 point [deg, deg, m].")
      .def(py::init([](double lat, double lon, double h) {
             return GeodeticPoint{lat, lon, h};
           }),
           py::arg("latitude_deg") = 0.0, py::arg("longitude_deg") = 0.0, py::arg("height_m") = 0.0)
      .def_readwrite("latitude_deg", &GeodeticPoint::latitude_deg)
      .def_readwrite("longitude_deg", &GeodeticPoint::longitude_deg)
      .def_readwrite("height_m", &GeodeticPoint::height_m)
      .def("__eq__",
           [](const GeodeticPoint& a, const GeodeticPoint& b) {
             return a.latitude_deg == b.latitude_deg && a.longitude_deg == b.longitude_deg &&
                    a.height_m == b.height_m;
           })
      .def("__repr__", [](const GeodeticPoint& g) {
        char buf[160];
        std::snprintf(buf, sizeof(buf),
                      "GeodeticPoint(latitude_deg=%.9f, longitude_deg=%.9f, "
                      "height_m=%.4f)",
                      g.latitude_deg, g.longitude_deg, g.height_m);
        return std::string(buf);
      });

  py::class_<ImuSample>(m, "ImuSample", "One IMU measurement in the body frame.")
      .def(py::init([](int64_t stamp_ns, const Eigen::Vector3d& a, const Eigen::Vector3d& g) {
             ImuSample s;
             s.stamp = Timestamp::FromNanoseconds(stamp_ns);
             s.accel_mps2 = a;
             s.gyro_radps = g;
             return s;
           }),
           py::arg("stamp_ns"), py::arg("accel_mps2"), py::arg("gyro_radps"))
      .def_property(
          "stamp_ns", [](const ImuSample& s) { return s.stamp.nanoseconds(); },
          [](ImuSample& s, int64_t ns) { s.stamp = Timestamp::FromNanoseconds(ns); })
      .def_readwrite("accel_mps2", &ImuSample::accel_mps2, "Specific force (gravity included).")
      .def_readwrite("gyro_radps", &ImuSample::gyro_radps);

  py::class_<GnssFix>(m, "GnssFix", "One GNSS position fix of the antenna in WGS-84.")
      .def(py::init([](int64_t stamp_ns, double lat, double lon, double h, double sh, double sv,
                       GnssFixType type, int sats) {
             return MakeGnssFix(stamp_ns, lat, lon, h, sh, sv, type, sats);
           }),
           py::arg("stamp_ns"), py::arg("latitude_deg"), py::arg("longitude_deg"),
           py::arg("height_m"), py::arg("sigma_horizontal_m") = 1.0,
           py::arg("sigma_vertical_m") = 1.5, py::arg("type") = GnssFixType::kSingle,
           py::arg("num_satellites") = 0)
      .def_property(
          "stamp_ns", [](const GnssFix& s) { return s.stamp.nanoseconds(); },
          [](GnssFix& s, int64_t ns) { s.stamp = Timestamp::FromNanoseconds(ns); })
      .def_readwrite("latitude_deg", &GnssFix::latitude_deg)
      .def_readwrite("longitude_deg", &GnssFix::longitude_deg)
      .def_readwrite("height_m", &GnssFix::height_m)
      .def_readwrite("sigma_horizontal_m", &GnssFix::sigma_horizontal_m)
      .def_readwrite("sigma_vertical_m", &GnssFix::sigma_vertical_m)
      .def_readwrite("type", &GnssFix::type)
      .def_readwrite("num_satellites", &GnssFix::num_satellites);

  py::class_<InsState>(m, "InsState",
                       "A navigation state of the body: stamp, T_world_body (4 x 4), velocity, "
                       "6 x 6 covariance [rot, trans], IMU biases.")
      .def(py::init([](int64_t stamp_ns, py::object T, const Eigen::Vector3d& v) {
             InsState s;
             s.stamp = Timestamp::FromNanoseconds(stamp_ns);
             if (!T.is_none()) s.T_world_body = ArrayToIsometry(T, "T_world_body");
             s.v_world_mps = v;
             return s;
           }),
           py::arg("stamp_ns") = 0, py::arg("T_world_body") = py::none(),
           py::arg("v_world_mps") = Eigen::Vector3d::Zero().eval())
      .def_property(
          "stamp_ns", [](const InsState& s) { return s.stamp.nanoseconds(); },
          [](InsState& s, int64_t ns) { s.stamp = Timestamp::FromNanoseconds(ns); })
      .def_property(
          "T_world_body", [](const InsState& s) { return IsometryToArray(s.T_world_body); },
          [](InsState& s, py::object T) { s.T_world_body = ArrayToIsometry(T, "T_world_body"); })
      .def_readwrite("v_world_mps", &InsState::v_world_mps)
      .def_readwrite("cov_T_world_body", &InsState::cov_T_world_body)
      .def_readwrite("accel_bias_mps2", &InsState::accel_bias_mps2)
      .def_readwrite("gyro_bias_radps", &InsState::gyro_bias_radps);

  // Scan: points are exposed as zero-copy views onto the scan's own arrays.
  py::class_<Scan>(m, "Scan",
                   "One LiDAR revolution in the lidar frame, not de-skewed. points (N x 3 "
                   "float32), intensities (N,), times (N,, offsets from stamp_start [s]) are "
                   "views onto the scan's own memory (no copy).")
      .def(py::init([](py::object points, int64_t start_ns, int64_t end_ns, py::object times,
                       py::object intensities, int64_t index, std::string source) {
             if (end_ns < start_ns) {
               throw py::value_error("stamp_end_ns = " + std::to_string(end_ns) +
                                     " is before stamp_start_ns = " + std::to_string(start_ns));
             }
             Scan s;
             s.cloud = CloudFromArrays(points, intensities, times);
             s.stamp_start = Timestamp::FromNanoseconds(start_ns);
             s.stamp_end = Timestamp::FromNanoseconds(end_ns);
             s.stamp_trigger = s.stamp_start;
             s.index = index;
             s.source = std::move(source);
             return s;
           }),
           py::arg("points"), py::arg("stamp_start_ns"), py::arg("stamp_end_ns"),
           py::arg("times") = py::none(), py::arg("intensities") = py::none(),
           py::arg("index") = -1, py::arg("source") = "")
      .def_readwrite("index", &Scan::index)
      .def_readwrite("source", &Scan::source)
      .def_property(
          "stamp_start_ns", [](const Scan& s) { return s.stamp_start.nanoseconds(); },
          [](Scan& s, int64_t ns) { s.stamp_start = Timestamp::FromNanoseconds(ns); })
      .def_property(
          "stamp_end_ns", [](const Scan& s) { return s.stamp_end.nanoseconds(); },
          [](Scan& s, int64_t ns) { s.stamp_end = Timestamp::FromNanoseconds(ns); })
      .def_property(
          "stamp_trigger_ns", [](const Scan& s) { return s.stamp_trigger.nanoseconds(); },
          [](Scan& s, int64_t ns) { s.stamp_trigger = Timestamp::FromNanoseconds(ns); })
      .def_property_readonly("duration_s", &Scan::DurationSeconds)
      .def_property_readonly("points",
                             [](py::object self) {
                               Scan& s = self.cast<Scan&>();
                               const auto n = static_cast<py::ssize_t>(s.cloud.size());
                               static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float));
                               return py::array_t<float>(
                                   {n, py::ssize_t{3}},
                                   {py::ssize_t{sizeof(Eigen::Vector3f)}, py::ssize_t{4}},
                                   n ? s.cloud.points().data()->data() : nullptr, self);
                             })
      .def_property_readonly("intensities",
                             [](py::object self) {
                               Scan& s = self.cast<Scan&>();
                               return py::array_t<float>(
                                   static_cast<py::ssize_t>(s.cloud.intensities().size()),
                                   s.cloud.intensities().data(), self);
                             })
      .def_property_readonly("times",
                             [](py::object self) {
                               Scan& s = self.cast<Scan&>();
                               return py::array_t<float>(
                                   static_cast<py::ssize_t>(s.cloud.time_offsets_s().size()),
                                   s.cloud.time_offsets_s().data(), self);
                             })
      .def("__len__", [](const Scan& s) { return s.cloud.size(); })
      .def("__repr__", [](const Scan& s) {
        return "Scan(index=" + std::to_string(s.index) +
               ", points=" + std::to_string(s.cloud.size()) +
               ", stamp_start_ns=" + std::to_string(s.stamp_start.nanoseconds()) + ")";
      });

  // Trajectory: stamps exact in ns, poses as TUM rows.
  py::class_<Trajectory>(m, "Trajectory",
                         "Time-ordered poses T_world_body with optional 6 x 6 covariances. "
                         "tum: N x 8 [t_s x y z qx qy qz qw]; stamps_ns: exact stamps.")
      .def(py::init<>())
      .def(py::init([](py::object tum, py::object stamps_ns, py::object covariances) {
             py::array a = FloatArray(tum, "tum");
             if (a.ndim() != 2 || a.shape(1) != 8) {
               throw py::value_error("tum: expected shape (N, 8) [t_s x y z qx qy qz qw]");
             }
             auto rows = py::array_t<double, py::array::forcecast>::ensure(a).unchecked<2>();
             const py::ssize_t n = rows.shape(0);
             std::optional<py::array_t<int64_t, py::array::forcecast>> stamps;
             if (!stamps_ns.is_none()) {
               stamps = py::array_t<int64_t, py::array::forcecast>::ensure(stamps_ns);
               if (!*stamps || stamps->ndim() != 1 || stamps->shape(0) != n) {
                 throw py::value_error("stamps_ns: expected shape (N,) int64, N = rows of tum");
               }
             }
             std::optional<py::array_t<double, py::array::forcecast>> covs;
             if (!covariances.is_none()) {
               covs = py::array_t<double, py::array::forcecast>::ensure(covariances);
               if (!*covs || covs->ndim() != 3 || covs->shape(0) != n || covs->shape(1) != 6 ||
                   covs->shape(2) != 6) {
                 throw py::value_error("covariances: expected shape (N, 6, 6)");
               }
             }
             Trajectory t;
             for (py::ssize_t i = 0; i < n; ++i) {
               StampedPose p;
               p.stamp = stamps ? Timestamp::FromNanoseconds(stamps->at(i))
                                : Timestamp::FromSeconds(rows(i, 0));
               Eigen::Quaterniond q(rows(i, 7), rows(i, 4), rows(i, 5), rows(i, 6));
               if (!(q.norm() > 0.0)) {
                 throw py::value_error("tum row " + std::to_string(i) + ": zero quaternion");
               }
               p.T_world_body.linear() = q.normalized().toRotationMatrix();
               p.T_world_body.translation() = Eigen::Vector3d(rows(i, 1), rows(i, 2), rows(i, 3));
               if (covs) {
                 Eigen::Matrix<double, 6, 6> c;
                 bool finite = true;
                 for (int r = 0; r < 6; ++r) {
                   for (int k = 0; k < 6; ++k) {
                     c(r, k) = covs->at(i, r, k);
                     finite = finite && std::isfinite(c(r, k));
                   }
                 }
                 if (finite) p.cov_T_world_body = c;
               }
               ThrowIfError(t.Add(p));
             }
             return t;
           }),
           py::arg("tum"), py::arg("stamps_ns") = py::none(), py::arg("covariances") = py::none(),
           "From N x 8 TUM rows; stamps_ns (exact, int64) replaces column 0 when given; "
           "covariances N x 6 x 6 (rows with NaN = none).")
      .def_property_readonly("tum", &TrajectoryTum)
      .def_property_readonly("stamps_ns", &TrajectoryStampsNs)
      .def_property_readonly("covariances", &TrajectoryCovariances)
      .def("__len__", &Trajectory::size)
      .def("path_length_m", &Trajectory::PathLength)
      .def(
          "between",
          [](const Trajectory& t, int64_t start_ns, int64_t end_ns) {
            const Timestamp a = Timestamp::FromNanoseconds(start_ns);
            const Timestamp b = Timestamp::FromNanoseconds(end_ns);
            Trajectory out;
            for (const StampedPose& p : t.poses()) {
              if (p.stamp >= a && p.stamp <= b) ThrowIfError(out.Add(p));
            }
            return out;
          },
          py::arg("start_ns"), py::arg("end_ns"),
          "The poses with start_ns <= stamp <= end_ns (exact copies, covariances included).")
      .def(
          "interpolate",
          [](const Trajectory& t, int64_t stamp_ns) {
            return IsometryToArray(
                ValueOrThrow(t.Interpolate(Timestamp::FromNanoseconds(stamp_ns))));
          },
          py::arg("stamp_ns"), "T_world_body (4 x 4) interpolated at stamp_ns.")
      .def_static(
          "read_tum",
          [](const std::filesystem::path& f) {
            return ValueOrThrow(WithoutGil([&] { return ReadTrajectoryTum(f); }));
          },
          py::arg("path"), "Reads a TUM file exactly (stamps to the nanosecond).")
      .def(
          "write_tum",
          [](const Trajectory& t, const std::filesystem::path& f) {
            ThrowIfError(WriteTrajectoryTum(t, f));
          },
          py::arg("path"))
      .def(
          "write_kitti",
          [](const Trajectory& t, const std::filesystem::path& f) {
            ThrowIfError(WriteTrajectoryKitti(t, f));
          },
          py::arg("path"))
      .def(
          "write_csv",
          [](const Trajectory& t, const std::filesystem::path& f) {
            ThrowIfError(WriteTrajectoryCsv(t, f));
          },
          py::arg("path"), "CSV with stamp_ns, pose and the 6 x 6 covariance.");
  py::implicitly_convertible<py::array, Trajectory>();
}

}  // namespace slam_mms::python
