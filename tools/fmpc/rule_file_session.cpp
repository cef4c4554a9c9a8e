#include "tools/fmpc/rule_file_session.h"

#include <ostream>

#include "tools/fmpc/warning_policy.h"

namespace fmpc::cli {

void print_diagnostics(const DiagnosticList& reported, const SourceFiles& sources, std::ostream& err) {
  const DiagnosticList diagnostics =
      with_warning_policy(reported, process_warning_policy(), promoted_warning_count());
  if (diagnostics.empty()) return;
  err << render_all(diagnostics, sources);
  const std::size_t errors = diagnostics.error_count();
  const std::size_t warnings = diagnostics.warning_count();
  auto plural = [](std::size_t n, const char* word) { return std::to_string(n) + " " + word + (n == 1 ? "" : "s"); };
  if (errors + warnings > 0) err << plural(errors, "error") << ", " << plural(warnings, "warning") << '\n';
}

const FuzzySystem* select_system(const LoadedRuleFile& file, const std::string& name, DiagnosticList& diagnostics) {
  return fmpc::select_system(file.rules, file.path, name, diagnostics);
}

}  // namespace fmpc::cli
