#include "slam_mms/pipeline/mapping_system.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <optional>
#include <string>
#include <thread>

#include "core/option_error.hpp"
#include "pipeline/mapping_system_impl.hpp"
#include "pipeline/scan_deskewer.hpp"
#include "slam_mms/core/lie.hpp"
#include "slam_mms/core/logging.hpp"
#include "slam_mms/core/voxel_downsample.hpp"
#include "slam_mms/ins/imu_preintegration.hpp"

namespace slam_mms {

void MappingSystem::Options::SetImuNoise(const ImuNoiseSpec& spec) {
  ins.SetImuNoise(spec);
  localizer.imu.SetImuNoise(spec);
}

Status MappingSystem::Options::Validate() const {
  if (!T_body_lidar.matrix().allFinite()) {
    return InvalidArgumentError("MappingSystem::Options::T_body_lidar is not finite");
  }
  const Eigen::Matrix3d R = T_body_lidar.linear();
  if ((R.transpose() * R - Eigen::Matrix3d::Identity()).norm() > 1e-6) {
    return InvalidArgumentError(
        "MappingSystem::Options::T_body_lidar has a rotation that is not orthonormal");
  }
  for (size_t i = 0; i < gnss_outages.size(); ++i) {
    const auto& [start, duration] = gnss_outages[i];
    if (!std::isfinite(start) || !(duration > 0.0)) {
      return InvalidArgumentError("MappingSystem::Options::gnss_outages[" + std::to_string(i) +
                                  "] = (" + std::to_string(start) + ", " +
                                  std::to_string(duration) +
                                  "); start must be finite and duration > 0");
    }
  }
  if (!(map_max_range_m > 0.0)) {
    return internal::OptionError("MappingSystem::Options", "map_max_range_m", map_max_range_m,
                                 "must be > 0");
  }
  if (!(map_voxel_m > 0.0)) {
    return internal::OptionError("MappingSystem::Options", "map_voxel_m", map_voxel_m,
                                 "must be > 0");
  }
  if (!(max_pos_jump_m > 0.0)) {
    return internal::OptionError("MappingSystem::Options", "max_pos_jump_m", max_pos_jump_m,
                                 "must be > 0");
  }
  if (!(max_pos_jump_rad > 0.0)) {
    return internal::OptionError("MappingSystem::Options", "max_pos_jump_rad", max_pos_jump_rad,
                                 "must be > 0");
  }
  if (!(vehicle_nhc_sigma_mps >= 0.0) || !std::isfinite(vehicle_nhc_sigma_mps)) {
    return internal::OptionError("MappingSystem::Options", "vehicle_nhc_sigma_mps",
                                 vehicle_nhc_sigma_mps, "must be >= 0 (0: never)");
  }
  if (num_threads < 1 || num_threads > 64) {
    return internal::OptionError("MappingSystem::Options", "num_threads", num_threads,
                                 "must be in [1, 64]");
  }
  if (mode == MappingMode::kGnssInsSmoothed) {
    return InvalidArgumentError(
        "MappingSystem::Options::mode = gnss_ins_smoothed; an offline method: RunDrive smooths the "
        "whole IMU/GNSS stream first (PosSmoother), or feed a smoothed POS with AddInsPose in "
        "gnss_ins mode");
  }
  SLAM_MMS_RETURN_IF_ERROR(ins.Validate());
  if (mode != MappingMode::kGnssIns) {
    SLAM_MMS_RETURN_IF_ERROR(localizer.Validate());
    SLAM_MMS_RETURN_IF_ERROR(level2.Validate());
  }
  return OkStatus();
}

MappingSystem::MappingSystem(const Options& options) : impl_(std::make_unique<Impl>()) {
  impl_->opt = options;
}
MappingSystem::~MappingSystem() = default;

StatusOr<std::unique_ptr<MappingSystem>> MappingSystem::Create(const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  std::unique_ptr<MappingSystem> sys(new MappingSystem(options));
  Impl& m = *sys->impl_;
  SLAM_MMS_ASSIGN_OR_RETURN(m.ins, InsFilter::Create(options.ins));
  if (options.origin) {
    SLAM_MMS_RETURN_IF_ERROR(m.ins.mutable_gnss_prior().SetOrigin(*options.origin));
  }
  ScanDeskewer::Options dopt;
  static_cast<DeskewOptions&>(dopt) = options.localizer.deskew;
  dopt.num_threads = options.num_threads;
  SLAM_MMS_ASSIGN_OR_RETURN(ScanDeskewer deskewer, ScanDeskewer::Create(dopt));
  m.motion_builder = internal::MotionInputBuilder(options.max_pos_jump_m, options.max_pos_jump_rad);
  m.pos_mapper = internal::PosMapper(std::move(deskewer), options.T_body_lidar, options.map_voxel_m,
                                     options.map_max_range_m);
  if (options.mode != MappingMode::kGnssIns) {
    Localizer::Options lopt;
    static_cast<Level1Options&>(lopt) = options.localizer;
    lopt.mode = options.mode;
    lopt.map_voxel_m = options.map_voxel_m;
    lopt.map_max_range_m = options.map_max_range_m;
    lopt.num_threads = options.num_threads;
    SLAM_MMS_ASSIGN_OR_RETURN(m.loc, Localizer::Create(lopt, options.T_body_lidar));
    SubmapManager::Options l2 = options.level2;
    if (options.mode == MappingMode::kLidarOnly) l2.use_gnss = false;
    if (l2.enabled) {
      SLAM_MMS_ASSIGN_OR_RETURN(m.level2, SubmapManager::Create(l2, options.num_threads));
    }
  }
  return sys;
}

Status MappingSystem::AddImu(const ImuSample& sample) {
  Impl& m = *impl_;
  if (m.finished) return FailedPreconditionError("MappingSystem::AddImu after Finish()");
  if (!sample.accel_mps2.allFinite() || !sample.gyro_radps.allFinite()) {
    return InvalidArgumentError("MappingSystem::AddImu: non-finite sample at " +
                                sample.stamp.ToKittiString());
  }
  SLAM_MMS_RETURN_IF_ERROR(m.input.AcceptImuTime(sample.stamp));
  if (!m.have_first_scan) {
    m.input.HoldImu(sample);
    return OkStatus();
  }
  SLAM_MMS_RETURN_IF_ERROR(m.FeedImu(sample));
  return m.ProcessQueued();
}

Status MappingSystem::AddGnss(const GnssFix& fix) {
  Impl& m = *impl_;
  if (m.finished) return FailedPreconditionError("MappingSystem::AddGnss after Finish()");
  SLAM_MMS_RETURN_IF_ERROR(m.input.AcceptGnssTime(fix.stamp));
  if (!m.have_first_scan) {
    m.input.HoldGnss(fix);
    return OkStatus();
  }
  SLAM_MMS_RETURN_IF_ERROR(m.FeedGnss(fix));
  return m.ProcessQueued();
}

Status MappingSystem::InitializePos(const InsState& state,
                                    const std::optional<Eigen::Vector3d>& sigma_rpy_rad) {
  Impl& m = *impl_;
  if (!state.T_world_body.matrix().allFinite() || !state.v_world_mps.allFinite()) {
    return InvalidArgumentError("MappingSystem::InitializePos: non-finite state");
  }
  // The stamp lets the IMU carry the attitude to the first usable fix (which may come later).
  return m.ins.InitializeAttitude(Eigen::Quaterniond(state.T_world_body.linear()),
                                  state.v_world_mps, state.stamp, sigma_rpy_rad);
}

Status MappingSystem::AddInsPose(const InsState& state) {
  Impl& m = *impl_;
  m.external_pos = true;
  SLAM_MMS_RETURN_IF_ERROR(m.ins.AddExternalPose(state));
  m.input.MarkPosInput(state.stamp);
  if (!m.have_first_scan) return OkStatus();
  return m.ProcessQueued();
}

Status MappingSystem::AddScan(const Scan& scan) {
  Impl& m = *impl_;
  if (m.finished) return FailedPreconditionError("MappingSystem::AddScan after Finish()");
  if (const auto why = m.input.ScanRejection(scan, m.have_scan, m.last_scan_start)) {
    ++m.skipped;
    SLAM_MMS_LOG(kWarning) << "scan '" << scan.source << "' (index " << scan.index
                           << ") skipped: " << *why;
    return OkStatus();
  }
  if (!m.have_first_scan) {
    m.have_first_scan = true;
    m.ins.mutable_gnss_prior().SetReferenceTime(scan.stamp_start);
    for (const auto& [start, duration] : m.opt.gnss_outages) {
      SLAM_MMS_RETURN_IF_ERROR(m.ins.mutable_gnss_prior().AddOutageWindow(start, duration));
    }
    SLAM_MMS_RETURN_IF_ERROR(m.FlushPending());
  }
  m.input.scans().push_back(scan);
  return m.ProcessQueued();
}

Status MappingSystem::Finish() {
  Impl& m = *impl_;
  if (m.finished) return OkStatus();
  if (!m.have_first_scan) SLAM_MMS_RETURN_IF_ERROR(m.FlushPending());
  m.finished = true;
  SLAM_MMS_RETURN_IF_ERROR(m.ProcessQueued());
  if (m.loc) {
    m.loc->FinishCurrentSubmap();
    SLAM_MMS_RETURN_IF_ERROR(m.ReportFinishedSubmaps());
    if (m.level2) {
      SLAM_MMS_ASSIGN_OR_RETURN(const std::vector<SubmapPoseUpdate> updates,
                                m.level2->Finish(*m.loc));
      SLAM_MMS_RETURN_IF_ERROR(m.ApplyLevel2(updates));
    }
  }
  return OkStatus();
}

const std::vector<LocalizationResult>& MappingSystem::results() const { return impl_->results; }

void MappingSystem::SetResultCallback(std::function<void(const LocalizationResult&)> callback) {
  impl_->callback = std::move(callback);
}

std::vector<Surfel> MappingSystem::SurfelMapSnapshot() const {
  if (!impl_->loc) return {};
  return impl_->loc->AllSurfels();
}

StatusOr<GeodeticPoint> MappingSystem::Origin() const {
  const GnssPrior& prior = impl_->ins.gnss_prior();
  if (!prior.has_origin()) {
    return FailedPreconditionError(
        "MappingSystem::Origin: no valid GNSS fix yet and no origin set");
  }
  return prior.origin();
}

std::vector<GnssAvailabilityInterval> MappingSystem::GnssAvailability() const {
  return impl_->ins.gnss_prior().AvailabilityIntervals();
}

int MappingSystem::num_pos_jumps() const { return impl_->motion_builder.num_pos_jumps(); }
int MappingSystem::num_skipped_scans() const { return impl_->skipped; }

Level2Stats MappingSystem::level2_stats() const {
  return impl_->level2 ? impl_->level2->stats() : Level2Stats{};
}

const MappingSystem::Options& MappingSystem::options() const { return impl_->opt; }

}  // namespace slam_mms
