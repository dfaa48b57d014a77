#include "slam_mms/drive/drive_runner.hpp"

#include <GeographicLib/LocalCartesian.hpp>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>

#include "core/option_error.hpp"
#include "ins/pos_smoother.hpp"
#include "slam_mms/core/geodesy.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/drive/open_drive.hpp"

namespace slam_mms {
namespace {

constexpr double kDegToRad = M_PI / 180.0;

// The next record of the three input streams in time order (IMU, then GNSS/POS, then the scan
// at equal stamps; a scan once the streams reached its end).
enum class Next { kImu, kGnss, kPos, kScan, kNone };

}  // namespace

StatusOr<std::vector<InsState>> PosRecordsInWorld(const std::vector<PosRecord>& records,
                                                  const GeodeticPoint& origin) {
  const GeographicLib::LocalCartesian lc(origin.latitude_deg, origin.longitude_deg,
                                         origin.height_m);
  const Eigen::Matrix3d R_world_ecef =
      R_ecef_enu(origin.latitude_deg, origin.longitude_deg).transpose();
  std::vector<InsState> states;
  states.reserve(records.size());
  for (size_t i = 0; i < records.size(); ++i) {
    const PosRecord& r = records[i];
    if (!(std::abs(r.latitude_deg) <= 90.0) || !(std::abs(r.longitude_deg) <= 180.0) ||
        !std::isfinite(r.height_m)) {
      return InvalidArgumentError("external POS record " + std::to_string(i) +
                                  ": position outside the WGS-84 range");
    }
    InsState s;
    s.stamp = r.stamp;
    Eigen::Vector3d p_world;
    lc.Forward(r.latitude_deg, r.longitude_deg, r.height_m, p_world.x(), p_world.y(), p_world.z());
    // R_world_body = R_world_ecef * R_ecef_local * R_local_body.
    s.T_world_body.linear() =
        R_world_ecef * R_ecef_enu(r.latitude_deg, r.longitude_deg) * r.R_enu_body;
    s.T_world_body.translation() = p_world;
    const Eigen::Vector3d sigma_rot =
        r.sigma_rpy_rad.value_or(Eigen::Vector3d::Constant(0.01 * kDegToRad));
    const Eigen::Vector3d sigma_pos = r.sigma_enu_m.value_or(Eigen::Vector3d::Constant(0.01));
    Vector6d var;
    var << sigma_rot.cwiseAbs2(), sigma_pos.cwiseAbs2();
    s.cov_T_world_body = var.asDiagonal();
    states.push_back(s);
  }
  return states;
}

const char* PosWorkflowName(PosWorkflow pos) {
  return pos == PosWorkflow::kSmoothed ? "smoothed" : "forward";
}

bool ParsePosWorkflow(const std::string& name, PosWorkflow* pos) {
  for (PosWorkflow p : {PosWorkflow::kForward, PosWorkflow::kSmoothed}) {
    if (name == PosWorkflowName(p)) {
      *pos = p;
      return true;
    }
  }
  return false;
}

bool UsesStatedImuNoise(const MappingSystem::Options& options, const DriveStreams& streams) {
  return options.use_stated_imu_noise && streams.imu_noise.has_value();
}

bool UsesVehicleConstraint(const MappingSystem::Options& options, const DriveStreams& streams) {
  return streams.imu_frame_is_vehicle_frame && options.vehicle_nhc_sigma_mps > 0.0 &&
         options.ins.nhc_sigma_mps == 0.0;
}

MappingSystem::Options ApplyInputModels(const MappingSystem::Options& options,
                                        const DriveStreams& streams) {
  MappingSystem::Options out = options;
  if (UsesStatedImuNoise(options, streams)) out.SetImuNoise(*streams.imu_noise);
  if (UsesVehicleConstraint(options, streams))
    out.ins.nhc_sigma_mps = options.vehicle_nhc_sigma_mps;
  return out;
}

StatusOr<OfflinePos> ComputeOfflinePos(const DriveReader& reader,
                                       const MappingSystem::Options& input_options) {
  const DriveStreams& in = reader.streams();
  const MappingSystem::Options options = ApplyInputModels(input_options, in);
  OfflinePos out;
  if (in.pos.empty()) {
    PosSmoother::Options so;
    so.ins = options.ins;
    so.origin = options.origin;
    so.gnss_outages = options.gnss_outages;
    if (reader.NumScans() > 0) so.outage_reference = reader.ScanStart(0);
    so.initial_sigma_rpy_rad = in.initial_attitude_sigma_rpy_rad;
    StatusOr<PosSmoother::Result> smoothed =
        PosSmoother::Run(so, in.imu, in.gnss, in.initial_state);
    if (!smoothed.ok()) return smoothed.status().WithContext(reader.Describe());
    out.origin = smoothed->origin;
    out.states = std::move(smoothed->smoothed);
    out.smoothed = true;
    return out;
  }
  out.origin = options.origin
                   ? *options.origin
                   : GeodeticPoint{in.pos.front().latitude_deg, in.pos.front().longitude_deg,
                                   in.pos.front().height_m};
  StatusOr<std::vector<InsState>> converted = PosRecordsInWorld(in.pos, out.origin);
  if (!converted.ok()) return converted.status().WithContext(reader.Describe());
  out.states = std::move(converted).value();
  return out;
}

Status DriveRunOptions::Validate() const {
  if (pos != PosWorkflow::kForward && pos != PosWorkflow::kSmoothed) {
    return internal::OptionError("DriveRunOptions", "pos", static_cast<double>(pos),
                                 "must be kForward or kSmoothed");
  }
  return extrinsic_calibration.Validate();
}

StatusOr<ExtrinsicCalibration> CalibrateDriveExtrinsics(
    const DriveReader& reader, const MappingSystem::Options& options,
    const ExtrinsicCalibrationOptions& calibration, const std::atomic<bool>* stop) {
  SLAM_MMS_ASSIGN_OR_RETURN(const OfflinePos pos, ComputeOfflinePos(reader, options));
  return CalibrateExtrinsics(reader, pos.states, reader.streams().T_body_lidar, 0.0, calibration,
                             stop, options.num_threads);
}

namespace {

DriveRun RunMethod(const DriveReader& reader, const MappingSystem::Options& base_options,
                   const DriveRunCallbacks& callbacks, const DriveRunOptions& run_options) {
  const DriveStreams& in = reader.streams();
  DriveRun run;
  run.mode = base_options.mode;
  run.scans_total = reader.NumScans();
  const auto t0 = std::chrono::steady_clock::now();

  MappingSystem::Options options = ApplyInputModels(base_options, in);
  if (UsesStatedImuNoise(options, in)) {
    SLAM_MMS_LOG(kInfo) << reader.Describe() << ": IMU noise as stated in " << in.imu_noise_source;
  }
  if (UsesVehicleConstraint(base_options, in)) {
    SLAM_MMS_LOG(kInfo) << reader.Describe() << ": the IMU frame is the vehicle's; POS with the "
                        << "non-holonomic constraint (" << options.ins.nhc_sigma_mps << " m/s)";
  }
  const bool smooth =
      base_options.mode == MappingMode::kGnssInsSmoothed ||
      (base_options.mode == MappingMode::kFull && run_options.pos == PosWorkflow::kSmoothed);
  // The offline method places scans through the external-POS path of a gnss_ins system.
  if (options.mode == MappingMode::kGnssInsSmoothed) options.mode = MappingMode::kGnssIns;
  std::vector<InsState> pos;
  if (smooth || !in.pos.empty()) {
    if (smooth && !in.pos.empty()) {
      SLAM_MMS_LOG(kInfo) << reader.Describe()
                          << ": the input's own external POS is used as the smoothed POS";
    }
    StatusOr<OfflinePos> offline = ComputeOfflinePos(reader, options);
    if (!offline.ok()) {
      run.status = offline.status();
      return run;
    }
    options.origin = offline->origin;
    pos = std::move(offline->states);
    if (offline->smoothed) {
      run.smoothed_pos = true;
      run.smoothing_wall_s =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
  }
  StatusOr<std::unique_ptr<MappingSystem>> created = MappingSystem::Create(options);
  if (!created.ok()) {
    run.status = created.status();
    return run;
  }
  std::unique_ptr<MappingSystem> system = std::move(created).value();

  Status status;
  if (pos.empty() && in.initial_state) {
    status = system->InitializePos(*in.initial_state, in.initial_attitude_sigma_rpy_rad)
                 .WithContext(in.initial_state_source);
  }
  // An input's external POS replaces IMU + GNSS; a smoothed one comes with them (see the header).
  const bool imu_gnss = pos.empty() || run.smoothed_pos;
  const size_t n_imu = imu_gnss ? in.imu.size() : 0;
  const size_t n_gnss = imu_gnss ? in.gnss.size() : 0;
  const size_t n_pos = pos.size(), n_scan = run.scans_total;
  size_t i_imu = 0, i_gnss = 0, i_pos = 0, i_scan = 0;
  bool stopped = false;
  size_t results_seen = 0;  // for on_submap
  int submaps_started = 0;
  while (status.ok() && (i_imu < n_imu || i_gnss < n_gnss || i_pos < n_pos || i_scan < n_scan)) {
    constexpr int64_t kNever = std::numeric_limits<int64_t>::max();
    const int64_t t_imu = i_imu < n_imu ? in.imu[i_imu].stamp.nanoseconds() : kNever;
    const int64_t t_gnss = i_gnss < n_gnss ? in.gnss[i_gnss].stamp.nanoseconds() : kNever;
    const int64_t t_pos = i_pos < n_pos ? pos[i_pos].stamp.nanoseconds() : kNever;
    const int64_t t_scan = i_scan < n_scan ? reader.ScanEnd(i_scan).nanoseconds() : kNever;
    Next next = Next::kScan;
    if (t_imu <= t_gnss && t_imu <= t_pos && t_imu <= t_scan) {
      next = Next::kImu;
    } else if (t_gnss <= t_pos && t_gnss <= t_scan) {
      next = Next::kGnss;
    } else if (t_pos <= t_scan) {
      next = Next::kPos;
    }
    switch (next) {
      case Next::kImu:
        status = system->AddImu(in.imu[i_imu]);
        if (!status.ok()) status = status.WithContext(in.imu_source[i_imu]);
        ++i_imu;
        break;
      case Next::kGnss:
        status = system->AddGnss(in.gnss[i_gnss]);
        if (!status.ok()) status = status.WithContext(in.gnss_source[i_gnss]);
        ++i_gnss;
        break;
      case Next::kPos:
        status = system->AddInsPose(pos[i_pos]);
        if (!status.ok()) status = status.WithContext(in.pos_source[i_pos]);
        ++i_pos;
        break;
      case Next::kScan:
      case Next::kNone: {
        if (callbacks.stop != nullptr && callbacks.stop->load()) {
          stopped = true;
          break;
        }
        StatusOr<Scan> scan = reader.ReadScan(i_scan);
        if (!scan.ok()) {
          // One unreadable scan is not fatal: skip it, say which one.
          SLAM_MMS_LOG(kWarning) << "skipping scan " << reader.ScanSource(i_scan) << ": "
                                 << scan.status().ToString();
          run.skipped_scans.push_back(reader.ScanSource(i_scan) + ": " + scan.status().message());
          ++run.scans_unreadable;
        } else {
          if (!run.first_scan_start) run.first_scan_start = scan->stamp_start;
          const int skipped_before = system->num_skipped_scans();
          status = system->AddScan(*scan);
          if (!status.ok()) status = status.WithContext(scan->source);
          if (system->num_skipped_scans() > skipped_before) {
            run.skipped_scans.push_back(reader.ScanSource(i_scan) + ": no finite point");
          }
        }
        ++i_scan;
        if (callbacks.on_scan) callbacks.on_scan(i_scan, n_scan);
        if (callbacks.on_submap) {
          const std::vector<LocalizationResult>& results = system->results();
          for (; results_seen < results.size(); ++results_seen) {
            if (results[results_seen].new_submap && ++submaps_started > 1) {
              callbacks.on_submap(*system, submaps_started - 1);
            }
          }
        }
        break;
      }
    }
    if (stopped) break;
  }
  if (status.ok()) {
    status = system->Finish();
    run.finished = status.ok();
    if (run.finished && callbacks.on_finished) callbacks.on_finished(*system);
  }
  run.complete = run.finished && !stopped;
  run.status = status;
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  // What was computed, also after a fatal error (the current estimates).
  run.trajectory = system->FinalTrajectory();
  run.results = system->results();
  run.map = system->FinalMap(&run.map_stamps);
  if (StatusOr<GeodeticPoint> origin = system->Origin(); origin.ok()) run.origin = *origin;
  run.availability = system->GnssAvailability();
  run.scans_skipped_by_system = system->num_skipped_scans();
  run.scans_processed = run.trajectory.size();
  return run;
}

}  // namespace

DriveRun RunDrive(const DriveReader& reader, const MappingSystem::Options& base_options,
                  const DriveRunCallbacks& callbacks, const DriveRunOptions& run_options) {
  // What a run that stops before the method returns: its counts and the error.
  auto failed = [&](const Status& status) {
    DriveRun run;
    run.mode = base_options.mode;
    run.scans_total = reader.NumScans();
    run.status = status;
    return run;
  };
  if (const Status valid = run_options.Validate(); !valid.ok()) return failed(valid);
  if (!run_options.estimate_extrinsics) {
    return RunMethod(reader, base_options, callbacks, run_options);
  }
  // The boresight self-calibration first, then the method with its estimate (file comment).
  const auto t0 = std::chrono::steady_clock::now();
  StatusOr<ExtrinsicCalibration> calibration = CalibrateDriveExtrinsics(
      reader, base_options, run_options.extrinsic_calibration, callbacks.stop);
  if (!calibration.ok()) {
    return failed(calibration.status().WithContext("boresight self-calibration"));
  }
  DriveExtrinsics extrinsics;
  extrinsics.T_body_lidar = calibration->T_body_lidar_estimated;
  extrinsics.lidar_time_offset_s = calibration->time_offset_s;
  const std::unique_ptr<DriveReader> calibrated = OverrideExtrinsics(reader, extrinsics);
  MappingSystem::Options options = base_options;
  options.T_body_lidar = extrinsics.T_body_lidar;
  const double calibration_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  DriveRun run = RunMethod(*calibrated, options, callbacks, run_options);
  run.wall_s += calibration_s;
  run.extrinsic_calibration = std::move(calibration).value();
  return run;
}

}  // namespace slam_mms
