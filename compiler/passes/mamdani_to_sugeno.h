#pragma once
// Mamdani -> zero-order Sugeno conversion, as MATLAB's convertToSugeno (formerly mam2sug) does it.
#include <optional>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

// One output term's conversion, for reports and tests.
struct ConvertedTerm {
  int output = -1;
  int term = -1;
  double constant = 0.0;  // the centroid the term became
};

// Converts the Mamdani system `system` in place into a zero-order Sugeno system:
// - every output term becomes `constant(value c)`, c = the centroid of the term's membership function over the
//   output range. MATLAB (mam2sug.m, Fuzzy Logic Toolbox 1994-2002, R. Jang; convertToSugeno since R2018b):
//   sample the range at linspace(min, max, 101), c = defuzz(x, mf(x), 'centroid') = sum(x mf) / sum(mf).
//   fmpc uses the system's own output sampling: `samples N` samples N points the same way (101 by default, as
//   MATLAB), `samples exact` integrates the term exactly (compiler/eval/defuzzify.h integrate_exact). Where the
//   term lies partly outside the range only its part inside counts, as in MATLAB (the range clips it).
// - defuzzification becomes weighted average ("wtaver"); implication becomes prod and aggregation sum, the
//   values MATLAB's Sugeno systems always carry ("Sugeno systems always use product implication and sum
//   aggregation", MathWorks, "What Is Sugeno-Type Fuzzy Inference?"). They do not enter a Sugeno output.
// - interval type-2 systems (`type interval_type2 mamdani`) become interval type-2 Sugeno systems (MATLAB
//   mamfistype2 -> sugfistype2): the inputs keep their footprints, and each output term with a footprint becomes
//   the type-1 constant (yl + yr) / 2, where [yl, yr] is the term's centroid interval computed by the system's
//   type reduction (Karnik-Mendel by default) over the same samples (101 for `samples exact`, which has no closed
//   form here). This is the crisp output the type-2 Mamdani system gives when that term's rule alone fires fully,
//   as the type-1 constant is the output when its rule alone fires fully. MATLAB's sugfistype2 outputs are type-1
//   constants too ("In type-2 Sugeno systems, only the input membership functions are type-2 fuzzy sets",
//   MathWorks, "Type-2 Fuzzy Inference Systems"); which crisp centroid convertToSugeno takes for a type-2 output
//   is not stated in the documentation available to us (docs/liver_fibrosis.md).
// - inputs, and/or methods, rules (hedges, negations, weights), the no-fire policy and names are unchanged.
// Differences from MATLAB, reported as warnings:
// - a Mamdani system defuzzified other than by centroid: the constants are still centroids (convertToSugeno's
//   documented behaviour); the 2002 mam2sug.m applied the system's DefuzzMethod to each term instead.
// Errors (the system is then left unchanged): the system is not Mamdani; a term whose membership is zero over
// the whole output range (MATLAB: "Total area is zero in centroid"), which has no centroid.
// Returns one entry per converted output term, in order.
std::vector<ConvertedTerm> convert_mamdani_to_sugeno(FuzzySystem& system, DiagnosticList& diagnostics);

// The centroid of one membership function over [min, max], sampled at `samples` points (>= 2) as MATLAB does, or
// exactly when samples == 0. nullopt when the membership is zero everywhere on the range.
std::optional<double> membership_centroid(const MembershipFunction& mf, double min, double max, int samples);

// The crisp centroid (yl + yr) / 2 of an interval type-2 term over [min, max] sampled at `samples` points (101
// when 0), [yl, yr] from type reduction `method`. A term without a footprint gives its type-1 sampled centroid.
// nullopt when the upper membership is zero everywhere on the range.
std::optional<double> type2_term_centroid(const Term& term, double min, double max, int samples,
                                          TypeReduction method);

}  // namespace fmpc
