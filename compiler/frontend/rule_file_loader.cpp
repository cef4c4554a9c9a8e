#include "compiler/frontend/rule_file_loader.h"

#include <algorithm>

#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/matlab_fis.h"
#include "compiler/sema/check.h"

namespace fmpc {

Dialect detect_dialect(const std::string& text) {
  std::size_t pos = 0;
  while (pos < text.size()) {
    const std::size_t end = std::min(text.find('\n', pos), text.size());
    std::size_t first = text.find_first_not_of(" \t\r", pos);
    if (first < end) {
      const char c = text[first];
      if (c != '%' && c != '#') return text.compare(first, 8, "[System]") == 0 ? Dialect::Matlab : Dialect::Fmpc;
    }
    pos = end + 1;
  }
  return Dialect::Fmpc;
}

RuleFile load_rule_file(const std::string& path, const std::string& text, DiagnosticList& diagnostics) {
  const Dialect dialect = detect_dialect(text);
  RuleFile file = dialect == Dialect::Matlab ? read_matlab_fis(path, text, diagnostics)
                                             : read_fmpc(path, text, diagnostics);
  // MATLAB rules name terms by number, so two terms of one variable may share a name there (juggler.fis does);
  // in the fmpc language rules name terms by name, and a duplicate would be ambiguous.
  CheckOptions options;
  options.terms_named_by_index = dialect == Dialect::Matlab;
  for (const FuzzySystem& system : file.systems) check_system(system, options, diagnostics);
  // An empty file, or one of comments only, would otherwise check clean and evaluate nothing.
  if (file.systems.empty() && !diagnostics.has_errors())
    diagnostics.error(SourceRange{path, 0, 0, 0, 0},
                      "the file defines no system (it is empty or holds only comments); a rule file starts with "
                      "'system NAME' (docs/language.md) or, in MATLAB's format, '[System]'");
  diagnostics.sort_by_position();
  return file;
}

}  // namespace fmpc
