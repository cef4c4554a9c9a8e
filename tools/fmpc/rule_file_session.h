#pragma once
// What every command does first: read a rule file, load it, and keep the text so diagnostics can show lines.
#include <iosfwd>
#include <optional>
#include <string>

#include "compiler/frontend/rule_file_loader.h"

namespace fmpc::cli {

// Exit codes shared by all commands (docs/cli.md).
enum ExitCode : int { kExitOk = 0, kExitWarnings = 1, kExitErrors = 2 };

struct LoadedRuleFile {
  std::string path;
  Dialect dialect = Dialect::Fmpc;
  RuleFile rules;
  DiagnosticList diagnostics;
  SourceFiles sources;
  bool readable = false;  // false when the file could not be read at all (diagnostics say why)
};

LoadedRuleFile load_rule_file_from_disk(const std::string& path);

// Prints the diagnostics to `err` compiler-style and, when there are any, a summary line; the -W flags
// (warning_policy.h) apply here, so every command honours them alike.
void print_diagnostics(const DiagnosticList& diagnostics, const SourceFiles& sources, std::ostream& err);

// Picks the system named `name`, or the only one when `name` is empty. Reports a located error otherwise.
const FuzzySystem* select_system(const LoadedRuleFile& file, const std::string& name, DiagnosticList& diagnostics);

}  // namespace fmpc::cli
