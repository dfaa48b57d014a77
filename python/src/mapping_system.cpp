// MappingSystem and RunDrive bindings. MappingSystem is not thread-safe: each Python object guards
// its system with a mutex, taken after the GIL is released (so a result callback that needs the
// GIL can never deadlock against a thread waiting for the mutex).

#include "slam_mms/pipeline/mapping_system.hpp"

#include <atomic>

#include "common.hpp"
#include "slam_mms/drive/drive_runner.hpp"
#include "slam_mms/drive/georeferenced_outputs.hpp"
#include "slam_mms/drive/scan_results_csv.hpp"

namespace slam_mms::python {
namespace {

class PyMappingSystem {
 public:
  explicit PyMappingSystem(const MappingSystem::Options& options) {
    StatusOr<std::unique_ptr<MappingSystem>> created =
        WithoutGil([&] { return MappingSystem::Create(options); });
    system_ = ValueOrThrow(std::move(created));
  }
  ~PyMappingSystem() {
    py::gil_scoped_release release;  // the system's threads may log while it shuts down
    std::lock_guard<std::mutex> lock(mu_);
    system_.reset();
  }

  // Runs f(system) with the GIL released under the mutex; raises a kept callback error, then the
  // Status error.
  template <typename F>
  auto Locked(F&& f) {
    auto result = WithoutGil([&] {
      std::lock_guard<std::mutex> lock(mu_);
      return f(*system_);
    });
    pending_.RaiseIfAny();
    return result;
  }
  void Call(const std::function<Status(MappingSystem&)>& f) { ThrowIfError(Locked(f)); }

  void SetCallback(py::object callback) {
    Locked([&](MappingSystem& s) {
      if (callback.is_none()) {
        s.SetResultCallback({});
      } else {
        s.SetResultCallback([this](const LocalizationResult& r) {
          py::gil_scoped_acquire acquire;
          if (pending_.has()) return;  // the first error stops the callbacks
          try {
            callback_(r);
          } catch (py::error_already_set& e) {
            pending_.Keep(e);
          }
        });
      }
      return 0;
    });
    callback_ = std::move(callback);
  }

 private:
  std::unique_ptr<MappingSystem> system_;
  std::mutex mu_;
  py::object callback_;
  PendingError pending_;
};

py::list AvailabilityList(const std::vector<GnssAvailabilityInterval>& intervals) {
  py::list out;
  for (const auto& i : intervals) {
    out.append(py::make_tuple(i.start.nanoseconds(), i.end.nanoseconds(), i.availability));
  }
  return out;
}

py::dict StatsDict(const Level2Stats& s) {
  py::dict d;
  d["solves"] = s.solves;
  d["loops_tested"] = s.loops_tested;
  d["loops_accepted"] = s.loops_accepted;
  d["map_to_map_accepted"] = s.map_to_map_accepted;
  d["gnss_factors"] = s.gnss_factors;
  d["last_solve_ms"] = s.last_solve_ms;
  return d;
}

std::optional<GeodeticPoint> OriginOrNone(const StatusOr<GeodeticPoint>& origin) {
  if (!origin.ok()) return std::nullopt;
  return *origin;
}

}  // namespace

void RegisterMappingSystem(py::module_& m) {
  py::enum_<MotionFactorType>(m, "MotionFactorType")
      .value("NONE", MotionFactorType::kNone)
      .value("ODOMETRY", MotionFactorType::kOdometry)
      .value("PREINTEGRATION", MotionFactorType::kPreintegration)
      .value("CONSTANT_VELOCITY", MotionFactorType::kConstantVelocity)
      .value("POS", MotionFactorType::kPos);
  py::enum_<IcpTermination>(m, "IcpTermination")
      .value("CONVERGED", IcpTermination::kConverged)
      .value("MAX_ITERATIONS", IcpTermination::kMaxIterations)
      .value("TOO_FEW_CORRESPONDENCES", IcpTermination::kTooFewCorrespondences)
      .value("DEGENERATE", IcpTermination::kDegenerate);

  using LR = LocalizationResult;
  py::class_<LR>(m, "LocalizationResult", "What level 1 reported for one scan (read-only).")
      .def_readonly("scan_index", &LR::scan_index)
      .def_property_readonly("stamp_ns", [](const LR& r) { return r.stamp.nanoseconds(); })
      .def_readonly("submap_id", &LR::submap_id)
      .def_readonly("new_submap", &LR::new_submap)
      .def_property_readonly("T_world_body",
                             [](const LR& r) { return IsometryToArray(r.T_world_body); })
      .def_readonly("cov_T_world_body", &LR::cov_T_world_body)
      .def_readonly("motion_factor", &LR::motion_factor)
      .def_readonly("registered", &LR::registered)
      .def_readonly("registration_used", &LR::registration_used)
      .def_readonly("registration_downweighted", &LR::registration_downweighted)
      .def_readonly("termination", &LR::termination)
      .def_readonly("num_inliers", &LR::num_inliers)
      .def_readonly("inlier_ratio", &LR::inlier_ratio)
      .def_readonly("rms_residual_m", &LR::rms_residual_m)
      .def_readonly("icp_iterations", &LR::icp_iterations)
      .def_readonly("degenerate", &LR::degenerate)
      .def_readonly("degeneracy_axis_information", &LR::degeneracy_axis_information)
      .def_readonly("consistency_mahalanobis_sq", &LR::consistency_mahalanobis_sq)
      .def_readonly("num_surfels", &LR::num_surfels)
      .def_readonly("num_model_surfels", &LR::num_model_surfels)
      .def_readonly("num_moving_objects", &LR::num_moving_objects)
      .def_readonly("num_moving_pixels", &LR::num_moving_pixels)
      .def_property_readonly("timings_ms",
                             [](const LR& r) {
                               py::dict d;
                               const auto values = r.timings.Values();
                               for (int i = 0; i < StageTimings::kNumStages; ++i) {
                                 d[StageTimings::Names()[i]] = values[i];
                               }
                               d["total"] = r.timings.total_ms;
                               return d;
                             })
      .def("__repr__", [](const LR& r) {
        return "LocalizationResult(scan_index=" + std::to_string(r.scan_index) +
               ", submap_id=" + std::to_string(r.submap_id) +
               ", motion_factor=" + MotionFactorTypeName(r.motion_factor) +
               ", registration_used=" + (r.registration_used ? "True" : "False") + ")";
      });

  py::class_<PyMappingSystem>(
      m, "MappingSystem",
      "The SDK facade: feed IMU, GNSS and scans in time order, finish(), read the trajectory "
      "and the map. Not thread-safe (calls are serialized); the GIL is released while it "
      "processes.")
      .def(py::init<const MappingSystem::Options&>(), py::arg("options"),
           "Validates the options (ValueError naming the field) and builds the system.")
      .def(
          "add_imu",
          [](PyMappingSystem& self, int64_t stamp_ns, const Eigen::Vector3d& accel,
             const Eigen::Vector3d& gyro) {
            ImuSample s;
            s.stamp = Timestamp::FromNanoseconds(stamp_ns);
            s.accel_mps2 = accel;
            s.gyro_radps = gyro;
            self.Call([&](MappingSystem& sys) { return sys.AddImu(s); });
          },
          py::arg("stamp_ns"), py::arg("accel_mps2"), py::arg("gyro_radps"),
          "One IMU sample (body frame): specific force [m/s^2], angular rate [rad/s].")
      .def(
          "add_imu",
          [](PyMappingSystem& self, const ImuSample& s) {
            self.Call([&](MappingSystem& sys) { return sys.AddImu(s); });
          },
          py::arg("sample"))
      .def(
          "add_imu_array",
          [](PyMappingSystem& self, py::array_t<int64_t, py::array::forcecast> stamps_ns,
             py::array_t<double, py::array::forcecast> samples) {
            if (stamps_ns.ndim() != 1 || samples.ndim() != 2 || samples.shape(1) != 6 ||
                samples.shape(0) != stamps_ns.shape(0)) {
              throw py::value_error(
                  "add_imu_array: expected stamps_ns (N,) and samples (N, 6) [ax ay az gx gy gz]");
            }
            std::vector<ImuSample> v(static_cast<size_t>(stamps_ns.shape(0)));
            auto t = stamps_ns.unchecked<1>();
            auto s = samples.unchecked<2>();
            for (size_t i = 0; i < v.size(); ++i) {
              const auto k = static_cast<py::ssize_t>(i);
              v[i].stamp = Timestamp::FromNanoseconds(t(k));
              v[i].accel_mps2 = Eigen::Vector3d(s(k, 0), s(k, 1), s(k, 2));
              v[i].gyro_radps = Eigen::Vector3d(s(k, 3), s(k, 4), s(k, 5));
            }
            self.Call([&](MappingSystem& sys) {
              for (size_t i = 0; i < v.size(); ++i) {
                Status st = sys.AddImu(v[i]);
                if (!st.ok()) return st.WithContext("IMU sample " + std::to_string(i));
              }
              return OkStatus();
            });
          },
          py::arg("stamps_ns"), py::arg("samples"),
          "Many IMU samples: stamps_ns (N,) int64, samples (N, 6) [ax ay az gx gy gz].")
      .def(
          "add_gnss",
          [](PyMappingSystem& self, const GnssFix& f) {
            self.Call([&](MappingSystem& sys) { return sys.AddGnss(f); });
          },
          py::arg("fix"))
      .def(
          "add_gnss",
          [](PyMappingSystem& self, int64_t stamp_ns, double lat, double lon, double h, double sh,
             double sv, GnssFixType type, int sats) {
            const GnssFix f = MakeGnssFix(stamp_ns, lat, lon, h, sh, sv, type, sats);
            self.Call([&](MappingSystem& sys) { return sys.AddGnss(f); });
          },
          py::arg("stamp_ns"), py::arg("latitude_deg"), py::arg("longitude_deg"),
          py::arg("height_m"), py::arg("sigma_horizontal_m") = 1.0,
          py::arg("sigma_vertical_m") = 1.5, py::arg("type") = GnssFixType::kSingle,
          py::arg("num_satellites") = 0, "One GNSS fix of the antenna (WGS-84).")
      .def(
          "add_scan",
          [](PyMappingSystem& self, const Scan& scan) {
            self.Call([&](MappingSystem& sys) { return sys.AddScan(scan); });
          },
          py::arg("scan"), "A Scan (e.g. from a reader).")
      .def(
          "add_scan",
          [](PyMappingSystem& self, py::object points, int64_t stamp_start_ns, int64_t stamp_end_ns,
             py::object times, py::object intensities, int64_t index, std::string source) {
            if (stamp_end_ns < stamp_start_ns) {
              throw py::value_error(
                  "stamp_end_ns = " + std::to_string(stamp_end_ns) +
                  " is before stamp_start_ns = " + std::to_string(stamp_start_ns));
            }
            Scan scan;
            scan.cloud = CloudFromArrays(points, intensities, times);
            scan.stamp_start = Timestamp::FromNanoseconds(stamp_start_ns);
            scan.stamp_end = Timestamp::FromNanoseconds(stamp_end_ns);
            scan.stamp_trigger = scan.stamp_start;
            scan.index = index;
            scan.source = std::move(source);
            self.Call([&](MappingSystem& sys) { return sys.AddScan(scan); });
          },
          py::arg("points"), py::arg("stamp_start_ns"), py::arg("stamp_end_ns"),
          py::arg("times") = py::none(), py::arg("intensities") = py::none(), py::arg("index") = -1,
          py::arg("source") = "",
          "A raw scan: points (N, 3) or (N, 4) float32/float64 in the lidar frame, optional "
          "per-point time offsets from stamp_start [s] (N,) and intensities (N,).")
      .def(
          "initialize_pos",
          [](PyMappingSystem& self, const InsState& s,
             const std::optional<Eigen::Vector3d>& sigma_rpy_rad) {
            self.Call([&](MappingSystem& sys) { return sys.InitializePos(s, sigma_rpy_rad); });
          },
          py::arg("state"), py::arg("sigma_rpy_rad") = py::none(),
          "Initial attitude and velocity of the POS at state.stamp_ns; sigma_rpy_rad: the "
          "attitude's stated 1-sigma roll, pitch, yaw [rad] (DriveStreams."
          "initial_attitude_sigma_rpy_rad), None: the filter's init sigmas.")
      .def(
          "add_ins_pose",
          [](PyMappingSystem& self, const InsState& s) {
            self.Call([&](MappingSystem& sys) { return sys.AddInsPose(s); });
          },
          py::arg("state"), "An external POS pose instead of IMU + GNSS.")
      .def(
          "finish",
          [](PyMappingSystem& self) { self.Call([](MappingSystem& sys) { return sys.Finish(); }); },
          "Processes the queued scans and runs the final level-2 refinement (GIL released).")
      .def("set_result_callback", &PyMappingSystem::SetCallback, py::arg("callback"),
           "callback(LocalizationResult) after every processed scan (None removes it). An "
           "exception in it stops further callbacks and is raised by the adding call.")
      .def(
          "final_trajectory",
          [](PyMappingSystem& self) {
            const Trajectory t =
                self.Locked([](MappingSystem& sys) { return sys.FinalTrajectory(); });
            return py::make_tuple(TrajectoryTum(t), TrajectoryCovariances(t));
          },
          "(N x 8 TUM rows [t_s x y z qx qy qz qw], N x 6 x 6 covariances [rot, trans]).")
      .def(
          "final_stamps_ns",
          [](PyMappingSystem& self) {
            return TrajectoryStampsNs(
                self.Locked([](MappingSystem& sys) { return sys.FinalTrajectory(); }));
          },
          "The exact stamps of final_trajectory() [ns].")
      .def(
          "final_trajectory_object",
          [](PyMappingSystem& self) {
            return self.Locked([](MappingSystem& sys) { return sys.FinalTrajectory(); });
          },
          "final_trajectory() as a Trajectory (exact stamps, for the eval functions).")
      .def(
          "final_map",
          [](PyMappingSystem& self) {
            return CloudToXyzi(self.Locked([](MappingSystem& sys) { return sys.FinalMap(); }));
          },
          "N x 4 float32 [x y z intensity] in world.")
      .def(
          "surfels",
          [](PyMappingSystem& self) {
            const std::vector<Surfel> s =
                self.Locked([](MappingSystem& sys) { return sys.SurfelMapSnapshot(); });
            py::array_t<float> a({static_cast<py::ssize_t>(s.size()), py::ssize_t{8}});
            auto r = a.mutable_unchecked<2>();
            for (size_t i = 0; i < s.size(); ++i) {
              const auto k = static_cast<py::ssize_t>(i);
              for (int j = 0; j < 3; ++j) r(k, j) = s[i].position(j);
              for (int j = 0; j < 3; ++j) r(k, 3 + j) = s[i].normal(j);
              r(k, 6) = s[i].radius;
              r(k, 7) = s[i].confidence;
            }
            return a;
          },
          "N x 8 float32 [x y z nx ny nz radius confidence] (world).")
      .def_property_readonly(
          "results",
          [](PyMappingSystem& self) {
            return self.Locked([](MappingSystem& sys) { return sys.results(); });
          },
          "Per-scan level-1 results so far (list of LocalizationResult).")
      .def_property_readonly(
          "origin",
          [](PyMappingSystem& self) {
            return OriginOrNone(self.Locked([](MappingSystem& sys) { return sys.Origin(); }));
          },
          "WGS-84 origin of world (GeodeticPoint), None before it is known.")
      .def(
          "gnss_availability",
          [](PyMappingSystem& self) {
            return AvailabilityList(
                self.Locked([](MappingSystem& sys) { return sys.GnssAvailability(); }));
          },
          "List of (start_ns, end_ns, GnssAvailability).")
      .def_property_readonly(
          "num_skipped_scans",
          [](PyMappingSystem& self) {
            return self.Locked([](MappingSystem& sys) { return sys.num_skipped_scans(); });
          })
      .def_property_readonly(
          "num_pos_jumps",
          [](PyMappingSystem& self) {
            return self.Locked([](MappingSystem& sys) { return sys.num_pos_jumps(); });
          })
      .def_property_readonly(
          "level2_stats",
          [](PyMappingSystem& self) {
            return StatsDict(self.Locked([](MappingSystem& sys) { return sys.level2_stats(); }));
          })
      .def_property_readonly("options", [](PyMappingSystem& self) {
        return self.Locked([](MappingSystem& sys) { return sys.options(); });
      });

  // ---- RunDrive ----
  py::class_<DriveRun>(m, "DriveRun",
                       "What RunDrive returned: the estimates (also after an error or a stop) "
                       "and the run's counts.")
      .def_readonly("mode", &DriveRun::mode)
      .def_readonly("trajectory", &DriveRun::trajectory, "Trajectory (exact stamps).")
      .def_readonly("results", &DriveRun::results)
      .def_property_readonly("map_points", [](const DriveRun& r) { return CloudToXyzi(r.map); })
      .def_readonly("origin", &DriveRun::origin)
      .def_property_readonly("availability",
                             [](const DriveRun& r) { return AvailabilityList(r.availability); })
      .def_property_readonly("first_scan_start_ns",
                             [](const DriveRun& r) -> std::optional<int64_t> {
                               if (!r.first_scan_start) return std::nullopt;
                               return r.first_scan_start->nanoseconds();
                             })
      .def_readonly("wall_s", &DriveRun::wall_s)
      .def_readonly("scans_total", &DriveRun::scans_total)
      .def_readonly("scans_processed", &DriveRun::scans_processed)
      .def_readonly("scans_unreadable", &DriveRun::scans_unreadable)
      .def_readonly("scans_skipped_by_system", &DriveRun::scans_skipped_by_system)
      .def_readonly("skipped_scans", &DriveRun::skipped_scans)
      .def_readonly("finished", &DriveRun::finished)
      .def_readonly("complete", &DriveRun::complete)
      .def_readonly("smoothed_pos", &DriveRun::smoothed_pos)
      .def_readonly("smoothing_wall_s", &DriveRun::smoothing_wall_s)
      .def_property_readonly(
          "extrinsic_calibration",
          [](const DriveRun& r) -> py::object {
            if (!r.extrinsic_calibration) return py::none();
            const ExtrinsicCalibration& c = *r.extrinsic_calibration;
            py::dict d;
            d["T_body_lidar_initial"] = IsometryToArray(c.T_body_lidar_initial);
            d["T_body_lidar_estimated"] = IsometryToArray(c.T_body_lidar_estimated);
            d["time_offset_s"] = c.time_offset_s;
            d["correction_rpy_rad"] = c.correction_rpy_rad;
            d["correction_xyz_m"] = c.correction_xyz_m;
            d["sigma_rpy_rad"] = c.sigma_rpy_rad;
            d["sigma_xyz_m"] = c.sigma_xyz_m;
            d["sigma_time_s"] = c.sigma_time_s;
            py::dict observable, applied;
            for (int i = 0; i < 7; ++i) {
              observable[ExtrinsicParameterName(i)] = c.observable[i];
              applied[ExtrinsicParameterName(i)] = c.applied[i];
            }
            d["observable"] = observable;
            d["applied"] = applied;
            d["scans_used"] = c.scans_used;
            d["rms_initial_m"] = c.rms_initial_m;
            d["rms_final_m"] = c.rms_final_m;
            d["wall_s"] = c.wall_s;
            return d;
          },
          "With estimate_extrinsics: the boresight self-calibration the run was made with "
          "(CalibrateExtrinsics' estimate, its sigmas and which of the seven parameters the drive "
          "observes, and which it applied), else None.")
      .def_property_readonly("ok", [](const DriveRun& r) { return r.status.ok(); })
      .def_property_readonly("status_message",
                             [](const DriveRun& r) { return r.status.ToString(); })
      .def(
          "raise_if_error", [](const DriveRun& r) { ThrowIfError(r.status); },
          "Raises the run's fatal error (ValueError for bad options, ...), if any.")
      .def_property_readonly(
          "level1_trajectory",
          [](const DriveRun& r) {
            // Level 1 alone (before any level-2 correction), as slam_mms_run's
            // <method>_level1.tum: one pose per result, up to the first out-of-order stamp.
            Trajectory level1;
            for (const LocalizationResult& lr : r.results) {
              if (!level1.Add(lr.stamp, lr.T_world_body).ok()) break;
            }
            return level1;
          },
          "Trajectory of the level-1 poses of the results (slam_mms_run's <mode>_level1.tum).")
      .def(
          "write_scan_results_csv",
          [](const DriveRun& r, const std::filesystem::path& path) {
            ThrowIfError(WithoutGil([&] { return WriteScanResultsCsv(r.results, path); }));
          },
          py::arg("path"), "Writes the per-scan results as slam_mms_run's <mode>_scans.csv.")
      .def_property_readonly(
          "map_time_ns",
          [](const DriveRun& r) {
            py::array_t<int64_t> a(static_cast<py::ssize_t>(r.map_stamps.time_ns.size()));
            std::copy(r.map_stamps.time_ns.begin(), r.map_stamps.time_ns.end(), a.mutable_data());
            return a;
          },
          "Per map point: UTC ns of the first point observed in its voxel (empty if unknown).")
      .def_property_readonly(
          "map_scan_index",
          [](const DriveRun& r) {
            py::array_t<int64_t> a(static_cast<py::ssize_t>(r.map_stamps.scan_index.size()));
            std::copy(r.map_stamps.scan_index.begin(), r.map_stamps.scan_index.end(),
                      a.mutable_data());
            return a;
          },
          "Per map point: the scan index of that first point (LAS point source ID mod 65536).")
      .def(
          "write_geo_outputs",
          [](const DriveRun& r, const std::string& name, const std::filesystem::path& out_dir,
             const std::string& crs, double las_tile_size_m,
             std::optional<GeodeticPoint> run_origin) {
            GeoOutputOptions o;
            o.crs = crs;
            o.las_tile_size_m = las_tile_size_m;
            o.run_origin = run_origin;
            ThrowIfError(WithoutGil([&] {
              return WriteGeoreferencedOutputs(name, r.mode, r.trajectory, r.map, r.map_stamps,
                                               r.origin, o, out_dir);
            }));
          },
          py::arg("name"), py::arg("out_dir"), py::arg("crs") = "",
          py::arg("las_tile_size_m") = 0.0, py::arg("run_origin") = py::none(),
          "slam_mms_run's geo-referenced files of this method: <name>_wgs84.csv, <name>_utm.csv "
          "(<name>_epsg<code>.csv with crs), map_<name>.las or map_<name>_tiles/ "
          "(WriteGeoreferencedOutputs).");
  m.def(
      "check_geo_output_options",
      [](const std::string& crs, double las_tile_size_m) {
        GeoOutputOptions o;
        o.crs = crs;
        o.las_tile_size_m = las_tile_size_m;
        ThrowIfError(o.Validate());
      },
      py::arg("crs") = "", py::arg("las_tile_size_m") = 0.0,
      "Raises ValueError for an unusable --crs or --las-tile-size (before any processing).");
  m.def(
      "georef_json",
      [](const GeodeticPoint& origin, const std::string& crs) {
        GeoOutputOptions o;
        o.crs = crs;
        return ValueOrThrow(RunGeorefJson(origin, o));
      },
      py::arg("origin"), py::arg("crs") = "", "georef.json's text (also report.json's georef).");
  m.def(
      "write_georef_json",
      [](const GeodeticPoint& origin, const std::filesystem::path& out_dir,
         const std::string& crs) {
        GeoOutputOptions o;
        o.crs = crs;
        ThrowIfError(WithoutGil([&] { return WriteRunGeorefJson(origin, o, out_dir); }));
      },
      py::arg("origin"), py::arg("out_dir"), py::arg("crs") = "",
      "Writes out_dir/georef.json (slam_mms_run writes it once, for the first method's origin).");
  m.def(
      "write_scan_results_csv",
      [](const std::vector<LocalizationResult>& results, const std::filesystem::path& path) {
        ThrowIfError(WithoutGil([&] { return WriteScanResultsCsv(results, path); }));
      },
      py::arg("results"), py::arg("path"),
      "Writes LocalizationResults (MappingSystem.results) as slam_mms_run's <mode>_scans.csv.");

  m.def(
      "apply_input_models",
      [](const MappingSystem::Options& options, const DriveStreams& streams) {
        return ApplyInputModels(options, streams);
      },
      py::arg("options"), py::arg("streams"),
      "A copy of options with what the input states about its sensors applied, as run_drive "
      "does: the stated IMU noise (use_stated_imu_noise) and the vehicle's non-holonomic "
      "constraint where its IMU frame is the vehicle's (vehicle_nhc_sigma_mps). For hosts that "
      "feed a MappingSystem from a reader's streams themselves.");

  m.def(
      "_run_drive",
      [](const DriveReader& reader, const MappingSystem::Options& options, py::object progress,
         PosWorkflow pos, bool estimate_extrinsics) {
        PendingError pending;
        std::atomic<bool> stop{false};
        DriveRunCallbacks callbacks;
        callbacks.stop = &stop;
        callbacks.on_scan = [&](size_t fed, size_t total) {
          py::gil_scoped_acquire acquire;
          if (pending.has()) return;
          try {
            if (PyErr_CheckSignals() != 0) throw py::error_already_set();  // Ctrl-C
            if (!progress.is_none()) progress(fed, total);
          } catch (py::error_already_set& e) {
            pending.Keep(e);
            stop = true;  // RunDrive finishes what it was fed, then returns
          }
        };
        DriveRunOptions run_options;
        run_options.pos = pos;
        run_options.estimate_extrinsics = estimate_extrinsics;
        DriveRun run =
            WithoutGil([&] { return RunDrive(reader, options, callbacks, run_options); });
        pending.RaiseIfAny();
        return run;
      },
      py::arg("reader"), py::arg("options"), py::arg("progress") = py::none(),
      py::arg("pos") = PosWorkflow::kForward, py::arg("estimate_extrinsics") = false,
      "The C++ RunDrive (GIL released); pos: the POS `full` runs on; estimate_extrinsics: the "
      "boresight self-calibration first (DriveRunOptions). progress(fed, total) after "
      "every scan; an exception in "
      "it (or Ctrl-C) stops the run after the current scan and is raised.");
}

}  // namespace slam_mms::python
