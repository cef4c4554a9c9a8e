#pragma once
// Coverage analysis for lint's coverage-hole warning: where on an input's range no term reaches a grade, and where
// in the box of all inputs no rule fires.
#include <vector>

#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

// A firing strength below this is rounding noise (a gaussian's far tail): lint treats the rule as not firing.
inline constexpr double kNegligibleFiringStrength = 1e-12;

// A run of consecutive sample points [from, to] of an input's range (from == to for a single point).
struct CoverageInterval {
  double from = 0.0;
  double to = 0.0;
};

// The maximal runs of `points` evenly spaced samples of [input.min, input.max] (ends included) where every term
// of `input` stays below `threshold`. Terms that cannot be evaluated count as grade 0. Empty when the range is not
// a finite non-empty interval or the input has no terms.
std::vector<CoverageInterval> input_coverage_holes(const Variable& input, double threshold, int points);

// Firing strength of rule `rule_index` (antecedent folded with the system's and/or method, times the weight) at
// `inputs`. Precondition: rule_is_evaluable(system, rule_index).
double rule_firing_strength(const FuzzySystem& system, std::size_t rule_index, const std::vector<double>& inputs);

// True when every antecedent clause of the rule names an existing input and a gradable term and there is at least
// one clause: the rules the coverage and never-fires analyses can evaluate.
bool rule_is_evaluable(const FuzzySystem& system, std::size_t rule_index);

struct JointCoverage {
  bool analysed = false;        // false when some input range is not a finite non-empty interval, or no inputs
  bool regular_grid = false;    // true: points_per_axis^inputs grid, ends included; false: Halton points
  long points_per_axis = 0;     // for the grid
  long points_checked = 0;       // every point sampled, skipped ones included
  long single_input_holes = 0;  // points skipped: some input alone has no term reaching the threshold there
  long holes = 0;               // the other points where no rule reaches the threshold
  std::vector<double> worst_point;  // the first hole with the lowest maximum firing strength
  double worst_strength = 0.0;  // that lowest maximum; 0 when below kNegligibleFiringStrength
  int strongest_rule = -1;      // a rule reaching worst_strength there; -1 when none fires (worst_strength 0)
};

// Samples the box of all input ranges with at most `budget` points: a regular grid (at most `max_points_per_axis`
// per input) when that allows at least 3 points per axis, a Halton sequence (bases 2, 3, 5, ...) otherwise, and
// finds the points where the strongest rule fires below `threshold`. Points where one input alone has no term
// reaching `threshold` (input_coverage_holes) are counted apart: the rules are not what leaves them uncovered.
JointCoverage joint_coverage(const FuzzySystem& system, double threshold, long budget, long max_points_per_axis);

}  // namespace fmpc
