#pragma once
// Structural comparison of two FuzzySystems for round-trip tests.
#include <string>

#include "compiler/ir/fuzzy_system.h"

namespace fmpc::testing {

// What a comparison looks at besides the meaning-carrying fields: the fmpc-only fields (descriptions, units, rule
// labels) that a MATLAB .fis file cannot hold.
struct ComparisonOptions {
  bool descriptions_units_and_labels = true;
};

// The first difference between `expected` and `actual` as a readable path ("input 'x' term 2 param 1: 0.1 vs
// 0.2"), or "" when they are equal. Source ranges are ignored. Numbers compare as doubles (==, so 0 equals -0,
// which format_number folds) with NaN equal to NaN: a value that went through text came back with the same bits.
// Clauses compare in variable order, since a rule may list them in any order.
std::string first_difference(const FuzzySystem& expected, const FuzzySystem& actual,
                             const ComparisonOptions& options = {});

}  // namespace fmpc::testing
