#include "slam_mms/ins/gnss_prior.hpp"

#include <GeographicLib/LocalCartesian.hpp>
#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>

#include "core/option_error.hpp"
#include "slam_mms/core/logging.hpp"

namespace slam_mms {

const char* GnssDecisionName(GnssDecision decision) {
  switch (decision) {
    case GnssDecision::kUse: return "use";
    case GnssDecision::kDownWeight: return "down-weight";
    case GnssDecision::kReject: return "reject";
    case GnssDecision::kWithheld: return "withheld";
  }
  return "unknown";
}

const char* GnssAvailabilityName(GnssAvailability availability) {
  switch (availability) {
    case GnssAvailability::kValid: return "valid";
    case GnssAvailability::kDegraded: return "degraded";
    case GnssAvailability::kOutage: return "outage";
  }
  return "unknown";
}

namespace {
bool PositiveFinite(double x) { return std::isfinite(x) && x > 0.0; }

Status FieldError(const char* field, double value, const char* rule) {
  return internal::OptionError("GnssPrior::Options", field, value, rule);
}

struct FixRecord {
  Timestamp stamp;
  GnssDecision decision;
};
}  // namespace

Status GnssPrior::Options::Validate() const {
  if (!t_body_antenna.allFinite())
    return InvalidArgumentError("GnssPrior::Options::t_body_antenna is not finite");
  if (!PositiveFinite(sigma_floor_horizontal_m))
    return FieldError("sigma_floor_horizontal_m", sigma_floor_horizontal_m, "must be > 0");
  if (!PositiveFinite(sigma_floor_vertical_m))
    return FieldError("sigma_floor_vertical_m", sigma_floor_vertical_m, "must be > 0");
  if (!(max_sigma_horizontal_m >= sigma_floor_horizontal_m) ||
      !std::isfinite(max_sigma_horizontal_m))
    return FieldError("max_sigma_horizontal_m", max_sigma_horizontal_m,
                      "must be finite and >= sigma_floor_horizontal_m");
  if (!(downweight_variance_factor >= 1.0) || !std::isfinite(downweight_variance_factor))
    return FieldError("downweight_variance_factor", downweight_variance_factor, "must be >= 1");
  if (!PositiveFinite(innovation_downweight_chi2))
    return FieldError("innovation_downweight_chi2", innovation_downweight_chi2, "must be > 0");
  if (!(innovation_reject_chi2 >= innovation_downweight_chi2) ||
      !std::isfinite(innovation_reject_chi2))
    return FieldError("innovation_reject_chi2", innovation_reject_chi2,
                      "must be finite and >= innovation_downweight_chi2");
  if (!PositiveFinite(max_rejection_streak_s))
    return FieldError("max_rejection_streak_s", max_rejection_streak_s, "must be > 0");
  if (!PositiveFinite(max_speed_mps))
    return FieldError("max_speed_mps", max_speed_mps, "must be > 0");
  if (!PositiveFinite(outage_timeout_s))
    return FieldError("outage_timeout_s", outage_timeout_s, "must be > 0");
  if (min_fix_type == GnssFixType::kNone)
    return InvalidArgumentError("GnssPrior::Options::min_fix_type = none; must be at least single");
  return OkStatus();
}

struct GnssPrior::Impl {
  Options options;
  std::optional<GeographicLib::LocalCartesian> proj;
  GeodeticPoint origin;
  std::optional<Timestamp> reference_time;
  std::vector<std::pair<double, double>> outage_windows_s;  // [start, end) relative to reference
  std::vector<FixRecord> history;
  std::optional<GnssMeasurement> last_used;
  std::optional<Timestamp> rejection_streak_start;
  int num_used = 0, num_downweighted = 0, num_rejected = 0, num_withheld = 0;

  void Record(Timestamp t, GnssDecision d) {
    history.push_back({t, d});
    switch (d) {
      case GnssDecision::kUse: ++num_used; break;
      case GnssDecision::kDownWeight: ++num_downweighted; break;
      case GnssDecision::kReject: ++num_rejected; break;
      case GnssDecision::kWithheld: ++num_withheld; break;
    }
  }
};

GnssPrior::GnssPrior() : GnssPrior(Options()) {}
GnssPrior::GnssPrior(const Options& options) : impl_(std::make_unique<Impl>()) {
  impl_->options = options;
}
GnssPrior::~GnssPrior() = default;
GnssPrior::GnssPrior(GnssPrior&&) noexcept = default;
GnssPrior& GnssPrior::operator=(GnssPrior&&) noexcept = default;

StatusOr<GnssPrior> GnssPrior::Create(const Options& options) {
  SLAM_MMS_RETURN_IF_ERROR(options.Validate());
  return GnssPrior(options);
}

const GnssPrior::Options& GnssPrior::options() const { return impl_->options; }

Status GnssPrior::SetOrigin(const GeodeticPoint& o) {
  if (impl_->proj)
    return FailedPreconditionError("GnssPrior::SetOrigin: the origin is already set");
  if (!std::isfinite(o.latitude_deg) || std::abs(o.latitude_deg) > 90.0 ||
      !std::isfinite(o.longitude_deg) || std::abs(o.longitude_deg) > 180.0 ||
      !std::isfinite(o.height_m)) {
    return InvalidArgumentError("GnssPrior::SetOrigin: latitude/longitude/height out of range");
  }
  impl_->proj.emplace(o.latitude_deg, o.longitude_deg, o.height_m);
  impl_->origin = o;
  return OkStatus();
}

bool GnssPrior::has_origin() const { return impl_->proj.has_value(); }
GeodeticPoint GnssPrior::origin() const { return impl_->origin; }

StatusOr<Eigen::Vector3d> GnssPrior::ToWorld(const GeodeticPoint& p) const {
  if (!impl_->proj) return FailedPreconditionError("GnssPrior::ToWorld: no origin yet");
  Eigen::Vector3d e;
  impl_->proj->Forward(p.latitude_deg, p.longitude_deg, p.height_m, e.x(), e.y(), e.z());
  return e;
}

StatusOr<GeodeticPoint> GnssPrior::ToGeodetic(const Eigen::Vector3d& p_world) const {
  if (!impl_->proj) return FailedPreconditionError("GnssPrior::ToGeodetic: no origin yet");
  GeodeticPoint g;
  impl_->proj->Reverse(p_world.x(), p_world.y(), p_world.z(), g.latitude_deg, g.longitude_deg,
                       g.height_m);
  return g;
}

void GnssPrior::SetReferenceTime(Timestamp t0) { impl_->reference_time = t0; }

Status GnssPrior::AddOutageWindow(double start_s, double duration_s) {
  if (!std::isfinite(start_s) || !PositiveFinite(duration_s)) {
    return InvalidArgumentError(
        "GnssPrior::AddOutageWindow: start_s must be finite and duration_s > 0");
  }
  impl_->outage_windows_s.emplace_back(start_s, start_s + duration_s);
  return OkStatus();
}

bool GnssPrior::IsWithheld(Timestamp t) const {
  if (!impl_->reference_time) return false;
  const double s = t.SecondsSince(*impl_->reference_time);
  for (const auto& [a, b] : impl_->outage_windows_s) {
    if (s >= a && s < b) return true;
  }
  return false;
}

StatusOr<GnssMeasurement> GnssPrior::ToMeasurement(const GnssFix& fix) {
  if (!std::isfinite(fix.latitude_deg) || !std::isfinite(fix.longitude_deg) ||
      !std::isfinite(fix.height_m) || std::abs(fix.latitude_deg) > 90.0 ||
      std::abs(fix.longitude_deg) > 180.0) {
    return InvalidArgumentError("GnssPrior: fix with invalid latitude/longitude/height");
  }
  if (!std::isfinite(fix.sigma_horizontal_m) || !std::isfinite(fix.sigma_vertical_m)) {
    return InvalidArgumentError("GnssPrior: fix with non-finite sigma");
  }
  if (!impl_->proj) {
    if (fix.type == GnssFixType::kNone) {
      return FailedPreconditionError("GnssPrior: no origin yet and this fix is invalid");
    }
    SLAM_MMS_RETURN_IF_ERROR(SetOrigin({fix.latitude_deg, fix.longitude_deg, fix.height_m}));
  }
  GnssMeasurement m;
  m.stamp = fix.stamp;
  m.type = fix.type;
  SLAM_MMS_ASSIGN_OR_RETURN(m.p_world_antenna,
                            ToWorld({fix.latitude_deg, fix.longitude_deg, fix.height_m}));
  const double sh = std::max(fix.sigma_horizontal_m, impl_->options.sigma_floor_horizontal_m);
  const double sv = std::max(fix.sigma_vertical_m, impl_->options.sigma_floor_vertical_m);
  m.cov_world_antenna = Eigen::Vector3d(sh * sh, sh * sh, sv * sv).asDiagonal();
  return m;
}

StatusOr<GnssDecisionResult> GnssPrior::Process(const GnssFix& fix,
                                                const GnssPrediction* prediction) {
  Impl& im = *impl_;
  const Options& o = im.options;
  if (!im.history.empty() && fix.stamp < im.history.back().stamp) {
    return InvalidArgumentError("GnssPrior::Process: fixes must come in time order");
  }
  if (!im.reference_time) im.reference_time = fix.stamp;
  GnssDecisionResult result;
  auto finish = [&](GnssDecision d, std::string reason) {
    result.decision = d;
    result.reason = std::move(reason);
    im.Record(fix.stamp, d);
    return result;
  };
  if (IsWithheld(fix.stamp))
    return finish(GnssDecision::kWithheld, "inside an injected outage window");
  if (fix.type < o.min_fix_type) {
    return finish(GnssDecision::kReject,
                  std::string("fix type ") + GnssFixTypeName(fix.type) + " below min_fix_type");
  }
  if (!(fix.sigma_horizontal_m <= o.max_sigma_horizontal_m)) {
    return finish(GnssDecision::kReject, "reported sigma above max_sigma_horizontal_m");
  }
  auto meas_or = ToMeasurement(fix);
  if (!meas_or.ok()) return finish(GnssDecision::kReject, meas_or.status().message());
  result.measurement = *meas_or;
  GnssMeasurement& m = result.measurement;

  double weight = 1.0;
  std::string reason;
  if (prediction != nullptr) {
    result.innovation_m = m.p_world_antenna - prediction->p_world_antenna;
    const Eigen::Matrix3d S = prediction->cov_world_antenna + m.cov_world_antenna;
    result.innovation_chi2 = result.innovation_m.dot(S.ldlt().solve(result.innovation_m));
    if (!std::isfinite(result.innovation_chi2)) {
      return finish(GnssDecision::kReject, "innovation covariance not usable");
    }
    if (result.innovation_chi2 > o.innovation_reject_chi2) {
      if (!im.rejection_streak_start) im.rejection_streak_start = fix.stamp;
      const double streak_s = fix.stamp.SecondsSince(*im.rejection_streak_start);
      if (streak_s < o.max_rejection_streak_s) {
        std::ostringstream s;
        s << "innovation " << result.innovation_m.norm() << " m, chi2 " << result.innovation_chi2
          << " > " << o.innovation_reject_chi2;
        return finish(GnssDecision::kReject, s.str());
      }
      SLAM_MMS_LOG(kWarning) << "GnssPrior: every fix rejected for " << streak_s
                             << " s; re-acquiring with a fix " << result.innovation_m.norm()
                             << " m away from the estimate";
      reason = "re-acquired after a rejection streak";
    } else if (result.innovation_chi2 > o.innovation_downweight_chi2) {
      weight = result.innovation_chi2 / o.innovation_downweight_chi2;
      reason = "innovation chi2 above innovation_downweight_chi2";
    }
  } else if (im.last_used) {
    const double dt = std::abs(fix.stamp.SecondsSince(im.last_used->stamp));
    const double jump = (m.p_world_antenna - im.last_used->p_world_antenna).norm();
    const double sigma =
        std::sqrt(m.cov_world_antenna.trace() + im.last_used->cov_world_antenna.trace());
    if (jump > o.max_speed_mps * dt + 3.0 * sigma) {
      std::ostringstream s;
      s << "jump of " << jump << " m in " << dt << " s from the last used fix";
      return finish(GnssDecision::kReject, s.str());
    }
  }
  im.rejection_streak_start.reset();
  result.innovation_weight = weight;
  if (fix.type < o.full_weight_fix_type) {
    weight *= o.downweight_variance_factor;
    if (reason.empty()) reason = std::string("fix type ") + GnssFixTypeName(fix.type);
  }
  m.cov_world_antenna *= weight;
  im.last_used = m;
  return finish(weight > 1.0 ? GnssDecision::kDownWeight : GnssDecision::kUse, reason);
}

GnssAvailability GnssPrior::AvailabilityAt(Timestamp t) const {
  const auto& h = impl_->history;
  // Last usable record at or before t.
  auto it = std::upper_bound(h.begin(), h.end(), t,
                             [](Timestamp a, const FixRecord& r) { return a < r.stamp; });
  while (it != h.begin()) {
    --it;
    if (it->decision == GnssDecision::kUse || it->decision == GnssDecision::kDownWeight) {
      if (t.SecondsSince(it->stamp) > impl_->options.outage_timeout_s)
        return GnssAvailability::kOutage;
      return it->decision == GnssDecision::kUse ? GnssAvailability::kValid
                                                : GnssAvailability::kDegraded;
    }
    if (t.SecondsSince(it->stamp) > impl_->options.outage_timeout_s) break;
  }
  return GnssAvailability::kOutage;
}

std::vector<GnssAvailabilityInterval> GnssPrior::AvailabilityIntervals() const {
  std::vector<GnssAvailabilityInterval> out;
  const auto& h = impl_->history;
  if (h.empty()) return out;
  // Availability only changes at a record or outage_timeout_s after a usable record.
  std::vector<Timestamp> events;
  const double timeout = impl_->options.outage_timeout_s;
  for (const FixRecord& r : h) {
    events.push_back(r.stamp);
    if (r.decision == GnssDecision::kUse || r.decision == GnssDecision::kDownWeight) {
      events.push_back(r.stamp.PlusSeconds(timeout + 1e-9));
    }
  }
  std::sort(events.begin(), events.end());
  events.erase(std::unique(events.begin(), events.end()), events.end());
  const Timestamp end = h.back().stamp.PlusSeconds(timeout);
  for (const Timestamp& t : events) {
    if (t >= end) break;
    const GnssAvailability a = AvailabilityAt(t);
    if (!out.empty() && out.back().availability == a) continue;
    if (!out.empty()) out.back().end = t;
    out.push_back({t, end, a});
  }
  return out;
}

int GnssPrior::num_used() const { return impl_->num_used; }
int GnssPrior::num_downweighted() const { return impl_->num_downweighted; }
int GnssPrior::num_rejected() const { return impl_->num_rejected; }
int GnssPrior::num_withheld() const { return impl_->num_withheld; }

}  // namespace slam_mms
