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
  RuleFile file = detect_dialect(text) == Dialect::Matlab ? read_matlab_fis(path, text, diagnostics)
                                                          : read_fmpc(path, text, diagnostics);
  for (const FuzzySystem& system : file.systems) check_system(system, diagnostics);
  diagnostics.sort_by_position();
  return file;
}

}  // namespace fmpc
