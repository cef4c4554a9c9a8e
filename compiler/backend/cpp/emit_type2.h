#pragma once
// The interval type-2 part of the C++ / CUDA code emitter (emit_cpp.h). A type-2 header has the same frame as a
// type-1 one (banner, embedded math, interface constants, evaluate_batch, the CUDA kernel and launcher); what
// differs is the evaluate function, written here, and the embedded math, which adds kernels/type2_math.h
// (footprints, interval norms) and kernels/type_reduction_math.h (KM, EKM, EIASC, Nie-Tan) to the type-1 copy.
// docs/codegen.md ("Interval type-2") describes the generated interface.
#include "compiler/backend/cpp/cpp_text.h"
#include "compiler/backend/cpp/emit_cpp.h"
#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

// Writes into `out` what takes the place of the type-1 evaluate function for an interval type-2 `system`:
//   unsigned evaluate_interval<T>(const T* inputs, T* outputs, T* lower, T* upper): one point; outputs[o] is the
//     crisp output (yl + yr) / 2 and, where lower / upper are not null, [lower[o], upper[o]] = [yl, yr], the
//     type-reduced interval (both ends the no-fire value where no rule fired, NaN for a NaN input);
//   unsigned evaluate<T>(const T* inputs, T* outputs): the crisp outputs alone.
// Every step is the interpreter's (compiler/eval/interpreter.cpp, run_type2), calling the embedded kernel
// functions, so double agrees with `fmpc eval` to rounding. The text goes inside the header's namespace, where
// `fmpc_math` names the embedded math and kFlag* are defined; `out` counts the header's lines, so that the `#line`
// directives after each rule can point back into the header.
// Preconditions: `system` passed sema and is interval type-2 (so Mamdani systems are sampled and defuzzify by
// centroid). A rule's folded grades (Rule::folded_grade, folded_grade_lower: fixed inputs folded in by the
// specialize pass) start the fold of its clauses on each end, as in the interpreter.
void emit_type2_evaluate_function(const FuzzySystem& system, const EmitOptions& options, CodeWriter& out);

}  // namespace fmpc
