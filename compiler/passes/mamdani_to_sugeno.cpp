#include "compiler/passes/mamdani_to_sugeno.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "compiler/eval/defuzzify.h"
#include "compiler/eval/interpreter.h"
#include "diagnostics/number_format.h"
#include "kernels/fuzzy_math.h"

namespace fmpc {

std::optional<double> membership_centroid(const MembershipFunction& mf, double min, double max, int samples) {
  if (samples == 0) {
    ExactAggregate single;
    single.min = min;
    single.max = max;
    single.rules.push_back({mf.kind, mf.params, 1.0, false, 1.0});
    return defuzzify_exact(Defuzzifier::Centroid, single, Reference::Matlab).value;
  }
  // MATLAB's linspace ends on max exactly, as Octave's does (output_sample_points' Octave flavour); the centroid
  // itself is MATLAB's defuzz: sum(x mf) / sum(mf).
  const std::vector<double> x = output_sample_points(min, max, samples, Reference::Octave);
  std::vector<double> grade(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) grade[k] = membership(mf.kind, mf.params.data(), x[k]);
  return defuzzify_sampled(Defuzzifier::Centroid, x, grade, Reference::Matlab);
}

std::optional<double> type2_term_centroid(const Term& term, double min, double max, int samples,
                                          TypeReduction method) {
  const int count = samples > 0 ? samples : 101;
  const std::vector<double> x = output_sample_points(min, max, count, Reference::Octave);
  std::vector<double> lower(x.size()), upper(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    const GradeInterval<double> mu = term_membership(term, x[k]);
    lower[k] = mu.lower;
    upper[k] = mu.upper;
  }
  const TypeReducedInterval<double> reduced =
      reduce_type(method, x.data(), lower.data(), upper.data(), static_cast<int>(x.size()));
  // KM and EKM end within N + 1 steps (kernels/type_reduction_math.h): the cap is a bug, never a centroid.
  if (reduced.iteration_cap_hit)
    throw std::logic_error("type reduction reached its iteration cap over " + std::to_string(x.size()) + " points");
  if (!reduced.fired) return std::nullopt;
  return (reduced.left + reduced.right) / 2.0;
}

std::vector<ConvertedTerm> convert_mamdani_to_sugeno(FuzzySystem& system, DiagnosticList& diagnostics) {
  std::vector<ConvertedTerm> converted;
  if (system.type != SystemType::Mamdani) {
    diagnostics.error(system.range, "system '" + system.name + "' is already a Sugeno system",
                      {"only Mamdani systems convert to Sugeno; use --to fmpc or --to matlab to change the format"});
    return converted;
  }
  const int samples = system.samples < 0 ? 101 : system.samples;
  bool failed = false;
  for (std::size_t o = 0; o < system.outputs.size(); ++o) {
    const Variable& output = system.outputs[o];
    for (std::size_t t = 0; t < output.terms.size(); ++t) {
      const Term& term = output.terms[t];
      const std::optional<double> centroid =
          system.interval_type2 && term.footprint
              ? type2_term_centroid(term, output.min, output.max, samples, system.type_reduction)
              : membership_centroid(term.mf, output.min, output.max, samples);
      if (!centroid || !std::isfinite(*centroid)) {
        diagnostics.error(term.range,
                          "output term '" + term.name + "' of '" + output.name + "' is zero over the whole range [" +
                              format_number(output.min) + ", " + format_number(output.max) +
                              "], so it has no centroid to become its Sugeno constant",
                          {"move the term inside the range or widen the range of '" + output.name + "'"});
        failed = true;
        continue;
      }
      converted.push_back({static_cast<int>(o), static_cast<int>(t), *centroid});
    }
  }
  if (failed) return {};
  if (system.defuzzifier != Defuzzifier::Centroid)
    diagnostics.warning(system.range, "sugeno-constants",
                        std::string("system '") + system.name + "' defuzzifies by " + to_string(system.defuzzifier) +
                            ", but the Sugeno constants are the centroids of the output terms",
                        {"this is convertToSugeno's behaviour; MATLAB's older mam2sug applied the system's "
                         "defuzzification method to each term instead"});
  for (const ConvertedTerm& c : converted) {
    MembershipFunction& mf =
        system.outputs[static_cast<std::size_t>(c.output)].terms[static_cast<std::size_t>(c.term)].mf;
    mf.kind = MfKind::Constant;
    mf.params = {c.constant};
    system.outputs[static_cast<std::size_t>(c.output)].terms[static_cast<std::size_t>(c.term)].footprint.reset();
  }
  system.type = SystemType::Sugeno;
  system.defuzzifier = Defuzzifier::WeightedAverage;
  system.implication = TNorm::Product;
  system.aggregation = SNorm::Sum;
  system.samples = 101;  // unused by Sugeno outputs; the default keeps the written file free of it
  return converted;
}

}  // namespace fmpc
