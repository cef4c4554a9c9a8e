#pragma once
// What lint needs to know about the shape of a term's membership function: where it peaks, how wide it is, how
// high and low it gets on an interval. Grades come from kernels/fuzzy_math.h (the one MF evaluator).
#include <optional>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

// True when `term` is an input-style MF (not constant/linear) with enough finite parameters to evaluate.
bool is_gradable(const Term& term);

// Grade of x in `term` (precondition: is_gradable(term)).
double term_grade(const Term& term, double x);

// Grade of x for the clause "VAR is [not] [hedge] TERM": hedge first, then the complement (MATLAB, Octave).
double clause_grade(const Term& term, const Clause& clause, double x);
// The same from the term's grade at x, for callers that have it already.
double clause_grade_of_term_grade(const Clause& clause, double term_grade);

// Sampled, not proven (passes/prune_rules.h has the proven GradeBounds): an estimate of the range.
struct SampledGradeRange {
  double lowest = 0.0;
  double highest = 0.0;
};

// Smallest and largest clause grade on [lo, hi], from `samples` evenly spaced points plus the MF's breakpoints
// and centres inside the interval (so that narrow peaks are never stepped over).
SampledGradeRange clause_grade_bounds(const Term& term, const Clause& clause, double lo, double hi, int samples);

// Where the term is "on": the points of grade 1 for a peaked shape (triangle peak, trapezoid shoulders, gaussian
// mean, ...), the half-line of grade >= 0.5 for a one-sided shape (zmf, smf, linsmf, linzmf, sigmf). Bounds may be
// infinite. nullopt for shapes without a simple core (dsigmf, psigmf) and for terms that are not gradable.
struct CoreInterval {
  double lo = 0.0;
  double hi = 0.0;
};
std::optional<CoreInterval> term_core(const Term& term);

// A point that orders terms from low to high: the middle of the core for peaked shapes, the centroid of the
// grade over [lo, hi] for one-sided and sigmoid shapes. nullopt when not gradable or zero on the whole interval.
std::optional<double> term_centre(const Term& term, double lo, double hi);

// The widths that make a term narrow (gaussian sd, triangle foot distance c - a, ...), named as messages say them.
// Exact zeros of zmf/smf/linsmf/linzmf are left out: a == b is MATLAB's crisp step, written on purpose.
struct TermWidth {
  std::string name;
  double value = 0.0;
};
std::vector<TermWidth> term_widths(const Term& term);

}  // namespace fmpc
