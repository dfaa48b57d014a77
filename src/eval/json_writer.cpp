#include "slam_mms/eval/json_writer.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace slam_mms::eval {

void JsonWriter::Fail(const std::string& message) {
  if (error_.empty()) error_ = message;
}

void JsonWriter::Newline(size_t depth) {
  out_ += '\n';
  out_.append(depth * static_cast<size_t>(indent_), ' ');
}

void JsonWriter::BeforeValue(bool container) {
  if (!error_.empty()) return;
  if (stack_.empty()) {
    if (done_) Fail("JsonWriter: a second top-level value");
    return;
  }
  Level& top = stack_.back();
  if (top.is_object) {
    if (!top.expect_value) Fail("JsonWriter: a value inside an object without a Key()");
    top.expect_value = false;
    return;  // Key() wrote the separator and indentation
  }
  if (container) top.multiline = true;
  if (!top.empty) out_ += top.multiline ? "," : ", ";
  if (top.multiline) Newline(stack_.size());
  top.empty = false;
}

JsonWriter& JsonWriter::BeginObject() {
  BeforeValue(true);
  out_ += '{';
  stack_.push_back({true, true, false, true});
  return *this;
}

JsonWriter& JsonWriter::EndObject() {
  if (stack_.empty() || !stack_.back().is_object || stack_.back().expect_value) {
    Fail("JsonWriter: EndObject() without a matching BeginObject() or after a dangling Key()");
    return *this;
  }
  const bool empty = stack_.back().empty;
  stack_.pop_back();
  if (!empty) Newline(stack_.size());
  out_ += '}';
  if (stack_.empty()) done_ = true;
  return *this;
}

JsonWriter& JsonWriter::BeginArray() {
  BeforeValue(true);
  out_ += '[';
  stack_.push_back({false, true, false, false});
  return *this;
}

JsonWriter& JsonWriter::EndArray() {
  if (stack_.empty() || stack_.back().is_object) {
    Fail("JsonWriter: EndArray() without a matching BeginArray()");
    return *this;
  }
  const bool multiline = stack_.back().multiline && !stack_.back().empty;
  stack_.pop_back();
  if (multiline) Newline(stack_.size());
  out_ += ']';
  if (stack_.empty()) done_ = true;
  return *this;
}

JsonWriter& JsonWriter::Key(std::string_view key) {
  if (stack_.empty() || !stack_.back().is_object || stack_.back().expect_value) {
    Fail("JsonWriter: Key(\"" + std::string(key) + "\") outside an object or after another Key()");
    return *this;
  }
  Level& top = stack_.back();
  if (!top.empty) out_ += ',';
  Newline(stack_.size());
  out_ += Quote(key);
  out_ += ": ";
  top.empty = false;
  top.expect_value = true;
  return *this;
}

JsonWriter& JsonWriter::String(std::string_view value) {
  BeforeValue(false);
  out_ += Quote(value);
  if (stack_.empty()) done_ = true;
  return *this;
}

JsonWriter& JsonWriter::Number(double value) {
  BeforeValue(false);
  out_ += FormatNumber(value);
  if (stack_.empty()) done_ = true;
  return *this;
}

JsonWriter& JsonWriter::Number(const std::optional<double>& value) {
  return value ? Number(*value) : Null();
}

JsonWriter& JsonWriter::Int(int64_t value) {
  BeforeValue(false);
  out_ += std::to_string(value);
  if (stack_.empty()) done_ = true;
  return *this;
}

JsonWriter& JsonWriter::Bool(bool value) {
  BeforeValue(false);
  out_ += value ? "true" : "false";
  if (stack_.empty()) done_ = true;
  return *this;
}

JsonWriter& JsonWriter::Null() {
  BeforeValue(false);
  out_ += "null";
  if (stack_.empty()) done_ = true;
  return *this;
}

StatusOr<std::string> JsonWriter::Finish() const {
  if (!error_.empty()) return FailedPreconditionError(error_);
  if (!stack_.empty()) {
    return FailedPreconditionError("JsonWriter: " + std::to_string(stack_.size()) +
                                   " unclosed object(s)/array(s)");
  }
  if (!done_) return FailedPreconditionError("JsonWriter: nothing was written");
  return out_ + "\n";
}

std::string JsonWriter::Quote(std::string_view s) {
  std::string q;
  q.reserve(s.size() + 2);
  q += '"';
  for (const char c : s) {
    switch (c) {
      case '"': q += "\\\""; break;
      case '\\': q += "\\\\"; break;
      case '\n': q += "\\n"; break;
      case '\r': q += "\\r"; break;
      case '\t': q += "\\t"; break;
      case '\b': q += "\\b"; break;
      case '\f': q += "\\f"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20) {
          char buf[8];
          std::snprintf(buf, sizeof(buf), "\\u%04x", static_cast<unsigned>(c));
          q += buf;
        } else {
          q += c;  // UTF-8 passes through unchanged
        }
    }
  }
  q += '"';
  return q;
}

std::string JsonWriter::FormatNumber(double v) {
  if (!std::isfinite(v)) return "null";
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof(buf), v);
  return std::string(buf, res.ptr);
}

}  // namespace slam_mms::eval
