#pragma once
// Defuzzification of a sampled Mamdani aggregate and of exactly known ones (`samples exact`). Used by the
// interpreter; exposed so that tests and other back ends can defuzzify hand-made sets the same way.
#include <cstddef>
#include <optional>
#include <vector>

#include "compiler/eval/interpreter.h"
#include "compiler/ir/fuzzy_system.h"
#include "kernels/fuzzy_kinds.h"

namespace fmpc {

// The sample points MATLAB uses for an output range: x_k = min + k (max - min) / (count - 1) (fis.c); Octave's
// linspace ends exactly on max. count >= 2.
std::vector<double> output_sample_points(double min, double max, int count, Reference reference);

// Defuzzifies the grades `grade` at the increasing points `x` with Mamdani defuzzifier `method` (centroid,
// bisector, mom, som, lom). nullopt when every grade is zero (MATLAB: "total area is zero"): the caller applies
// the no-fire policy. MATLAB: centroid = sum(x g) / sum(g); bisector = first x where the running sum of g reaches
// half the total; mom = mean of the maximising x; som / lom = the maximising x of smallest / largest magnitude
// (first one on ties). Octave: centroid = trapz(x, x g) / trapz(x, g); som / lom = smallest / largest maximising
// x (signed); bisector and mom as MATLAB (docs/numerics.md explains why Octave's bisector is not copied).
std::optional<double> defuzzify_sampled(Defuzzifier method, const std::vector<double>& x,
                                        const std::vector<double>& grade, Reference reference);

// One rule's contribution to an exact Mamdani aggregate: implication(firing, not?(hedge(mf(y)))).
struct ImpliedConsequent {
  MfKind kind = MfKind::Triangle;
  std::vector<double> params;
  double hedge_exponent = 1.0;
  bool negated = false;
  double firing = 0.0;
};

// The aggregated output set of one Mamdani output as a function of y on [min, max].
struct ExactAggregate {
  double min = 0.0;
  double max = 1.0;
  TNorm implication = TNorm::Minimum;
  SNorm aggregation = SNorm::Maximum;
  std::vector<ImpliedConsequent> rules;  // the rules that fired (firing > 0) with a consequent on this output

  double grade(double y) const;
  // True when the aggregate is piecewise linear in y and fmpc integrates it in closed form: every consequent is
  // trimf, trapmf, linsmf or linzmf without a hedge, implication min or prod, aggregation max or sum.
  bool piecewise_linear() const;
};

struct ExactIntegrals {
  double area = 0.0;    // integral of the aggregate over [min, max]
  double moment = 0.0;  // integral of y times the aggregate
  std::vector<double> points;  // the points the integration evaluated, sorted (for --explain)
};

// Closed form when piecewise_linear(), else adaptive Gauss-Kronrod (7/15) until the estimated error is below
// 1e-10 of the area and 1e-10 of max(|min|, |max|) times the area for the moment (docs/numerics.md).
ExactIntegrals integrate_exact(const ExactAggregate& aggregate);

// `samples exact` defuzzification: centroid = moment / area, bisector = the y halving the area, mom / som / lom on
// the exact pieces when piecewise linear and on 100001 samples otherwise. nullopt when the area is zero.
struct ExactDefuzzification {
  std::optional<double> value;
  std::vector<double> points;  // where the aggregate was evaluated, sorted
};
ExactDefuzzification defuzzify_exact(Defuzzifier method, const ExactAggregate& aggregate, Reference reference);

}  // namespace fmpc
