#pragma once
// evaluate_batch over blocks of lanes (docs/codegen.md, "Batch evaluation"): for type-1 Mamdani systems that
// defuzzify by centroid with max aggregation and min or product implication (MATLAB's defaults, the liver's kind),
// the generated evaluate_batch takes the points in blocks of kBatchLanes and runs every step as a loop over the
// block's lanes on structure-of-arrays locals, which compilers vectorise (GCC: -O2 -ftree-vectorize or -O3). It
// agrees with evaluate() to the tolerances of docs/codegen.md, not bit for bit. Other systems keep a loop over
// evaluate() (emit_cpp.cpp).
#include <string>

#include "compiler/backend/cpp/cpp_text.h"
#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

// The kernel header whose namespace body (embedded_namespace_body) gives the lanes their exp.
inline constexpr const char* kLaneExpMathFile = "kernels/lane_exp_math.h";

// Whether `system`'s evaluate_batch runs lanes: the class above, and an unrolled aggregation of at most 16,384
// column-samples (beyond that the header would take too long to compile).
bool lane_batch_applies(const FuzzySystem& system);

// Writes, inside the header's namespace and after evaluate(): the FMPC_GENERATED_BATCH_CLONES macro (GCC's
// target_clones for x86-64 v3 and v4), kBatchLanes, `lane_exp_text` (kLaneExpMathFile's body: lane_exp and
// lane_gaussian), the consequent grades the aggregation reads (kLaneGrades<o>) and evaluate_batch, which sends
// NaN inputs and aggregates too small for its shortcuts to evaluate().
// Precondition: lane_batch_applies(system).
void emit_lane_batch(const FuzzySystem& system, const std::string& lane_exp_text, CodeWriter& out);

}  // namespace fmpc
