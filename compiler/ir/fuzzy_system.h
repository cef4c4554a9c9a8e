#pragma once
// The IR every stage shares: the frontends (fmpc language, MATLAB .fis) produce it, sema and lint check it, the
// passes transform it, the interpreter and the back ends consume it. Plain data, no behaviour beyond lookups.
#include <optional>
#include <string>
#include <vector>

#include "diagnostics/source_range.h"
#include "kernels/fuzzy_kinds.h"
#include "kernels/type2_math.h"
#include "kernels/type_reduction_math.h"

namespace fmpc {

enum class SystemType { Mamdani, Sugeno };

enum class Defuzzifier { Centroid, Bisector, MeanOfMaximum, SmallestOfMaximum, LargestOfMaximum, WeightedAverage,
                         WeightedSum };

// What a Mamdani output, or a Sugeno output with zero total firing, evaluates to when no rule fires.
enum class NoFirePolicy { Midrange, Value, Error };

enum class Connective { And, Or };

struct MembershipFunction {
  MfKind kind = MfKind::Triangle;
  std::vector<double> params;  // MATLAB order, see kernels/fuzzy_kinds.h
};

// An interval type-2 term's footprint of uncertainty (docs/language.md, "Interval type-2"). The kind and the
// meaning of `first`/`second` are kernels/type2_math.h's FootprintKind; `lower` is used by ExplicitLower only.
struct Footprint {
  FootprintKind kind = FootprintKind::ExplicitLower;
  double first = 0.0;   // UncertainMean: m1; UncertainSd: sd1; ScaleLag: scale; IntervalValue: low end
  double second = 0.0;  // UncertainMean: m2; UncertainSd: sd2; ScaleLag: lag;   IntervalValue: high end
  MembershipFunction lower;  // ExplicitLower: the lower MF (any input family)
  SourceRange range;         // the interval literal or the `lower ...` part
};

struct Term {
  std::string name;
  // Type-1 terms: the MF. Type-2 terms: the type-1 view used where one is needed (lint, plots, MATLAB's type-1
  // conversions): the upper MF for ExplicitLower and ScaleLag; the Gaussian or constant at the middle of the
  // interval for UncertainMean, UncertainSd and IntervalValue, whose interval is in the footprint.
  MembershipFunction mf;
  SourceRange range;  // the whole term definition
  SourceRange name_range;
  // Only in interval type-2 systems; absent = zero width (upper == lower == mf).
  std::optional<Footprint> footprint = std::nullopt;
};

struct Variable {
  std::string name;
  std::string description;
  std::string unit;  // empty when the source gave none (MATLAB files)
  double min = 0.0;
  double max = 1.0;
  std::vector<Term> terms;
  SourceRange range;  // the header line
  SourceRange name_range;

  // Index of the term called `term_name`, or -1.
  int find_term(const std::string& term_name) const;
};

// "VAR is [not] [hedge] TERM". The hedge applies first, then the negation (MATLAB and Octave order).
struct Clause {
  int variable = -1;  // index into inputs (antecedent) or outputs (consequent)
  int term = -1;      // index into that variable's terms
  bool negated = false;
  Hedge hedge = Hedge::None;
  SourceRange range;
};

struct Rule {
  std::string label;  // empty when the source gave none; diagnostics then say "rule N"
  Connective connective = Connective::And;
  std::vector<Clause> antecedent;  // at most one clause per input, in any order
  std::vector<Clause> consequent;  // at most one clause per output
  double weight = 1.0;
  // Set only by compiler/passes/specialize.h: the combined grade of the clauses on inputs that a binding fixed
  // and folded away. It joins the fold of the remaining clauses with the rule's connective (and_method for And,
  // or_method for Or) before them; with no clauses left it is the rule's strength. Never set by a reader.
  std::optional<double> folded_grade;
  // Interval type-2 systems only, set with folded_grade: the fold's state is an interval, folded_grade holds its
  // upper end and this its lower end (each end folded with the same norms, kernels/type2_math.h). The ends are
  // those of the fold, before the interpreter takes their span, so lower <= upper is not assumed.
  std::optional<double> folded_grade_lower;
  SourceRange range;
};

struct FuzzySystem {
  std::string name;
  std::string description;
  SystemType type = SystemType::Mamdani;
  bool interval_type2 = false;  // `type interval_type2 mamdani|sugeno`, MATLAB mamdanitype2 / sugenotype2
  TypeReduction type_reduction = TypeReduction::KarnikMendel;  // interval type-2 only
  TNorm and_method = TNorm::Minimum;
  SNorm or_method = SNorm::Maximum;
  TNorm implication = TNorm::Minimum;
  SNorm aggregation = SNorm::Maximum;
  Defuzzifier defuzzifier = Defuzzifier::Centroid;
  int samples = 101;  // output sampling points for Mamdani defuzzification; 0 = exact (analytic / adaptive)
  NoFirePolicy no_fire = NoFirePolicy::Midrange;
  double no_fire_value = 0.0;  // used when no_fire == Value
  std::vector<Variable> inputs;
  std::vector<Variable> outputs;
  std::vector<Rule> rules;
  SourceRange range;  // the "system" line or MATLAB's [System] section

  int find_input(const std::string& variable_name) const;
  int find_output(const std::string& variable_name) const;
  // "r7" when labelled, else "rule 7" (1-based), for messages.
  std::string rule_display_name(std::size_t rule_index) const;
};

// A file may hold several systems (the fmpc language allows it; MATLAB files hold one).
struct RuleFile {
  std::string path;
  std::vector<FuzzySystem> systems;
};

// Canonical spellings shared by the fmpc printer, the MATLAB writer, the CLI and messages.
const char* to_string(SystemType type);
const char* to_string(Defuzzifier defuzzifier);
const char* to_string(TNorm norm);   // "min", "prod", "einstein_product" (MATLAB spellings)
const char* to_string(SNorm norm);   // "max", "probor", "sum", "einstein_sum"
const char* to_string(Hedge hedge);  // "", "somewhat", "very", "extremely", "very very"
const char* matlab_name(MfKind kind);  // "trimf", ..., "constant", "linear"
std::optional<MfKind> mf_kind_from_matlab_name(const std::string& name);
std::optional<TNorm> tnorm_from_string(const std::string& name);
std::optional<SNorm> snorm_from_string(const std::string& name);
std::optional<Defuzzifier> defuzzifier_from_string(const std::string& name);
double hedge_exponent(Hedge hedge);  // 1, 0.5, 2, 3, 4
// "karnik_mendel", "enhanced_karnik_mendel", "eiasc", "nie_tan" (the fmpc language's spellings).
const char* to_string(TypeReduction method);
std::optional<TypeReduction> type_reduction_from_string(const std::string& name);

// Number of MATLAB parameters a kind takes; Linear takes (number of inputs + 1), reported here as -1.
int mf_param_count(MfKind kind);

}  // namespace fmpc
