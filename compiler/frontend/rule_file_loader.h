#pragma once
// One entry point for every reader: picks the dialect from the text (detect_dialect), parses, lowers and checks. Returns what it could build; errors are in `diagnostics`.
#include <optional>
#include <string>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

enum class Dialect { Fmpc, Matlab, Fll, Fcl };

// Told apart by the first line that is not blank or a comment (%, #, //, (* ... *)): "[System]" is MATLAB's,
// "Engine:" (or another FLL section) fuzzylite's FLL, "FUNCTION_BLOCK" IEC 61131-7 FCL, anything else fmpc's.
Dialect detect_dialect(const std::string& text);
const char* dialect_name(Dialect dialect);  // "fmpc", "MATLAB .fis", "fuzzylite FLL", "IEC 61131-7 FCL"

// A format fmpc does not read, named from its first line (XML, JSON, a YAML scene, CSV data), with what to do; empty
// when the text does not look like one of them.
std::string foreign_format(const std::string& text);

// Parses `text` (the contents of `path`), resolves names and checks parameters (sema). The result holds every
// system that could be built; when diagnostics.has_errors() it must not be evaluated.
RuleFile load_rule_file(const std::string& path, const std::string& text, DiagnosticList& diagnostics);

// The system of `rules` (read from `path`) named `name`, or the only one when `name` is empty. Reports an error
// naming the file otherwise (with the names defined, or the closest one).
const FuzzySystem* select_system(const RuleFile& rules, const std::string& path, const std::string& name,
                                 DiagnosticList& diagnostics);

}  // namespace fmpc
