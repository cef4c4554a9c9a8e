#include "tools/fmpc/binding_arguments.h"

#include <cmath>
#include <cstdlib>
#include <optional>

namespace fmpc::cli {

namespace {

SourceRange argument(const std::string& option, const std::string& value) {
  return SourceRange{"argument '" + option + " " + value + "'", 0, 0, 0, 0};
}

std::optional<double> whole_text_number(const std::string& text) {
  if (text.empty()) return std::nullopt;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) return std::nullopt;
  return value;
}

}  // namespace

Bindings parse_binding_arguments(const std::vector<std::string>& fix, const std::vector<std::string>& vary,
                                 DiagnosticList& diagnostics) {
  Bindings bindings;
  for (const std::string& text : fix) {
    const SourceRange where = argument("--fix", text);
    const std::size_t eq = text.find('=');
    if (eq == std::string::npos || eq == 0) {
      diagnostics.error(where, "expected NAME=VALUE", {"for example: --fix HCV=7.5"});
      continue;
    }
    const std::optional<double> value = whole_text_number(text.substr(eq + 1));
    if (!value) {
      diagnostics.error(where, "'" + text.substr(eq + 1) + "' is not a number");
      continue;
    }
    bindings.fixed.push_back({text.substr(0, eq), *value, where});
  }
  for (const std::string& text : vary) {
    const SourceRange where = argument("--vary", text);
    const std::size_t colon = text.rfind(':');
    VariedInput varied{text, 0, where};
    if (colon != std::string::npos) {
      varied.name = text.substr(0, colon);
      const std::optional<double> points = whole_text_number(text.substr(colon + 1));
      if (!points || *points != std::floor(*points) || *points < 2 || *points > kMaxAxisPoints) {
        diagnostics.error(where, "'" + text.substr(colon + 1) + "' is not a point count",
                          {"write NAME:POINTS with a whole number of at least 2, e.g. --vary HCV:33"});
        continue;
      }
      varied.points = static_cast<int>(*points);
    }
    bindings.varied.push_back(varied);
  }
  return bindings;
}

}  // namespace fmpc::cli
