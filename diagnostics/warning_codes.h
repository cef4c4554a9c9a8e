#pragma once
// Every warning code fmpc reports, with the stage that reports it. `-Wno-CODE` and `-Werror=CODE` (tools/fmpc)
// accept exactly these names; tests/cmake/warning_codes_check.cmake fails when a `warning(..., "code", ...)` in
// the sources is missing here, so the list cannot drift from the code.
#include <string>
#include <vector>

namespace fmpc {

struct WarningCode {
  const char* name;   // as in the "[-Wname]" tag
  const char* stage;  // who reports it: "lint", "eval", "matlab", "scene", ...
};

const std::vector<WarningCode>& warning_codes();
bool is_warning_code(const std::string& name);

}  // namespace fmpc
