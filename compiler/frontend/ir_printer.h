#pragma once
// A readable dump of the IR, for `fmpc compile --dump-after=PASS` and for tests: the system in the fmpc language's
// canonical layout (compiler/frontend/fmpc_language.h), with what the language cannot say written in angle
// brackets: a rule's folded grade (compiler/passes/specialize.h) as `if <fixed 0.37> and ...`, a rule with no
// clause left as `if <fixed 0.37> then ...`; an interval type-2 rule's folded interval as `<fixed [0.2, 0.37]>`.
#include <string>

#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

std::string print_ir(const FuzzySystem& system);

}  // namespace fmpc
