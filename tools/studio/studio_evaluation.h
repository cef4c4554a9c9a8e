#pragma once
// The patient panel and the control surface as JSON, from the library the CLI uses: the interpreter (the outputs
// `fmpc eval` prints, with their exact text), each rule's firing strength and contribution ("why this stiffness",
// compiler/eval/rule_contributions.h), the aggregated output sets, the evaluation's warnings as `fmpc eval` words
// them, and control surfaces with the strongest rule's firing at every grid point.
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "tools/studio/studio_rule_model.h"

namespace fmpc::studio {

// Precondition: the system passed sema and `inputs` has one finite value per input (the caller checks).
Json evaluation_json(const FuzzySystem& system, const std::vector<double>& inputs);

// The surface of `output` over inputs `x` and `y` (indices), the other inputs at `point`; `resolution` per axis.
Json surface_json(const FuzzySystem& system, std::size_t x, std::size_t y, std::size_t output,
                  const std::vector<double>& point, std::size_t resolution);

// Largest grid a surface request may ask for, per axis.
inline constexpr std::size_t kMaxSurfaceResolution = 201;

}  // namespace fmpc::studio
