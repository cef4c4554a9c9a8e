#include "runtime/io/rule_file_input.h"

#include "compiler/backend/table/lookup_table.h"
#include "runtime/io/input_file.h"

namespace fmpc::sim {

LoadedRuleFile load_rule_file_from_disk(const std::string& path) {
  LoadedRuleFile file;
  file.path = path;
  std::string error;
  const std::optional<std::string> text = read_input_file(path, kMaxRuleFileBytes, "rule file", error);
  if (!text) {
    file.diagnostics.error(SourceRange{path, 0, 0, 0, 0}, error);
    return file;
  }
  if (has_fzt_signature(*text)) {
    file.diagnostics.error(SourceRange{path, 0, 0, 0, 0},
                           "'" + path + "' is a compiled lookup table (.fzt), not a rule file",
                           {"fmpc eval evaluates tables: fmpc eval " + path + " NAME=VALUE..."});
    return file;
  }
  return load_rule_text(path, *text);
}

LoadedRuleFile load_rule_text(const std::string& path, const std::string& text) {
  LoadedRuleFile file;
  file.path = path;
  file.readable = true;
  file.sources.add(path, text);
  file.dialect = detect_dialect(text);
  file.rules = load_rule_file(path, text, file.diagnostics);
  return file;
}

void lint_rule_file(LoadedRuleFile& file, LintOptions options) {
  if (!file.readable || file.diagnostics.has_errors()) return;
  options.require_units = file.dialect == Dialect::Fmpc;
  for (const FuzzySystem& system : file.rules.systems) lint_system(system, options, file.diagnostics);
  file.diagnostics.sort_by_position();
}

}  // namespace fmpc::sim
