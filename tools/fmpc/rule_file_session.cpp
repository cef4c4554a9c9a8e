#include "tools/fmpc/rule_file_session.h"

#include <ostream>

#include "compiler/backend/table/lookup_table.h"
#include "tools/fmpc/text_files.h"
#include "tools/fmpc/warning_policy.h"

namespace fmpc::cli {

LoadedRuleFile load_rule_file_from_disk(const std::string& path) {
  LoadedRuleFile file;
  file.path = path;
  std::string error;
  const std::optional<std::string> text = read_text_file(path, sim::kMaxRuleFileBytes, "rule file", error);
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
  file.readable = true;
  file.sources.add(path, *text);
  file.dialect = detect_dialect(*text);
  file.rules = load_rule_file(path, *text, file.diagnostics);
  return file;
}

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
  const auto& systems = file.rules.systems;
  if (name.empty()) {
    if (systems.size() == 1) return &systems.front();
    if (systems.empty()) {
      diagnostics.error(SourceRange{file.path, 0, 0, 0, 0}, "the file defines no system");
      return nullptr;
    }
    std::string names;
    for (const FuzzySystem& s : systems) names += (names.empty() ? "" : ", ") + s.name;
    diagnostics.error(SourceRange{file.path, 0, 0, 0, 0}, "the file defines " + std::to_string(systems.size()) +
                                                              " systems (" + names +
                                                              "); choose one with --system NAME");
    return nullptr;
  }
  std::vector<std::string> names;
  for (const FuzzySystem& s : systems) {
    if (s.name == name) return &s;
    names.push_back(s.name);
  }
  std::vector<std::string> notes;
  if (auto suggestion = closest_name(name, names)) notes.push_back("did you mean '" + *suggestion + "'?");
  diagnostics.error(SourceRange{file.path, 0, 0, 0, 0}, "no system named '" + name + "' in the file", notes);
  return nullptr;
}

}  // namespace fmpc::cli
