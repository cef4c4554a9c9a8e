#pragma once
// Semantic errors on the IR that both dialects share: invalid MF parameters (sd <= 0, triangle feet out of
// order, ...), empty or inverted ranges, duplicate variable or term names, rule indices that do not resolve,
// weights outside [0, 1], Sugeno/Mamdani mismatches (a gaussmf output in a Sugeno system, a constant in a Mamdani
// one), defuzzifiers that do not fit the type.
#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

void check_system(const FuzzySystem& system, DiagnosticList& diagnostics);

struct CheckOptions {
  // MATLAB's rules name terms by index, so a MATLAB file may repeat a term name within a variable (MATLAB's own
  // juggler.fis does). Set for MATLAB files: a repeated term name is then the warning `duplicate-term` instead of
  // an error (writing such a system as fmpc text needs new names).
  bool terms_named_by_index = false;
};

void check_system(const FuzzySystem& system, const CheckOptions& options, DiagnosticList& diagnostics);

}  // namespace fmpc
