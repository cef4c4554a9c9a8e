#pragma once
// MATLAB's .fis format, versions 1 and 2 (also Octave's fuzzy-logic-toolkit layout), read with the meaning MATLAB
// gives it and written so that MATLAB reads it back. docs/matlab_fis.md lists every key and rule-line feature.
#include <string>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

// Reads one MATLAB .fis file into a RuleFile holding one system. Errors (unknown keys are warnings, malformed
// values, rule indices out of range, counts that disagree) carry file:line:column.
RuleFile read_matlab_fis(const std::string& path, const std::string& text, DiagnosticList& diagnostics);

// Writes `system` in MATLAB's version 2.0 layout. What MATLAB cannot hold (units, descriptions, `samples exact`,
// a no-fire value or error policy, mixed connectives) is reported as a warning naming the field.
std::string write_matlab_fis(const FuzzySystem& system, DiagnosticList& diagnostics);

}  // namespace fmpc
