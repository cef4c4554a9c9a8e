// libFuzzer target: MATLAB .fis (grammar/MatlabFis.g4, compiler/frontend/matlab_fis_reader.cpp, sema, lint).
// The text is read as MATLAB's format whatever it starts with.
#include "compiler/frontend/matlab_fis.h"
#include "compiler/sema/check.h"
#include "compiler/sema/lint.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  fmpc::DiagnosticList diagnostics;
  const fmpc::RuleFile file = fmpc::read_matlab_fis("fuzz.fis", text, diagnostics);
  fmpc::CheckOptions check;
  check.terms_named_by_index = true;
  for (const fmpc::FuzzySystem& system : file.systems) fmpc::check_system(system, check, diagnostics);
  if (!diagnostics.has_errors()) {
    fmpc::LintOptions lint;
    lint.coverage_grid_budget = 2000;
    lint.require_units = false;
    for (const fmpc::FuzzySystem& system : file.systems) fmpc::lint_system(system, lint, diagnostics);
  }
  fmpc::SourceFiles sources;
  sources.add("fuzz.fis", text);
  (void)fmpc::render_all(diagnostics, sources);
  return 0;
}
