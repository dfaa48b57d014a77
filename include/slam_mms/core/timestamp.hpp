#pragma once
// Timestamp: integer nanoseconds since the Unix epoch in a strong type. Durations are plain
// double seconds (SI) where arithmetic needs them, int64 nanoseconds where exactness matters.
//
// Thread safety: value type.

#include <cstdint>
#include <string>

namespace slam_mms {

class Timestamp {
 public:
  constexpr Timestamp() = default;
  static constexpr Timestamp FromNanoseconds(int64_t ns) { return Timestamp(ns); }
  /// Rounds to the nearest nanosecond.
  static Timestamp FromSeconds(double seconds);

  constexpr int64_t nanoseconds() const { return ns_; }
  /// Seconds since the epoch as double (about 0.2 us resolution in 2011: use differences instead).
  double seconds() const { return static_cast<double>(ns_) * 1e-9; }

  /// (*this - other) in seconds, exact to double precision of the difference.
  double SecondsSince(Timestamp other) const { return static_cast<double>(ns_ - other.ns_) * 1e-9; }
  /// This time shifted by `dt` seconds.
  Timestamp PlusSeconds(double dt) const;

  /// "2011-09-26 13:02:25.964389445" (UTC), the KITTI timestamp format.
  std::string ToKittiString() const;

  friend constexpr bool operator==(Timestamp a, Timestamp b) { return a.ns_ == b.ns_; }
  friend constexpr bool operator!=(Timestamp a, Timestamp b) { return a.ns_ != b.ns_; }
  friend constexpr bool operator<(Timestamp a, Timestamp b) { return a.ns_ < b.ns_; }
  friend constexpr bool operator<=(Timestamp a, Timestamp b) { return a.ns_ <= b.ns_; }
  friend constexpr bool operator>(Timestamp a, Timestamp b) { return a.ns_ > b.ns_; }
  friend constexpr bool operator>=(Timestamp a, Timestamp b) { return a.ns_ >= b.ns_; }

 private:
  explicit constexpr Timestamp(int64_t ns) : ns_(ns) {}
  int64_t ns_ = 0;
};

}  // namespace slam_mms
