#pragma once
// Compiler-style control of warnings for every command: -Wno-CODE silences a code, -WCODE brings it back,
// -Werror turns every warning into an error, -Werror=CODE one code, -Wno-error=CODE exempts one from -Werror.
// A warning turned into an error is printed as "error: ... [-Werror=CODE]" and makes the command exit 1 (docs/cli.md:
// the command still finishes; the status says the warnings were asked to fail it).
#include <cstddef>
#include <set>
#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"

namespace CLI {
class App;
}

namespace fmpc::cli {

struct WarningPolicy {
  bool all_errors = false;
  std::set<std::string> disabled;
  std::set<std::string> errors;
  std::set<std::string> not_errors;
};

// Reads one -W value ("no-unit", "error", "error=unit", "no-error=unit", "unit"). Returns an empty string, or
// what is wrong with it (an unknown code, with the closest known one).
std::string apply_warning_flag(const std::string& value, WarningPolicy& policy);

// `diagnostics` with the policy applied: silenced warnings dropped, promoted ones as errors with code
// "error=CODE". `promoted` counts those.
DiagnosticList with_warning_policy(const DiagnosticList& diagnostics, const WarningPolicy& policy,
                                   std::size_t& promoted);

// The process's policy, set from the command line and applied by print_diagnostics (rule_file_session.h).
WarningPolicy& process_warning_policy();
// Warnings promoted to errors so far in this process: main() turns a clean exit into status 1 when there are any.
std::size_t& promoted_warning_count();

// Adds -W to a command (repeatable; the values are applied to process_warning_policy() as they are parsed).
void add_warning_options(CLI::App& command);

}  // namespace fmpc::cli
