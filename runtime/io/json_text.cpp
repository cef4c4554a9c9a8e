#include "runtime/io/json_text.h"

#include <cmath>

#include "diagnostics/number_format.h"

namespace fmpc::sim {

namespace {

// A scalar or a string as nlohmann writes it (strings escaped; invalid UTF-8 replaced, never thrown).
std::string library_text(const JsonDocument& value) {
  return value.dump(-1, ' ', false, JsonDocument::error_handler_t::replace);
}

void append(const JsonDocument& value, std::size_t depth, std::string& out) {
  const bool object = value.is_object();
  if (object || value.is_array()) {
    const char* brackets = object ? "{}" : "[]";
    out += brackets[0];
    bool first = true;
    for (auto member = value.begin(); member != value.end(); ++member) {
      out += first ? "\n" : ",\n";
      first = false;
      out.append(2 * (depth + 1), ' ');
      if (object) out += library_text(JsonDocument(member.key())) + ": ";
      append(member.value(), depth + 1, out);
    }
    if (!first) out += "\n" + std::string(2 * depth, ' ');
    out += brackets[1];
    return;
  }
  if (value.is_number_float()) {
    const double number = value.get<double>();
    out += std::isfinite(number) ? format_number(number) : "null";
    return;
  }
  out += library_text(value);
}

}  // namespace

std::string json_text(const JsonDocument& document) {
  std::string out;
  append(document, 0, out);
  return out + "\n";
}

}  // namespace fmpc::sim
