#pragma once
// What every command does first: read a rule file, load it, and keep the text so diagnostics can show lines.
#include <iosfwd>
#include <optional>
#include <string>

#include "runtime/io/rule_file_input.h"

namespace fmpc::cli {

// Exit codes shared by all commands (docs/cli.md).
enum ExitCode : int { kExitOk = 0, kExitWarnings = 1, kExitErrors = 2 };

// Reading and loading are the library's (runtime/io/rule_file_input.h); printing is the CLI's.
using sim::LoadedRuleFile;
using sim::load_rule_file_from_disk;

// Prints the diagnostics to `err` compiler-style and, when there are any, a summary line; the -W flags
// (warning_policy.h) apply here, so every command honours them alike.
void print_diagnostics(const DiagnosticList& diagnostics, const SourceFiles& sources, std::ostream& err);

// select_system (compiler/frontend/rule_file_loader.h) on a loaded file.
const FuzzySystem* select_system(const LoadedRuleFile& file, const std::string& name, DiagnosticList& diagnostics);

}  // namespace fmpc::cli
