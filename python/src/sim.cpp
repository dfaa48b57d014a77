// Simulator binding: simulate_drive writes a KITTI-raw-like drive with true ground truth.

#include "common.hpp"
#include "slam_mms/sim/drive_simulator.hpp"

namespace slam_mms::python {

void RegisterSim(py::module_& m) {
  m.def(
      "_simulate_drive",
      [](const std::filesystem::path& out_dir, const std::string& scenario, double duration_s,
         uint64_t seed, std::optional<std::filesystem::path> oxts_drive_dir, bool write_scene_cloud,
         int num_threads, py::object progress) {
        sim::DriveSimulator::Options o;
        o.scenario = scenario;
        o.duration_s = duration_s;
        o.seed = seed;
        if (oxts_drive_dir) o.oxts_drive_dir = *oxts_drive_dir;
        o.write_scene_cloud = write_scene_cloud;
        o.num_threads = num_threads;
        ThrowIfError(o.Validate());
        PendingError pending;
        StatusOr<sim::DriveSimulator::Summary> summary = WithoutGil([&] {
          StatusOr<sim::DriveSimulator> simulator = sim::DriveSimulator::Create(o);
          if (!simulator.ok()) return StatusOr<sim::DriveSimulator::Summary>(simulator.status());
          return simulator->Run(out_dir, [&](int done, int total) {
            if (progress.is_none()) return;
            py::gil_scoped_acquire acquire;
            if (pending.has()) return;
            try {
              progress(done, total);
            } catch (py::error_already_set& e) {
              pending.Keep(e);
            }
          });
        });
        pending.RaiseIfAny();
        const sim::DriveSimulator::Summary s = ValueOrThrow(std::move(summary));
        py::dict d;
        d["date_dir"] = s.date_dir;
        d["drive_dir"] = s.drive_dir;
        d["drive_name"] = s.drive_name;
        d["num_scans"] = s.num_scans;
        d["num_points"] = s.num_points;
        d["num_imu_records"] = s.num_imu_records;
        d["num_scene_points"] = s.num_scene_points;
        d["simulated_seconds"] = s.simulated_seconds;
        d["path_length_m"] = s.path_length_m;
        d["seconds_total"] = s.seconds_total;
        d["fraction_fixed"] = s.fraction_fixed;
        d["fraction_float"] = s.fraction_float;
        d["fraction_sps"] = s.fraction_sps;
        d["fraction_none"] = s.fraction_none;
        return d;
      },
      py::arg("out_dir"), py::arg("scenario") = "default", py::arg("duration_s") = 30.0,
      py::arg("seed") = 1, py::arg("oxts_drive_dir") = py::none(),
      py::arg("write_scene_cloud") = true, py::arg("num_threads") = 2,
      py::arg("progress") = py::none(),
      "Simulates a drive into out_dir (GIL released); returns the Summary as a dict.");
}

}  // namespace slam_mms::python
