#pragma once
// fuzzylite's FLL ("fuzzylite language", fuzzylite 6) read and written by fmpc itself: an Engine with its input
// and output variables, terms and rule blocks. docs/fll_fcl.md lists what maps to what and what is refused (features
// fmpc's semantics have no counterpart for are errors naming the line, never silently different numbers).
#include <string>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

// One FLL engine as a RuleFile holding one system; errors and warnings carry file:line:column.
RuleFile read_fll(const std::string& path, const std::string& text, DiagnosticList& diagnostics);

// `system` as FLL that fuzzylite's FllImporter reads back; what FLL cannot hold (units, interval type-2,
// `samples exact`, the `error` no-fire policy, a hedge fuzzylite means differently) is an error or a warning
// naming the field.
std::string write_fll(const FuzzySystem& system, DiagnosticList& diagnostics);

// FCL (IEC 61131-7, as fuzzylite's FclImporter and FclExporter read and write it).
RuleFile read_fcl(const std::string& path, const std::string& text, DiagnosticList& diagnostics);
std::string write_fcl(const FuzzySystem& system, DiagnosticList& diagnostics);

}  // namespace fmpc
