#pragma once
#include "compiler/ir/fuzzy_system.h"
#include "compiler/passes/pass_report.h"

namespace fmpc {

// Under max aggregation in a Mamdani system, rules with the same consequent (every output clause equal: output,
// term, hedge, negation) add max(T(w1, mu), T(w2, mu)) = T(max(w1, w2), mu) to the aggregate, for every
// implication t-norm (they are nondecreasing). Two kinds of such pairs are fused, exactly:
//  1. identical antecedents (same connective, same clauses in any order) with equal weights: one rule whose
//     folded grade (compiler/passes/specialize.h) is the larger of the two, since F(max(c1, c2), A) =
//     max(F(c1, A), F(c2, A)) for any nondecreasing fold F; or with equal folded grades: one rule with the larger
//     weight. This is what specialising leaves behind (rules that differed only in fixed inputs).
//  2. with `or max`, rules in disjunctive form (connective `or`, or a single clause and no folded grade, or no
//     clause) with equal weights whose clauses name different inputs, or the same clause: one `or` rule over
//     the union, since max(max(A), max(B)) = max(A u B). MATLAB's one-connective rules cannot express
//     "(a and b) or c", so conjunctions are fused only by kind 1.
// The fused rule keeps the first rule's label and position. Sugeno systems and other aggregations are left alone
// (a weighted average sums the rules). Interval type-2 Mamdani systems are fused the same way: the interpreter
// aggregates each end of the output sets with max, so the argument holds on each end (folded grades max-ed end by
// end), the aggregated [lower, upper] sets are unchanged, and so is their type reduction, whichever the method
// (KM, EKM, EIASC and Nie-Tan read only the aggregated sets). Exact: the aggregate is the same (bitwise, except where an Einstein norm rounds differently).
PassReport fuse_consequents(FuzzySystem& system);

}  // namespace fmpc
