#pragma once
// A seeded generator of valid type-1 fuzzy systems for property, round-trip and differential tests.
// The same seed gives the same system on every platform: the generator draws from std::mt19937_64 (whose output
// the standard fixes) and maps the draws itself, never through std::*_distribution (implementation-defined).
//
// Every system it returns is valid for sema (compiler/sema/check.h): MF parameters in the order and domain each
// family needs (feet ascending, widths and sds > 0), Linear outputs with (inputs + 1) coefficients, at least one
// term per variable and at least one antecedent and consequent clause per rule, distinct variable names across
// inputs and outputs, distinct term names within a variable.
#include <cstdint>
#include <vector>

#include "compiler/ir/fuzzy_system.h"

namespace fmpc::testing {

struct RandomSystemOptions {
  bool mamdani = true;  // which system types may be drawn
  bool sugeno = true;

  int min_inputs = 1, max_inputs = 4;
  int min_outputs = 1, max_outputs = 3;
  int min_terms = 1, max_terms = 5;  // per variable
  int min_rules = 1, max_rules = 12;

  std::vector<MfKind> input_kinds;           // empty = every input family (trimf ... linzmf)
  std::vector<MfKind> mamdani_output_kinds;  // empty = every input family
  bool constant_outputs = true;              // Sugeno output terms; at least one of the two must be true
  bool linear_outputs = true;

  std::vector<TNorm> and_methods;          // empty = every TNorm
  std::vector<SNorm> or_methods;           // empty = every SNorm
  std::vector<TNorm> implication_methods;  // empty = every TNorm
  std::vector<SNorm> aggregation_methods;  // empty = every SNorm
  std::vector<Defuzzifier> mamdani_defuzzifiers;  // empty = centroid, bisector, mom, som, lom
  std::vector<Defuzzifier> sugeno_defuzzifiers;   // empty = wtaver, wtsum

  bool or_rules = true;        // rules joined by OR (otherwise every rule is AND)
  bool negation = true;        // "not" on antecedent clauses
  std::vector<Hedge> hedges;   // empty = every hedge; {Hedge::None} = no hedges
  bool consequent_negation = false;  // "not" / hedges on consequents: Octave's .fis allows them; off by default
  bool consequent_hedges = false;    // because fuzzylite and MATLAB have no meaning for them
  bool weights = true;         // weights other than 1
  bool dont_care = true;       // inputs left out of a rule (MATLAB's 0), outputs left out of a rule

  // fmpc-only features, off in the MATLAB and fuzzylite presets: what a .fis or FLL file cannot hold.
  bool descriptions_and_units = true;
  bool rule_labels = true;
  bool exact_samples = true;         // `samples exact` and sample counts other than 101
  bool no_fire_policies = true;      // `value X` and `error` besides MATLAB's midrange

  // Names with '-' and spaces ("F0-F1", "very low") as MATLAB files have; fuzzylite wants identifiers.
  bool names_with_dashes_and_spaces = true;

  // Interval type-2 (default off): `type interval_type2 ...`, a drawn type reduction, and footprints on most terms
  // (uncertain mean / sd on Gaussians, MATLAB scale and lag, explicit lower MFs lying under the upper ones,
  // interval constants on Sugeno outputs). Mamdani systems then defuzzify by centroid on 101 samples.
  bool interval_type2 = false;
  std::vector<TypeReduction> type_reductions;  // empty = every method

  // Decimal places of every generated number; negative = full double precision (tests bit-exact writers).
  int decimals = -1;

  // What a MATLAB .fis file holds, Octave's extensions included (hedges as rule fractions, Einstein norms):
  // no units, descriptions, labels, sample counts or no-fire policies.
  static RandomSystemOptions matlab_fis();
  // What MATLAB itself evaluates: matlab_fis() without hedges and Einstein norms.
  static RandomSystemOptions matlab();
  // What fuzzylite 6 expresses with the same meaning as MATLAB: identifier names, no hedges (fuzzylite's
  // "extremely" is not a power), no negated consequents, no fmpc-only features.
  static RandomSystemOptions fuzzylite();
};

// A valid system drawn from `seed`. Ranges, parameters and coefficients are finite; MF centres lie in the
// variable's range so that rules fire over most of the input space.
FuzzySystem random_system(std::uint64_t seed, const RandomSystemOptions& options = {});

// `count` input vectors for `system`, uniform over each input's [min, max], drawn from `seed`.
std::vector<std::vector<double>> random_inputs(const FuzzySystem& system, std::uint64_t seed, std::size_t count);

}  // namespace fmpc::testing
