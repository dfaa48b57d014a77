#pragma once
// Status and StatusOr<T>: how every fallible slam_mms call reports failure. No exception crosses
// the public API; bad input or bad options return a Status whose message names the file, line,
// field or option and the rule it breaks.
//
// Thread safety: value types; distinct objects may be used from distinct threads.

#include <cassert>
#include <optional>
#include <string>
#include <utility>

namespace slam_mms {

enum class StatusCode {
  kOk = 0,
  kInvalidArgument,     ///< A bad option or argument value.
  kNotFound,            ///< A file, folder or record that should exist does not.
  kDataLoss,            ///< A file is truncated or corrupt.
  kOutOfRange,          ///< A time or index outside what the data covers.
  kFailedPrecondition,  ///< Called in the wrong state (e.g. before initialisation).
  kUnavailable,         ///< A resource (EGL display, GPU) could not be opened.
  kInternal,            ///< A solver or library failure that is not the caller's fault.
  kUnimplemented,
};

/// Human-readable name of a code ("INVALID_ARGUMENT", ...).
const char* StatusCodeName(StatusCode code);

class [[nodiscard]] Status {
 public:
  Status() = default;
  Status(StatusCode code, std::string message) : code_(code), message_(std::move(message)) {}

  static Status Ok() { return Status(); }

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  const std::string& message() const { return message_; }
  /// "INVALID_ARGUMENT: message", or "OK".
  std::string ToString() const;

  /// Returns a copy with `context + ": "` prepended to the message (no-op when ok).
  Status WithContext(const std::string& context) const;

 private:
  StatusCode code_ = StatusCode::kOk;
  std::string message_;
};

inline Status OkStatus() { return Status(); }
inline Status InvalidArgumentError(std::string m) {
  return Status(StatusCode::kInvalidArgument, std::move(m));
}
inline Status NotFoundError(std::string m) { return Status(StatusCode::kNotFound, std::move(m)); }
inline Status DataLossError(std::string m) { return Status(StatusCode::kDataLoss, std::move(m)); }
inline Status OutOfRangeError(std::string m) {
  return Status(StatusCode::kOutOfRange, std::move(m));
}
inline Status FailedPreconditionError(std::string m) {
  return Status(StatusCode::kFailedPrecondition, std::move(m));
}
inline Status UnavailableError(std::string m) {
  return Status(StatusCode::kUnavailable, std::move(m));
}
inline Status InternalError(std::string m) { return Status(StatusCode::kInternal, std::move(m)); }

/// A value or the Status saying why there is none.
template <typename T>
class [[nodiscard]] StatusOr {
 public:
  /// Implicit from an error Status (must not be ok).
  StatusOr(Status status) : status_(std::move(status)) {  // NOLINT(google-explicit-constructor)
    if (status_.ok()) status_ = InternalError("StatusOr constructed from an OK Status");
  }
  StatusOr(const T& value) : value_(value) {}        // NOLINT(google-explicit-constructor)
  StatusOr(T&& value) : value_(std::move(value)) {}  // NOLINT(google-explicit-constructor)

  bool ok() const { return status_.ok(); }
  const Status& status() const { return status_; }

  const T& value() const& {
    assert(ok());
    return *value_;
  }
  T& value() & {
    assert(ok());
    return *value_;
  }
  T&& value() && {
    assert(ok());
    return std::move(*value_);
  }
  const T& operator*() const& { return value(); }
  T& operator*() & { return value(); }
  const T* operator->() const { return &value(); }
  T* operator->() { return &value(); }

 private:
  Status status_;
  std::optional<T> value_;
};

}  // namespace slam_mms

/// Returns early from the enclosing function when `expr` (a Status) is not ok.
#define SLAM_MMS_RETURN_IF_ERROR(expr)                   \
  do {                                                   \
    ::slam_mms::Status slam_mms_status_ = (expr);        \
    if (!slam_mms_status_.ok()) return slam_mms_status_; \
  } while (0)

#define SLAM_MMS_CONCAT_INNER_(a, b) a##b
#define SLAM_MMS_CONCAT_(a, b) SLAM_MMS_CONCAT_INNER_(a, b)
/// `SLAM_MMS_ASSIGN_OR_RETURN(auto x, Foo());` unwraps a StatusOr or returns its Status.
#define SLAM_MMS_ASSIGN_OR_RETURN(lhs, expr)                  \
  auto SLAM_MMS_CONCAT_(slam_mms_or_, __LINE__) = (expr);     \
  if (!SLAM_MMS_CONCAT_(slam_mms_or_, __LINE__).ok())         \
    return SLAM_MMS_CONCAT_(slam_mms_or_, __LINE__).status(); \
  lhs = std::move(SLAM_MMS_CONCAT_(slam_mms_or_, __LINE__)).value()
