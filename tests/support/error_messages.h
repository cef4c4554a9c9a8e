#pragma once
// The error messages of a diagnostic list, one a line, without positions or notes (what the runtime's tests compare).
#include <string>

#include "diagnostics/diagnostic.h"

namespace fmpc::testing {

inline std::string errors_of(const DiagnosticList& diagnostics) {
  std::string text;
  for (const Diagnostic& d : diagnostics.items())
    if (d.severity == Severity::Error) text += (text.empty() ? "" : "\n") + d.message;
  return text;
}

}  // namespace fmpc::testing
