#pragma once
#include "compiler/ir/fuzzy_system.h"
#include "compiler/passes/pass_report.h"

namespace fmpc {

// Removes the input and output terms that no rule names (after specialisation and pruning many are left) and
// renumbers the clauses. Exact: a term's grade enters the output only through a clause.
PassReport drop_dead_terms(FuzzySystem& system);

}  // namespace fmpc
