#include "runtime/io/json_writer.h"

#include <cmath>
#include <cstdio>

#include "diagnostics/number_format.h"

namespace fmpc::sim {

std::string json_quote(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '"') out += "\\\"";
    else if (c == '\\') out += "\\\\";
    else if (c == '\n') out += "\\n";
    else if (c == '\t') out += "\\t";
    else if (byte < 0x20) {
      char escape[8];
      std::snprintf(escape, sizeof escape, "\\u%04x", static_cast<unsigned>(byte));
      out += escape;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

void JsonWriter::prefix(const std::string& key) {
  if (!first_.empty()) {
    if (!first_.back()) out_ += ",";
    first_.back() = false;
    out_ += "\n" + std::string(2 * first_.size(), ' ');
  }
  if (!key.empty()) out_ += json_quote(key) + ": ";
}

JsonWriter& JsonWriter::begin_object(const std::string& key) {
  prefix(key);
  out_ += "{";
  first_.push_back(true);
  return *this;
}

JsonWriter& JsonWriter::end_object() {
  const bool empty = first_.back();
  first_.pop_back();
  if (!empty) out_ += "\n" + std::string(2 * first_.size(), ' ');
  out_ += "}";
  return *this;
}

JsonWriter& JsonWriter::begin_array(const std::string& key) {
  prefix(key);
  out_ += "[";
  first_.push_back(true);
  return *this;
}

JsonWriter& JsonWriter::end_array() {
  const bool empty = first_.back();
  first_.pop_back();
  if (!empty) out_ += "\n" + std::string(2 * first_.size(), ' ');
  out_ += "]";
  return *this;
}

JsonWriter& JsonWriter::value(const std::string& key, double number) {
  prefix(key);
  out_ += std::isfinite(number) ? format_number(number) : "null";
  return *this;
}

JsonWriter& JsonWriter::value(const std::string& key, long long number) {
  prefix(key);
  out_ += std::to_string(number);
  return *this;
}

JsonWriter& JsonWriter::value(const std::string& key, std::size_t number) {
  prefix(key);
  out_ += std::to_string(number);
  return *this;
}

JsonWriter& JsonWriter::value(const std::string& key, bool flag) {
  prefix(key);
  out_ += flag ? "true" : "false";
  return *this;
}

JsonWriter& JsonWriter::value(const std::string& key, const std::string& text) {
  prefix(key);
  out_ += json_quote(text);
  return *this;
}

JsonWriter& JsonWriter::value(const std::string& key, const char* text) { return value(key, std::string(text)); }

JsonWriter& JsonWriter::element(double number) { return value("", number); }

std::string JsonWriter::str() const { return out_ + "\n"; }

}  // namespace fmpc::sim
