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

// Writes `system` in MATLAB's version 2.0 layout (type-2 systems as MATLAB's mamfistype2 / sugfistype2). What
// MATLAB cannot hold is reported as a warning naming the field: with code kMatlabExport where reading the file
// back gives the same outputs (descriptions, units of inputs, rule labels, Octave's hedge fractions and Einstein
// norms, which MATLAB itself does not know), kMatlabLossy where it does not (sample counts, no-fire policies,
// footprints MATLAB cannot express, which are written as the closest MATLAB footprint, Nie-Tan, interval
// constants, an output in Pa or MPa, which scenes would read as kPa).
std::string write_matlab_fis(const FuzzySystem& system, DiagnosticList& diagnostics);

inline constexpr const char* kMatlabExport = "matlab-export";
inline constexpr const char* kMatlabLossy = "matlab-lossy";

}  // namespace fmpc
