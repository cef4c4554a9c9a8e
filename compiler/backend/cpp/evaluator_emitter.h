#pragma once
// The type-1 evaluate function of a generated header (docs/codegen.md, "How it is fast"): one point, straight-line
// code, every formula the interpreter's. The frame around it (banner, embedded math, interface constants,
// evaluate_batch, the CUDA kernel) is emit_cpp.h's; interval type-2 systems get emit_type2.h's instead.
#include "compiler/backend/cpp/cpp_text.h"
#include "compiler/backend/cpp/emit_cpp.h"
#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

// Writes `template <typename T> FMPC_HD unsigned evaluate(const T* inputs, T* outputs)` for the type-1 `system`
// into `out`, inside the header's namespace, where `fmpc_math` names the embedded math and kFlag*, grade_min and
// grade_max are defined. Each input term's grade is computed once, rules sharing a prefix of clauses share its
// partial fold, Mamdani consequents become constant tables of their grades at the output's samples, and under max
// aggregation with min or prod implication rules with the same consequent share one column. `#line` directives
// point each rule's code at the rule file (and back at the header), as `options` ask.
// Precondition: `system` passed sema, is type-1, and Mamdani systems are sampled (not `samples exact`).
void emit_type1_evaluate_function(const FuzzySystem& system, const EmitOptions& options, CodeWriter& out);

}  // namespace fmpc
