#pragma once
// The body both rule-file targets share: load (parse, lower, check), lint what loaded cleanly, render every
// diagnostic with the source. A finding is a crash, a sanitizer report, a leak or a timeout.
#include <cstddef>
#include <cstdint>
#include <string>

#include "compiler/frontend/rule_file_loader.h"
#include "compiler/sema/lint.h"

namespace fmpc::fuzz {

inline void load_lint_render(const std::string& path, const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  DiagnosticList diagnostics;
  const RuleFile file = load_rule_file(path, text, diagnostics);
  if (!diagnostics.has_errors()) {
    LintOptions options;
    options.coverage_grid_budget = 2000;  // the joint check's cost is its budget; keep executions fast
    for (const FuzzySystem& system : file.systems) lint_system(system, options, diagnostics);
  }
  SourceFiles sources;
  sources.add(path, text);
  (void)render_all(diagnostics, sources);
}

}  // namespace fmpc::fuzz
