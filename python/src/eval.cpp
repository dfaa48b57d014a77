// Evaluation bindings: ATE, KITTI relative error, outage errors, map entropy, report.json (the C++
// writer, so the keys are exactly the schema of eval/report.hpp), map files, and the ground truth
// of a drive in a run's world frame (eval/ground_truth.hpp, the loader slam_mms_run uses), the
// PNG plots slam_mms_run draws (eval/plots.hpp) and slam_mms_run's --config file reader.

#include <cmath>

#include "common.hpp"
#include "slam_mms/eval/ground_truth.hpp"
#include "slam_mms/eval/map_entropy.hpp"
#include "slam_mms/eval/outage_error.hpp"
#include "slam_mms/eval/plots.hpp"
#include "slam_mms/eval/relative_error.hpp"
#include "slam_mms/eval/report.hpp"
#include "slam_mms/eval/trajectory_error.hpp"
#include "slam_mms/io/drive_reader.hpp"
#include "slam_mms/io/map_io.hpp"
#include "slam_mms/pipeline/mapping_system.hpp"
#include "slam_mms_run/config_file.hpp"

namespace slam_mms::python {
namespace {

using namespace slam_mms::eval;  // NOLINT(google-build-using-namespace)

py::array_t<double> Rows3(const std::vector<PoseError>& e,
                          const std::function<Eigen::Vector3d(const PoseError&)>& f) {
  py::array_t<double> a({static_cast<py::ssize_t>(e.size()), py::ssize_t{3}});
  auto r = a.mutable_unchecked<2>();
  for (size_t i = 0; i < e.size(); ++i) {
    const Eigen::Vector3d v = f(e[i]);
    for (int k = 0; k < 3; ++k) r(static_cast<py::ssize_t>(i), k) = v(k);
  }
  return a;
}
py::array_t<double> Column(const std::vector<PoseError>& e,
                           const std::function<double(const PoseError&)>& f) {
  py::array_t<double> a(static_cast<py::ssize_t>(e.size()));
  double* p = a.mutable_data();
  for (size_t i = 0; i < e.size(); ++i) p[i] = f(e[i]);
  return a;
}

std::optional<double> FiniteOrNone(double v) {
  if (!std::isfinite(v)) return std::nullopt;
  return v;
}

RelativeErrorOptions RelativeOptions(py::object lengths, int step_frames) {
  RelativeErrorOptions o;
  if (py::isinstance<py::str>(lengths)) {
    const std::string name = lengths.cast<std::string>();
    if (name == "kitti") {
      o = RelativeErrorOptions::Kitti();
    } else if (name == "short") {
      o = RelativeErrorOptions::ShortDrive();
    } else {
      throw py::value_error("segment_lengths_m = '" + name +
                            "'; must be 'kitti', 'short' or a list of lengths [m]");
    }
  } else {
    o.segment_lengths_m = lengths.cast<std::vector<double>>();
  }
  o.step_frames = step_frames;
  ThrowIfError(o.Validate());
  return o;
}

PlotOptions MakePlotOptions(const std::string& title, int width_px, int height_px) {
  PlotOptions o;
  o.title = title;
  o.width_px = width_px;
  o.height_px = height_px;
  ThrowIfError(o.Validate());
  return o;
}

std::vector<OutageWindow> Windows(const std::vector<std::pair<double, double>>& outages) {
  std::vector<OutageWindow> w;
  for (const auto& [start, duration] : outages) w.push_back({start, duration});
  return w;
}

}  // namespace

void RegisterEval(py::module_& m) {
  py::enum_<Alignment>(m, "Alignment", "NONE: as given (geo-referenced); SE3 / SIM3: Umeyama.")
      .value("NONE", Alignment::kNone)
      .value("SE3", Alignment::kSe3)
      .value("SIM3", Alignment::kSim3);

  py::class_<AteResult>(m, "AteResult", "Absolute trajectory error (read-only).")
      .def_readonly("alignment", &AteResult::alignment)
      .def_readonly("num_matched", &AteResult::num_matched)
      .def_readonly("num_unmatched", &AteResult::num_unmatched)
      .def_readonly("ate_rmse_m", &AteResult::ate_rmse_m)
      .def_readonly("ate_rmse_xyz_m", &AteResult::ate_rmse_xyz_m)
      .def_readonly("ate_mean_m", &AteResult::ate_mean_m)
      .def_readonly("ate_median_m", &AteResult::ate_median_m)
      .def_readonly("ate_max_m", &AteResult::ate_max_m)
      .def_readonly("rot_rmse_deg", &AteResult::rot_rmse_deg)
      .def_readonly("rot_rmse_rpy_deg", &AteResult::rot_rmse_rpy_deg)
      .def_readonly("rot_mean_rpy_deg", &AteResult::rot_mean_rpy_deg,
                    "Mean roll/pitch/yaw difference [deg], signed (estimate - ground truth).")
      .def_readonly("rot_max_deg", &AteResult::rot_max_deg)
      .def_property_readonly("scale", [](const AteResult& r) { return r.T_gt_est.scale; })
      .def_property_readonly("R_gt_est", [](const AteResult& r) { return r.T_gt_est.R; })
      .def_property_readonly("t_gt_est", [](const AteResult& r) { return r.T_gt_est.t; })
      .def_property_readonly("stamps_ns",
                             [](const AteResult& r) {
                               py::array_t<int64_t> a(static_cast<py::ssize_t>(r.errors.size()));
                               for (size_t i = 0; i < r.errors.size(); ++i) {
                                 a.mutable_data()[i] = r.errors[i].stamp.nanoseconds();
                               }
                               return a;
                             })
      .def_property_readonly(
          "position_errors_m",
          [](const AteResult& r) {
            return Rows3(r.errors, [](const PoseError& e) { return e.position_error_world; });
          },
          "N x 3 p_est - p_gt [m] per matched pose.")
      .def_property_readonly("position_error_norm_m",
                             [](const AteResult& r) {
                               return Column(r.errors,
                                             [](const PoseError& e) { return e.position_error_m; });
                             })
      .def_property_readonly("rpy_errors_rad",
                             [](const AteResult& r) {
                               return Rows3(r.errors,
                                            [](const PoseError& e) { return e.rpy_error_rad; });
                             })
      .def_property_readonly(
          "rotation_error_rad",
          [](const AteResult& r) {
            return Column(r.errors, [](const PoseError& e) { return e.rotation_error_rad; });
          })
      .def_property_readonly("p_est_world",
                             [](const AteResult& r) {
                               return Rows3(r.errors,
                                            [](const PoseError& e) { return e.p_est_world; });
                             })
      .def_property_readonly("p_gt_world", [](const AteResult& r) {
        return Rows3(r.errors, [](const PoseError& e) { return e.p_gt_world; });
      });

  m.def(
      "compute_ate",
      [](const Trajectory& estimate, const Trajectory& ground_truth, Alignment alignment,
         double max_ground_truth_gap_s) {
        AteOptions o;
        o.alignment = alignment;
        o.match.max_ground_truth_gap_s = max_ground_truth_gap_s;
        return ValueOrThrow(WithoutGil([&] { return ComputeAte(estimate, ground_truth, o); }));
      },
      py::arg("estimate"), py::arg("ground_truth"), py::arg("alignment") = Alignment::kNone,
      py::arg("max_ground_truth_gap_s") = 1.0,
      "ATE of estimate against ground_truth interpolated at each estimated stamp (no alignment "
      "by default). Trajectories: Trajectory objects or N x 8 TUM arrays.");

  py::class_<RelativeErrorResult>(m, "RelativeErrorResult", "KITTI devkit relative error.")
      .def_readonly("lengths_label", &RelativeErrorResult::lengths_label)
      .def_readonly("num_segments", &RelativeErrorResult::num_segments)
      .def_property_readonly("t_rel_pct",
                             [](const RelativeErrorResult& r) { return FiniteOrNone(r.t_rel_pct); })
      .def_property_readonly(
          "r_rel_deg_per_100m",
          [](const RelativeErrorResult& r) { return FiniteOrNone(r.r_rel_deg_per_100m); })
      .def_readonly("ground_truth_path_length_m", &RelativeErrorResult::ground_truth_path_length_m)
      .def_property_readonly("per_length", [](const RelativeErrorResult& r) {
        py::list out;
        for (const SegmentLengthError& s : r.per_length) {
          py::dict d;
          d["length_m"] = s.length_m;
          d["num_segments"] = s.num_segments;
          d["t_rel_pct"] = s.t_rel_pct;
          d["r_rel_deg_per_100m"] = s.r_rel_deg_per_100m;
          out.append(d);
        }
        return out;
      });
  m.def(
      "compute_relative_error",
      [](const Trajectory& estimate, const Trajectory& ground_truth, py::object lengths,
         int step_frames) {
        const RelativeErrorOptions o = RelativeOptions(lengths, step_frames);
        return ValueOrThrow(
            WithoutGil([&] { return ComputeRelativeError(estimate, ground_truth, o); }));
      },
      py::arg("estimate"), py::arg("ground_truth"), py::arg("segment_lengths_m") = "kitti",
      py::arg("step_frames") = 10,
      "KITTI relative error; segment_lengths_m: 'kitti' (100..800 m), 'short' (10..80 m) or a "
      "list of lengths [m]. t_rel_pct / r_rel_deg_per_100m are None without any segment.");

  py::class_<OutageErrorResult>(m, "OutageErrorResult", "Errors inside GNSS outage windows.")
      .def_readonly("num_poses", &OutageErrorResult::num_poses)
      .def_readonly("max_pos_err_m", &OutageErrorResult::max_pos_err_m)
      .def_readonly("rms_pos_err_m", &OutageErrorResult::rms_pos_err_m)
      .def_readonly("max_rot_err_deg", &OutageErrorResult::max_rot_err_deg)
      .def_readonly("rms_rot_err_deg", &OutageErrorResult::rms_rot_err_deg)
      .def_property_readonly("windows", [](const OutageErrorResult& r) {
        py::list out;
        for (const WindowError& w : r.windows) {
          py::dict d;
          d["start_s"] = w.window.start_s;
          d["duration_s"] = w.window.duration_s;
          d["num_poses"] = w.num_poses;
          d["max_pos_err_m"] = w.max_pos_err_m;
          d["rms_pos_err_m"] = w.rms_pos_err_m;
          d["max_rot_err_deg"] = w.max_rot_err_deg;
          d["rms_rot_err_deg"] = w.rms_rot_err_deg;
          out.append(d);
        }
        return out;
      });
  m.def(
      "compute_outage_errors",
      [](const AteResult& ate, const std::vector<std::pair<double, double>>& windows,
         int64_t reference_ns) {
        std::vector<OutageWindow> w;
        for (const auto& [s, d] : windows) w.push_back({s, d});
        return ValueOrThrow(
            ComputeOutageErrors(ate.errors, w, Timestamp::FromNanoseconds(reference_ns)));
      },
      py::arg("ate"), py::arg("windows"), py::arg("reference_ns"),
      "Errors of ate's poses inside [(start_s, duration_s), ...] relative to reference_ns.");

  py::class_<MapEntropyResult>(m, "MapEntropyResult", "Mean map entropy (eqs 26-27).")
      .def_property_readonly(
          "mean_map_entropy",
          [](const MapEntropyResult& r) { return FiniteOrNone(r.mean_map_entropy); })
      .def_property_readonly(
          "mean_plane_variance_m2",
          [](const MapEntropyResult& r) { return FiniteOrNone(r.mean_plane_variance_m2); })
      .def_readonly("num_input_points", &MapEntropyResult::num_input_points)
      .def_readonly("num_evaluated_points", &MapEntropyResult::num_evaluated_points)
      .def_readonly("num_valid_points", &MapEntropyResult::num_valid_points)
      .def_readonly("num_sparse_points", &MapEntropyResult::num_sparse_points)
      .def_readonly("num_degenerate_points", &MapEntropyResult::num_degenerate_points)
      .def_readonly("mean_neighbors", &MapEntropyResult::mean_neighbors);
  m.def(
      "compute_map_entropy",
      [](py::object points, double radius_m, double voxel_size_m, int min_neighbors,
         int num_threads) {
        const PointCloud cloud = CloudFromArrays(points, py::none(), py::none());
        MapEntropyOptions o;
        o.radius_m = radius_m;
        o.voxel_size_m = voxel_size_m;
        o.min_neighbors = min_neighbors;
        o.num_threads = num_threads;
        return ValueOrThrow(WithoutGil([&] { return ComputeMapEntropy(cloud, o); }));
      },
      py::arg("points"), py::arg("radius_m") = 0.5, py::arg("voxel_size_m") = 0.1,
      py::arg("min_neighbors") = 5, py::arg("num_threads") = 2,
      "Mean map entropy of points (N x 3 or N x 4); lower is sharper (GIL released).");

  py::class_<NeesResult>(m, "NeesResult",
                         "Consistency of a trajectory's covariances (3-dof NEES of position and "
                         "attitude; a consistent estimator: mean ~3, ~95 % inside).")
      .def(py::init<>())
      .def_readwrite("num_epochs", &NeesResult::num_epochs)
      .def_readwrite("position_mean", &NeesResult::position_mean)
      .def_readwrite("position_fraction_inside_95", &NeesResult::position_fraction_inside_95)
      .def_readwrite("attitude_mean", &NeesResult::attitude_mean)
      .def_readwrite("attitude_fraction_inside_95", &NeesResult::attitude_fraction_inside_95);
  m.def(
      "compute_nees",
      [](const Trajectory& estimate, const Trajectory& ground_truth) {
        return ValueOrThrow(ComputeNees(estimate, ground_truth));
      },
      py::arg("estimate"), py::arg("ground_truth"),
      "NEES of the estimate's own (absolute) covariances against the ground truth.");
  py::class_<ReferenceMetrics>(m, "ReferenceMetrics",
                               "A method's trajectory against a second reference (report.json "
                               "methods.<m>.vs_oxts_velocity); None is written as null.")
      .def(py::init<>())
      .def_readwrite("ate_rmse_m", &ReferenceMetrics::ate_rmse_m)
      .def_readwrite("rot_rmse_deg", &ReferenceMetrics::rot_rmse_deg)
      .def_readwrite("t_rel_pct", &ReferenceMetrics::t_rel_pct)
      .def_readwrite("r_rel_deg_per_100m", &ReferenceMetrics::r_rel_deg_per_100m)
      .def_readwrite("max_pos_err_in_outage_m", &ReferenceMetrics::max_pos_err_in_outage_m);
  py::class_<MethodReport>(m, "MethodReport",
                           "One method's numbers in report.json; None is written as null.")
      .def(py::init<>())
      .def_readwrite("ate_rmse_m", &MethodReport::ate_rmse_m)
      .def_readwrite("ate_rmse_xyz_m", &MethodReport::ate_rmse_xyz_m)
      .def_readwrite("rot_rmse_deg", &MethodReport::rot_rmse_deg)
      .def_readwrite("rot_rmse_rpy_deg", &MethodReport::rot_rmse_rpy_deg)
      .def_readwrite("rot_mean_rpy_deg", &MethodReport::rot_mean_rpy_deg)
      .def_readwrite("t_rel_pct", &MethodReport::t_rel_pct)
      .def_readwrite("r_rel_deg_per_100m", &MethodReport::r_rel_deg_per_100m)
      .def_readwrite("max_pos_err_in_outage_m", &MethodReport::max_pos_err_in_outage_m)
      .def_readwrite("max_rot_err_in_outage_deg", &MethodReport::max_rot_err_in_outage_deg)
      .def_readwrite("mme", &MethodReport::mme)
      .def_readwrite("nees", &MethodReport::nees)
      .def_readwrite("scans_per_s", &MethodReport::scans_per_s)
      .def_readwrite("peak_rss_mb", &MethodReport::peak_rss_mb)
      .def_readwrite("vs_oxts_velocity", &MethodReport::vs_oxts_velocity);
  m.def(
      "make_reference_metrics",
      [](const AteResult* ate, const RelativeErrorResult* relative,
         const OutageErrorResult* outage) { return MakeReferenceMetrics(ate, relative, outage); },
      py::arg("ate") = nullptr, py::arg("relative") = nullptr, py::arg("outage") = nullptr,
      "The fields of a ReferenceMetrics (None leaves null).");
  m.def(
      "make_method_report",
      [](const AteResult* ate, const RelativeErrorResult* relative, const OutageErrorResult* outage,
         const MapEntropyResult* entropy,
         const NeesResult* nees) { return MakeMethodReport(ate, relative, outage, entropy, nees); },
      py::arg("ate") = nullptr, py::arg("relative") = nullptr, py::arg("outage") = nullptr,
      py::arg("entropy") = nullptr, py::arg("nees") = nullptr,
      "The metric fields of a MethodReport (None leaves null)."),
      m.def(
          "report_to_json",
          [](const std::string& drive, int64_t scans, double duration_s,
             const std::string& ground_truth, const std::vector<std::pair<double, double>>& outages,
             const std::vector<std::pair<std::string, MethodReport>>& methods,
             std::optional<double> ground_truth_map_mme, const std::string& kind,
             int64_t scans_total,
             const std::vector<std::pair<std::string, std::string>>& skipped_scans,
             const std::vector<std::string>& command_line, const std::string& options_json,
             const std::string& georef_json, bool complete, const std::vector<std::string>& outputs,
             const std::string& imu_noise, std::optional<double> oxts_inertial_delay_s) {
            EvalReport r;
            r.input.imu_noise = imu_noise;
            r.input.oxts_inertial_delay_s = oxts_inertial_delay_s;
            r.input.drive = drive;
            r.input.kind = kind;
            r.input.scans = scans;
            r.input.scans_total = scans_total;
            r.input.duration_s = duration_s;
            r.input.ground_truth = ground_truth;
            for (const auto& [source, reason] : skipped_scans) {
              r.input.skipped_scans.push_back({source, reason});
            }
            for (const auto& [s, d] : outages) r.gnss_outages.push_back({s, d});
            r.methods = methods;
            r.ground_truth_map_mme = ground_truth_map_mme;
            r.command_line = command_line;
            r.options_json = options_json;
            r.georef_json = georef_json;
            r.complete = complete;
            r.outputs = outputs;
            return ValueOrThrow(ReportToJson(r));
          },
          py::arg("drive"), py::arg("scans"), py::arg("duration_s"), py::arg("ground_truth"),
          py::arg("gnss_outages"), py::arg("methods"), py::arg("ground_truth_map_mme") = py::none(),
          py::kw_only(), py::arg("kind") = "", py::arg("scans_total") = -1,
          py::arg("skipped_scans") = std::vector<std::pair<std::string, std::string>>(),
          py::arg("command_line") = std::vector<std::string>(), py::arg("options_json") = "",
          py::arg("georef_json") = "", py::arg("complete") = true,
          py::arg("outputs") = std::vector<std::string>(), py::arg("imu_noise") = "",
          py::arg("oxts_inertial_delay_s") = py::none(),
          "report.json text by the C++ writer (the schema of eval/report.hpp): kind "
          "(kitti_raw|folder|rosbag|simulated, '' = null), scans_total (< 0 = null), skipped_scans "
          "[(source, reason)], command_line, options_json / georef_json (JSON object texts, '' = "
          "null), complete, outputs (file names), imu_noise (the IMU noise file used, '' = null), "
          "oxts_inertial_delay_s (KITTI raw: the IMU stamps' delay, None = null).");
  m.def("peak_rss_mb", &PeakRssMb, "Peak resident set size of this process [MB] (Linux).");

  // ---- map files ----
  m.def(
      "read_ply",
      [](const std::filesystem::path& f) {
        const MapCloud map = ValueOrThrow(WithoutGil([&] { return ReadPly(f); }));
        return CloudToXyzi(map.cloud);
      },
      py::arg("path"), "N x 4 float32 [x y z intensity].");
  m.def(
      "write_map",
      [](py::object points, const std::filesystem::path& f, std::optional<GeodeticPoint> origin) {
        MapCloud map;
        map.cloud = CloudFromArrays(points, py::none(), py::none());
        const std::string ext = f.extension().string();
        Status s;
        if (ext == ".ply") {
          s = WithoutGil([&] { return WritePly(map, f); });
        } else if (ext == ".pcd") {
          s = WithoutGil([&] { return WritePcd(map, f); });
        } else if (ext == ".las") {
          if (!origin) throw py::value_error("write_map: a .las file needs the origin");
          s = WithoutGil([&] { return WriteLas(map, *origin, f); });
        } else {
          throw py::value_error("write_map: " + f.string() +
                                ": extension must be .ply, .pcd, .las");
        }
        ThrowIfError(s);
      },
      py::arg("points"), py::arg("path"), py::arg("origin") = py::none(),
      "Writes N x 3 / N x 4 points as PLY, PCD or geo-referenced LAS 1.4 (by extension).");

  // ---- PNG plots (eval/plots.hpp: the ones slam_mms_run draws) ----
  m.def(
      "plot_trajectories_top_view",
      [](const Trajectory& ground_truth, const std::string& ground_truth_name,
         const std::vector<std::pair<std::string, Trajectory>>& methods,
         const std::vector<std::pair<double, double>>& outages, int64_t outage_reference_ns,
         const std::filesystem::path& path, const std::string& title, int width_px, int height_px) {
        const PlotOptions o = MakePlotOptions(title, width_px, height_px);
        std::vector<NamedTrajectory> named;
        for (const auto& [name, t] : methods) named.push_back({name, t});
        const std::vector<OutageWindow> w = Windows(outages);
        ThrowIfError(WithoutGil([&] {
          return PlotTrajectoriesTopView({ground_truth_name, ground_truth}, named, w,
                                         Timestamp::FromNanoseconds(outage_reference_ns), path, o);
        }));
      },
      py::arg("ground_truth"), py::arg("ground_truth_name"), py::arg("methods"),
      py::arg("gnss_outages"), py::arg("outage_reference_ns"), py::arg("path"),
      py::arg("title") = "", py::arg("width_px") = 1400, py::arg("height_px") = 1050,
      "slam_mms_run's trajectories.png: the ground truth and [(name, Trajectory), ...] from "
      "above, outage windows [(start_s, duration_s)] relative to outage_reference_ns.");
  m.def(
      "plot_position_errors",
      [](const std::vector<std::pair<std::string, const AteResult*>>& methods,
         const std::vector<std::pair<double, double>>& outages, int64_t reference_ns,
         const std::filesystem::path& path, const std::string& title, int width_px, int height_px) {
        const PlotOptions o = MakePlotOptions(title, width_px, height_px);
        std::vector<ErrorSeries> series;
        for (const auto& [name, ate] : methods) {
          if (ate == nullptr) throw py::value_error("plot_position_errors: " + name + ": no ATE");
          series.push_back(
              MakeErrorSeries(name, ate->errors, Timestamp::FromNanoseconds(reference_ns)));
        }
        const std::vector<OutageWindow> w = Windows(outages);
        ThrowIfError(WithoutGil([&] { return PlotPositionErrors(series, w, path, o); }));
      },
      py::arg("methods"), py::arg("gnss_outages"), py::arg("reference_ns"), py::arg("path"),
      py::arg("title") = "", py::arg("width_px") = 1400, py::arg("height_px") = 1050,
      "slam_mms_run's position_error.png: [(name, AteResult), ...] over time from reference_ns.");
  m.def(
      "plot_map_height",
      [](py::object points, const std::filesystem::path& path, py::object overlay,
         const std::string& title, int width_px, int height_px) {
        const PlotOptions o = MakePlotOptions(title, width_px, height_px);
        const PointCloud cloud = CloudFromArrays(points, py::none(), py::none());
        std::vector<Eigen::Vector3d> line;
        if (!overlay.is_none()) {
          auto a = py::array_t<double, py::array::forcecast>::ensure(overlay);
          if (!a || a.ndim() != 2 || a.shape(1) != 3) {
            throw py::value_error("overlay: expected shape (N, 3)");
          }
          auto r = a.unchecked<2>();
          for (py::ssize_t i = 0; i < r.shape(0); ++i) line.emplace_back(r(i, 0), r(i, 1), r(i, 2));
        }
        ThrowIfError(WithoutGil([&] { return PlotMapHeight(cloud, line, path, o); }));
      },
      py::arg("points"), py::arg("path"), py::arg("overlay") = py::none(), py::arg("title") = "",
      py::arg("width_px") = 1400, py::arg("height_px") = 1050,
      "slam_mms_run's map_<mode>_height.png: N x 3/4 points from above coloured by height, an "
      "optional N x 3 line (the trajectory) on top.");

  // ---- ground truth (eval/ground_truth.hpp) and slam_mms_run's config file ----
  m.def(
      "has_simulator_ground_truth",
      [](const std::filesystem::path& d) { return eval::HasSimulatorGroundTruth(d); },
      py::arg("drive_dir"));
  m.def(
      "load_ground_truth",
      [](const std::filesystem::path& gt_dir, const DriveReader& reader,
         const GeodeticPoint& origin) {
        eval::GroundTruth gt =
            ValueOrThrow(WithoutGil([&] { return eval::LoadGroundTruth(gt_dir, reader, origin); }));
        py::dict d;
        d["kind"] = gt.kind;
        d["trajectory"] = std::move(gt.T_world_body);
        d["scene_map"] = gt.scene_map.empty() ? py::none() : py::cast(gt.scene_map);
        d["source"] = gt.source;
        return d;
      },
      py::arg("gt_dir"), py::arg("reader"), py::arg("origin"),
      "The ground truth slam_mms_run evaluates against (eval::LoadGroundTruth: "
      "gt_dir/ground_truth/ of the simulator, else the OXTS records "
      "of a KITTI reader; FileNotFoundError otherwise) carried into the ENU frame at origin "
      "through WGS-84: {'kind', 'trajectory', 'scene_map', 'source'}.");
  m.def(
      "load_oxts_ground_truth",
      [](const DriveReader& reader, const GeodeticPoint& origin, const std::string& positions) {
        eval::OxtsPositions p = eval::OxtsPositions::kRecorded;
        if (positions == "velocity") {
          p = eval::OxtsPositions::kVelocityIntegrated;
        } else if (positions != "recorded") {
          throw py::value_error("positions must be \"recorded\" or \"velocity\", not \"" +
                                positions + "\"");
        }
        eval::GroundTruth gt =
            ValueOrThrow(WithoutGil([&] { return eval::LoadOxtsGroundTruth(reader, origin, p); }));
        py::dict d;
        d["kind"] = gt.kind;
        d["trajectory"] = std::move(gt.T_world_body);
        d["source"] = gt.source;
        return d;
      },
      py::arg("reader"), py::arg("origin"), py::arg("positions") = "recorded",
      "The OXTS records of a KITTI reader (eval::LoadOxtsGroundTruth) in the ENU frame at origin, "
      "with their recorded positions or their velocities integrated from the first record "
      "(positions=\"velocity\": the second reference slam_mms_run reports as vs_oxts_velocity); "
      "FileNotFoundError for other readers: {'kind', 'trajectory', 'source'}.");
  m.def(
      "apply_config_file",
      [](const std::filesystem::path& f, MappingSystem::Options& options) {
        ThrowIfError(app::ApplyConfigFile(f, &options));
      },
      py::arg("path"), py::arg("options"),
      "Applies a slam_mms_run --config file (YAML) to options in place (ValueError naming the "
      "file, line and key).");
  m.def(
      "apply_config_text",
      [](const std::string& text, MappingSystem::Options& options, const std::string& name) {
        ThrowIfError(app::ApplyConfigText(text, name, &options));
      },
      py::arg("text"), py::arg("options"), py::arg("name") = "<config>",
      "apply_config_file on YAML text already read; `name` is used in messages.");
  m.def(
      "options_to_yaml", [](const MappingSystem::Options& o) { return app::OptionsToYaml(o); },
      py::arg("options"),
      "Every --config key of options as YAML with a type/default comment each, as slam_mms_run "
      "--dump-config writes it (apply_config_text reads it back unchanged).");
  m.def(
      "options_to_json", [](const MappingSystem::Options& o) { return app::OptionsToJson(o); },
      py::arg("options"),
      "The same keys and values as a JSON object text (report.json's options).");
  m.def(
      "config_keys",
      [] {
        py::list out;
        for (const app::ConfigKeyInfo& k : app::ConfigKeys()) {
          out.append(py::make_tuple(k.key, k.type, k.default_value));
        }
        return out;
      },
      "Every --config key as (key, type, default); slam_mms_run --config-keys prints them as "
      "YAML.");
}

}  // namespace slam_mms::python
