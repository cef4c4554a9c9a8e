#pragma once
// A rule file read from disk the way every front end reads it (`fmpc check`, `eval`, `compile`, ..., and the Python
// module): bounded (kMaxRuleFileBytes), a lookup table named as such, the dialect told from the text, then parsed
// and checked. The text is kept so that diagnostics can quote their lines.
#include <string>

#include "compiler/frontend/rule_file_loader.h"
#include "compiler/sema/lint.h"
#include "diagnostics/diagnostic.h"

namespace fmpc::sim {

struct LoadedRuleFile {
  std::string path;
  Dialect dialect = Dialect::Fmpc;
  RuleFile rules;
  DiagnosticList diagnostics;
  SourceFiles sources;
  bool readable = false;  // false when the file could not be read at all (diagnostics say why)
};

LoadedRuleFile load_rule_file_from_disk(const std::string& path);
// The same for text already read from `path` (by read_input_file with the rule file's kind).
LoadedRuleFile load_rule_text(const std::string& path, const std::string& text);

// `fmpc check`'s lint of every system of a file read without errors, appended to its diagnostics in file order.
// Units are asked for only in fmpc's own language: MATLAB's format, FLL and FCL have no field for them.
void lint_rule_file(LoadedRuleFile& file, LintOptions options);

}  // namespace fmpc::sim
