#include "rosbag/point_cloud2_codec.hpp"

#include <sensor_msgs/PointField.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "io/parsers.hpp"

namespace slam_mms::rosbag_internal {
namespace {

using sensor_msgs::PointField;

// Per-point times further than this from header.stamp are a wrong convention or unit.
constexpr double kMaxTimeFromStamp_s = 10.0;
// kAuto: a first time above this is absolute (seconds since the epoch: 1e6 s is 1970-01-12).
constexpr double kAbsoluteThreshold_s = 1e6;

size_t DatatypeSize(uint8_t datatype) {
  switch (datatype) {
    case PointField::INT8:
    case PointField::UINT8: return 1;
    case PointField::INT16:
    case PointField::UINT16: return 2;
    case PointField::INT32:
    case PointField::UINT32:
    case PointField::FLOAT32: return 4;
    case PointField::FLOAT64: return 8;
    default: return 0;
  }
}

bool IsInteger(uint8_t datatype) {
  return datatype != PointField::FLOAT32 && datatype != PointField::FLOAT64;
}

template <typename T>
T Load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}

// The value of a field of any datatype (little endian host, checked by ParseCloudLayout).
double ReadNumber(const uint8_t* p, uint8_t datatype) {
  switch (datatype) {
    case PointField::INT8: return Load<int8_t>(p);
    case PointField::UINT8: return Load<uint8_t>(p);
    case PointField::INT16: return Load<int16_t>(p);
    case PointField::UINT16: return Load<uint16_t>(p);
    case PointField::INT32: return Load<int32_t>(p);
    case PointField::UINT32: return Load<uint32_t>(p);
    case PointField::FLOAT32: return Load<float>(p);
    case PointField::FLOAT64: return Load<double>(p);
    default: return std::numeric_limits<double>::quiet_NaN();
  }
}

float ReadCoordinate(const uint8_t* p, uint8_t datatype) {
  return datatype == PointField::FLOAT32 ? Load<float>(p) : static_cast<float>(Load<double>(p));
}

// Seconds: float fields are seconds, integer fields nanoseconds.
double ReadTimeSeconds(const uint8_t* p, const FieldRef& f) {
  const double v = ReadNumber(p + f.offset, f.datatype);
  return IsInteger(f.datatype) ? v * 1e-9 : v;
}

const char* DatatypeName(uint8_t datatype) {
  switch (datatype) {
    case PointField::INT8: return "int8";
    case PointField::UINT8: return "uint8";
    case PointField::INT16: return "int16";
    case PointField::UINT16: return "uint16";
    case PointField::INT32: return "int32";
    case PointField::UINT32: return "uint32";
    case PointField::FLOAT32: return "float32";
    case PointField::FLOAT64: return "float64";
    default: return "unknown";
  }
}

// Visits every point's bytes in row-major order.
template <typename F>
void ForEachPoint(const sensor_msgs::PointCloud2& msg, F&& f) {
  const uint8_t* data = msg.data.data();
  for (uint32_t r = 0; r < msg.height; ++r) {
    const uint8_t* row = data + static_cast<size_t>(r) * msg.row_step;
    for (uint32_t c = 0; c < msg.width; ++c) f(row + static_cast<size_t>(c) * msg.point_step);
  }
}

// header.stamp split so that an absolute time t [s] becomes (t - sec) - nsec 1e-9 without
// losing the fraction to 1.7e9 s of magnitude.
struct HeaderSeconds {
  double sec, nsec_s;
};

HeaderSeconds SplitStamp(const sensor_msgs::PointCloud2& msg) {
  return {static_cast<double>(msg.header.stamp.sec), msg.header.stamp.nsec * 1e-9};
}

// Whether the cloud's times are absolute under `convention`: kAuto looks at the first finite one.
bool TimesAreAbsolute(const sensor_msgs::PointCloud2& msg, const FieldRef& time,
                      RosbagDriveReader::TimeField convention) {
  if (convention != RosbagDriveReader::TimeField::kAuto) {
    return convention == RosbagDriveReader::TimeField::kAbsolute;
  }
  const uint8_t* data = msg.data.data();
  for (uint32_t r = 0; r < msg.height; ++r) {
    for (uint32_t c = 0; c < msg.width; ++c) {
      const double t = ReadTimeSeconds(
          data + static_cast<size_t>(r) * msg.row_step + static_cast<size_t>(c) * msg.point_step,
          time);
      if (std::isfinite(t)) return std::abs(t) > kAbsoluteThreshold_s;
    }
  }
  return false;
}

}  // namespace

StatusOr<CloudLayout> ParseCloudLayout(const sensor_msgs::PointCloud2& msg,
                                       const std::string& source) {
  if (msg.is_bigendian) {
    return DataLossError(source + ": is_bigendian = true: big-endian PointCloud2 is not supported");
  }
  CloudLayout layout;
  // Name -> slot, by priority (the first listed name wins where a cloud has several).
  struct Want {
    FieldRef* slot;
    std::vector<const char*> names;
  };
  const Want wants[] = {{&layout.x, {"x"}},
                        {&layout.y, {"y"}},
                        {&layout.z, {"z"}},
                        {&layout.intensity, {"intensity", "i", "reflectance"}},
                        {&layout.time, {"time", "t", "timestamp"}}};
  for (const Want& w : wants) {
    for (const char* name : w.names) {
      const auto it = std::find_if(msg.fields.begin(), msg.fields.end(),
                                   [&](const PointField& f) { return f.name == name; });
      if (it == msg.fields.end()) continue;
      const size_t size = DatatypeSize(it->datatype);
      if (size == 0) {
        return DataLossError(source + ": field '" + it->name + "' has unknown datatype " +
                             std::to_string(it->datatype));
      }
      if (it->count < 1) {
        return DataLossError(source + ": field '" + it->name + "' has count 0");
      }
      if (static_cast<uint64_t>(it->offset) + size > msg.point_step) {
        return DataLossError(source + ": field '" + it->name + "' (offset " +
                             std::to_string(it->offset) + ", " + DatatypeName(it->datatype) +
                             ") lies outside point_step " + std::to_string(msg.point_step));
      }
      w.slot->name = it->name;
      w.slot->offset = it->offset;
      w.slot->datatype = it->datatype;
      break;
    }
  }
  const char* xyz_names[] = {"x", "y", "z"};
  const FieldRef* xyz[] = {&layout.x, &layout.y, &layout.z};
  for (int k = 0; k < 3; ++k) {
    if (!xyz[k]->present()) {
      std::string have;
      for (const PointField& f : msg.fields) have += (have.empty() ? "" : " ") + f.name;
      return DataLossError(source + ": no field '" + xyz_names[k] + "' (fields: " + have + ")");
    }
    if (xyz[k]->datatype != PointField::FLOAT32 && xyz[k]->datatype != PointField::FLOAT64) {
      return DataLossError(source + ": field '" + xyz_names[k] + "' is " +
                           DatatypeName(xyz[k]->datatype) + "; float32 or float64 required");
    }
  }
  return layout;
}

Status CheckCloudSize(const sensor_msgs::PointCloud2& msg, const std::string& source) {
  if (msg.width > 0 && msg.height > 0) {
    if (msg.point_step == 0) return DataLossError(source + ": field point_step is 0");
    const uint64_t min_row = static_cast<uint64_t>(msg.width) * msg.point_step;
    if (msg.row_step < min_row) {
      return DataLossError(source + ": field row_step " + std::to_string(msg.row_step) +
                           " < width " + std::to_string(msg.width) + " x point_step " +
                           std::to_string(msg.point_step));
    }
  }
  const uint64_t expected = static_cast<uint64_t>(msg.row_step) * msg.height;
  if (msg.data.size() != expected) {
    return DataLossError(source + ": field data has " + std::to_string(msg.data.size()) +
                         " bytes, row_step " + std::to_string(msg.row_step) + " x height " +
                         std::to_string(msg.height) + " = " + std::to_string(expected) +
                         (msg.data.size() < expected ? " (truncated)" : ""));
  }
  return OkStatus();
}

StatusOr<CloudTimeRange> ComputeCloudTimeRange(const sensor_msgs::PointCloud2& msg,
                                               const CloudLayout& layout,
                                               RosbagDriveReader::TimeField convention,
                                               const std::string& source) {
  CloudTimeRange range;
  range.absolute = TimesAreAbsolute(msg, layout.time, convention);
  const HeaderSeconds h = SplitStamp(msg);
  double lo = std::numeric_limits<double>::infinity();
  double hi = -lo;
  ForEachPoint(msg, [&](const uint8_t* p) {
    double t = ReadTimeSeconds(p, layout.time);
    if (range.absolute) t = (t - h.sec) - h.nsec_s;
    if (std::isfinite(t)) {
      lo = std::min(lo, t);
      hi = std::max(hi, t);
    }
  });
  if (lo > hi) return range;  // no finite time
  if (lo < -kMaxTimeFromStamp_s || hi > kMaxTimeFromStamp_s) {
    return DataLossError(
        source + ": field '" + layout.time.name + "' gives times from " + std::to_string(lo) +
        " to " + std::to_string(hi) + " s relative to header.stamp (read as " +
        (range.absolute ? "absolute" : "relative") + ", " +
        (IsInteger(layout.time.datatype) ? "ns" : "s") + "); check Options::time_field");
  }
  range.min_s = lo;
  range.max_s = hi;
  return range;
}

size_t DecodeCloud(const sensor_msgs::PointCloud2& msg, const CloudLayout& layout,
                   const DecodeParams& params, PointCloud* cloud) {
  const size_t n = static_cast<size_t>(msg.width) * msg.height;
  cloud->clear();
  if (!layout.time.present()) {
    // As a KITTI scan: x y z reflectance quadruples, then the azimuth time.
    std::vector<float> xyzr(4 * n);
    size_t k = 0;
    ForEachPoint(msg, [&](const uint8_t* p) {
      xyzr[k++] = ReadCoordinate(p + layout.x.offset, layout.x.datatype);
      xyzr[k++] = ReadCoordinate(p + layout.y.offset, layout.y.datatype);
      xyzr[k++] = ReadCoordinate(p + layout.z.offset, layout.z.datatype);
      xyzr[k++] = layout.intensity.present()
                      ? static_cast<float>(
                            ReadNumber(p + layout.intensity.offset, layout.intensity.datatype))
                      : 0.0f;
    });
    KittiRawReader::Options kitti;
    kitti.spin = params.spin;
    kitti.per_point_time = params.per_point_time;
    kitti.vertical_angle_correction = false;
    return io_internal::KittiPointsToCloud(xyzr, kitti, params.duration_s, cloud);
  }
  const bool absolute = TimesAreAbsolute(msg, layout.time, params.time_field);
  const HeaderSeconds h = SplitStamp(msg);
  cloud->resize(n);
  auto& pts = cloud->points();
  auto& intensity = cloud->intensities();
  auto& time = cloud->time_offsets_s();
  size_t kept = 0;
  ForEachPoint(msg, [&](const uint8_t* p) {
    const Eigen::Vector3f q(ReadCoordinate(p + layout.x.offset, layout.x.datatype),
                            ReadCoordinate(p + layout.y.offset, layout.y.datatype),
                            ReadCoordinate(p + layout.z.offset, layout.z.datatype));
    const float i =
        layout.intensity.present()
            ? static_cast<float>(ReadNumber(p + layout.intensity.offset, layout.intensity.datatype))
            : 0.0f;
    double t = ReadTimeSeconds(p, layout.time);
    if (absolute) t = (t - h.sec) - h.nsec_s;
    const auto dt = static_cast<float>(t - params.start_from_header_s);
    if (!q.allFinite() || !std::isfinite(i) || !std::isfinite(dt)) return;
    pts[kept] = q;
    intensity[kept] = i;
    time[kept] = std::max(0.0f, dt);
    ++kept;
  });
  cloud->resize(kept);
  return n - kept;
}

void EncodeCloud(const PointCloud& cloud, bool with_time, sensor_msgs::PointCloud2* msg) {
  const char* names[] = {"x", "y", "z", "intensity", "time"};
  const int num_fields = with_time ? 5 : 4;
  msg->fields.resize(num_fields);
  for (int k = 0; k < num_fields; ++k) {
    msg->fields[k].name = names[k];
    msg->fields[k].offset = 4 * k;
    msg->fields[k].datatype = PointField::FLOAT32;
    msg->fields[k].count = 1;
  }
  const size_t n = cloud.size();
  msg->height = 1;
  msg->width = static_cast<uint32_t>(n);
  msg->is_bigendian = false;
  msg->is_dense = true;
  msg->point_step = 4 * num_fields;
  msg->row_step = msg->point_step * msg->width;
  msg->data.resize(static_cast<size_t>(msg->row_step));
  uint8_t* out = msg->data.data();
  for (size_t k = 0; k < n; ++k) {
    float v[5] = {cloud.points()[k].x(), cloud.points()[k].y(), cloud.points()[k].z(),
                  cloud.intensities()[k], cloud.time_offsets_s()[k]};
    std::memcpy(out + k * msg->point_step, v, msg->point_step);
  }
}

}  // namespace slam_mms::rosbag_internal
