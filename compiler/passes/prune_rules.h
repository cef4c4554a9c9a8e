#pragma once
#include <optional>

#include "compiler/ir/fuzzy_system.h"
#include "compiler/passes/pass_report.h"

namespace fmpc {

// Bounds of a grade over an interval of its input: low <= grade(x) <= high for every x in [lo, hi].
struct GradeBounds {
  double low = 0.0;
  double high = 1.0;
};

// Proven bounds of a membership function over [lo, hi], or nullopt where fmpc knows none (NaN parameters,
// dsigmf or an inverted bell whose grades may leave [0, 1]). Monotone families (sigmf, smf, zmf, linsmf, linzmf)
// take their extremes at the ends; quasi-concave ones (trimf, trapmf, gaussmf, gauss2mf, gbellmf with b > 0,
// pimf) are monotone on each side of their top [p, q] (the peak, or the plateau or overlap of the two edges), so
// the bound is 1 where [lo, hi] meets the top and the larger end value elsewhere, the smaller end value below;
// psigmf is bounded by the products of its monotone factors' bounds.
std::optional<GradeBounds> membership_bounds(const MembershipFunction& mf, double lo, double hi);

// Proven bounds of rule `rule`'s firing strength (weight times antecedent strength) while every input lies in its
// declared [min, max]. T-norms and s-norms are nondecreasing in each argument, so folding the clause bounds
// bounds the fold. nullopt when a clause has no known bounds.
std::optional<GradeBounds> firing_bounds(const FuzzySystem& system, std::size_t rule);

// Interval type-2 rules: proven bounds of each end of the firing interval [lower, upper] (the interpreter's
// weight times the span of the two folded ends), from bounds of each end of every clause's footprint (uncertain
// mean and explicit lower MFs as quasi-concave / min-max of type-1 bounds, uncertain sd as two Gaussians, scale and
// lag through its nondecreasing map). nullopt when a clause has no known bounds.
struct FiringIntervalBounds {
  GradeBounds lower;
  GradeBounds upper;
};
std::optional<FiringIntervalBounds> firing_interval_bounds(const FuzzySystem& system, std::size_t rule);

// Removes the rules that cannot fire while the inputs lie in their declared ranges (firing bound 0: exact), and,
// when `epsilon` > 0 in a Mamdani system with max aggregation, the rules whose firing is provably below epsilon.
// Such a rule's implied set is below epsilon everywhere (T(w, mu) <= w for every t-norm), so removing it lowers
// the max-aggregated set by less than epsilon at each of the n output samples. For the centroid,
//   |C - C'| = |sum (y_k - C') (g_k - g'_k)| / sum g_k <= R n epsilon / S_min,
// R the output range and S_min a proven lower bound of the pruned set's sampled mass (from the kept rules' lower
// firing bounds); the bound reported is min(R, that). Other defuzzifiers, `samples exact` and S_min = 0 get R
// (the whole range: a set that changes by epsilon can move their output anywhere). Sugeno systems and other
// aggregations ignore epsilon and remove only the rules that cannot fire.
// Interval type-2 systems: a rule whose upper firing bound is 0 cannot fire (its lower end is 0 too), and the
// interpreter skips such a rule on every output: removing it is exact. Epsilon is ignored (no bound is known for
// the type-reduced output; run_pipeline refuses it).
PassReport prune_rules(FuzzySystem& system, double epsilon);

}  // namespace fmpc
