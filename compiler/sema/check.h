#pragma once
// Semantic errors on the IR that both dialects share: invalid MF parameters (sd <= 0, triangle feet out of
// order, ...), empty or inverted ranges, duplicate variable or term names, rule indices that do not resolve,
// weights outside [0, 1], Sugeno/Mamdani mismatches (a gaussmf output in a Sugeno system, a constant in a Mamdani
// one), defuzzifiers that do not fit the type.
#include "compiler/ir/fuzzy_system.h"
#include "compiler/sema/diagnostic.h"

namespace fmpc {

void check_system(const FuzzySystem& system, DiagnosticList& diagnostics);

// check_system for every system of `file`, plus systems of the same name within the file.
void check_rule_file(const RuleFile& file, DiagnosticList& diagnostics);

}  // namespace fmpc
