#pragma once
// JsonWriter: a tiny streaming JSON writer (no third-party JSON library), pretty-printed with
// objects one key per line and arrays of scalars on one line. Non-finite numbers are written as
// null (JSON has no NaN). Numbers use the shortest text that round-trips (std::to_chars).
//
//   JsonWriter w;
//   w.BeginObject().Key("ate_rmse_m").Number(0.42).Key("xyz").BeginArray().Number(1).EndArray()
//    .EndObject();
//   StatusOr<std::string> text = w.Finish();
//
// Misuse (a value where a key is expected, unbalanced Begin/End) is recorded and reported by
// Finish() as kFailedPrecondition, never by aborting.
//
// Thread safety: none; one writer per thread.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "slam_mms/core/status.hpp"

namespace slam_mms::eval {

class JsonWriter {
 public:
  JsonWriter() = default;
  explicit JsonWriter(int indent) : indent_(indent) {}

  JsonWriter& BeginObject();
  JsonWriter& EndObject();
  JsonWriter& BeginArray();
  JsonWriter& EndArray();
  /// The next member's name (inside an object only).
  JsonWriter& Key(std::string_view key);

  JsonWriter& String(std::string_view value);
  JsonWriter& Number(double value);                        ///< NaN/Inf -> null.
  JsonWriter& Number(const std::optional<double>& value);  ///< nullopt -> null.
  JsonWriter& Int(int64_t value);
  JsonWriter& Bool(bool value);
  JsonWriter& Null();

  /// The document, once exactly one complete top-level value was written.
  StatusOr<std::string> Finish() const;

  /// JSON string literal of `s` (quotes and escapes included).
  static std::string Quote(std::string_view s);
  /// Shortest round-trip text of `v`, or "null" when not finite.
  static std::string FormatNumber(double v);

 private:
  struct Level {
    bool is_object = false;
    bool empty = true;
    bool expect_value = false;  // in an object, after Key()
    bool multiline = false;     // an array holding containers
  };
  // Writes the separator/indentation before a value; `container` for Begin*.
  void BeforeValue(bool container);
  void Newline(size_t depth);
  void Fail(const std::string& message);

  int indent_ = 2;
  std::string out_;
  std::vector<Level> stack_;
  bool done_ = false;
  std::string error_;
};

}  // namespace slam_mms::eval
