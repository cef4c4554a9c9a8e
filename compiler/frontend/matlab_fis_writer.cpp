// MATLAB .fis writer: the version 2.0 layout of MATLAB's writefis (keys without spaces, MFs as
// MFk='name':'type',[params], rules as "a b, c (w) : k"), with hedges as Octave's rule fractions.
// Numbers go through format_number so that reading the file back gives the same bits.
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "compiler/frontend/matlab_fis.h"
#include "diagnostics/number_format.h"
#include "kernels/type2_math.h"

namespace fmpc {

namespace {

// MATLAB strings double a quote inside.
std::string matlab_string(const std::string& text) {
  std::string result = "'";
  for (char c : text) {
    result += c;
    if (c == '\'') result += '\'';
  }
  return result + "'";
}

std::string vector_text(const std::vector<double>& values) {
  std::string text = "[";
  for (std::size_t i = 0; i < values.size(); ++i) text += (i > 0 ? " " : "") + format_number(values[i]);
  return text + "]";
}

// Octave's rule-entry fractions (get_mf_index_and_hedge: round(100 * fraction) / 10 is the power).
const char* hedge_fraction(Hedge hedge) {
  switch (hedge) {
    case Hedge::None: return "";
    case Hedge::Somewhat: return ".05";
    case Hedge::Very: return ".2";
    case Hedge::Extremely: return ".3";
    case Hedge::VeryVery: return ".4";
  }
  return "";
}

std::string clause_entry(const Clause& clause) {
  return std::string(clause.negated ? "-" : "") + std::to_string(clause.term + 1) + hedge_fraction(clause.hedge);
}

// One column per variable: the clause on it, or 0.
std::string columns(const std::vector<Clause>& clauses, std::size_t variable_count) {
  std::vector<std::string> entries(variable_count, "0");
  for (const Clause& clause : clauses)
    if (clause.variable >= 0 && static_cast<std::size_t>(clause.variable) < variable_count)
      entries[static_cast<std::size_t>(clause.variable)] = clause_entry(clause);
  std::string text;
  for (std::size_t i = 0; i < entries.size(); ++i) text += (i > 0 ? " " : "") + entries[i];
  return text;
}

// The closest MATLAB footprint to a term's: LowerScale S in (0, 1] and LowerLag L in [0, 1), lower =
// S max(0, (upper - L) / (1 - L)) (kernels/type2_math.h), minimising the largest difference from the term's own
// lower MF over 201 points of the variable's range (grid search, S and L in steps of 0.01), ties to the larger S
// and the smaller L. The upper MF written is exactly the term's upper MF (writer's upper_mf).
struct ScaleLagFit {
  double scale = 1.0, lag = 0.0, largest_difference = 0.0;
};

ScaleLagFit fit_scale_lag(const Term& term, const Variable& variable) {
  constexpr int kPoints = 201, kSteps = 100;
  std::vector<double> upper(kPoints), lower(kPoints);
  for (int i = 0; i < kPoints; ++i) {
    const double x = variable.min + (variable.max - variable.min) * i / (kPoints - 1);
    const Footprint& f = *term.footprint;
    const GradeInterval<double> mu = footprint_membership(term.mf.kind, term.mf.params.data(), f.kind, f.first,
                                                          f.second, f.lower.kind, f.lower.params.data(), x);
    upper[static_cast<std::size_t>(i)] = mu.upper;
    lower[static_cast<std::size_t>(i)] = mu.lower;
  }
  ScaleLagFit best;
  best.largest_difference = std::numeric_limits<double>::infinity();
  for (int l = 0; l < kSteps; ++l) {
    const double lag = static_cast<double>(l) / kSteps;
    for (int k = kSteps; k >= 1; --k) {
      const double scale = static_cast<double>(k) / kSteps;
      double worst = 0.0;
      for (int i = 0; i < kPoints && worst < best.largest_difference; ++i) {
        const double raised = std::max(0.0, (upper[static_cast<std::size_t>(i)] - lag) / (1.0 - lag));
        worst = std::max(worst, std::fabs(scale * raised - lower[static_cast<std::size_t>(i)]));
      }
      if (worst < best.largest_difference) best = ScaleLagFit{scale, lag, worst};
    }
  }
  return best;
}

class Writer {
 public:
  Writer(const FuzzySystem& system, DiagnosticList& diagnostics) : system_(system), diagnostics_(diagnostics) {}

  std::string write() {
    report_what_matlab_cannot_hold();
    std::string out;
    out += "[System]\n";
    out += "Name=" + matlab_string(system_.name) + "\n";
    // A type-2 system is MATLAB's mamfistype2 / sugfistype2: Type stays 'mamdani' / 'sugeno' and the
    // TypeReductionMethod key, which only type-2 systems have, marks it (docs/matlab_fis.md).
    out += "Type=" + matlab_string(to_string(system_.type)) + "\n";
    out += "Version=2.0\n";
    out += "NumInputs=" + std::to_string(system_.inputs.size()) + "\n";
    out += "NumOutputs=" + std::to_string(system_.outputs.size()) + "\n";
    out += "NumRules=" + std::to_string(system_.rules.size()) + "\n";
    out += "AndMethod=" + matlab_string(to_string(system_.and_method)) + "\n";
    out += "OrMethod=" + matlab_string(to_string(system_.or_method)) + "\n";
    out += "ImpMethod=" + matlab_string(to_string(system_.implication)) + "\n";
    out += "AggMethod=" + matlab_string(to_string(system_.aggregation)) + "\n";
    out += "DefuzzMethod=" + matlab_string(to_string(system_.defuzzifier)) + "\n";
    if (system_.interval_type2)
      out += "TypeReductionMethod=" + matlab_string(matlab_type_reduction(system_.type_reduction)) + "\n";
    const bool type2 = system_.interval_type2;
    const bool sugeno = system_.type == SystemType::Sugeno;
    for (std::size_t i = 0; i < system_.inputs.size(); ++i) out += variable("Input", i + 1, system_.inputs[i], type2);
    for (std::size_t i = 0; i < system_.outputs.size(); ++i)
      out += variable("Output", i + 1, system_.outputs[i], type2 && !sugeno);
    out += "\n[Rules]\n";
    for (const Rule& rule : system_.rules) {
      out += columns(rule.antecedent, system_.inputs.size()) + ", " + columns(rule.consequent, system_.outputs.size());
      out += " (" + format_number(rule.weight) + ") : " + (rule.connective == Connective::And ? "1" : "2") + "\n";
    }
    return out;
  }

 private:
  // MATLAB's TypeReductionMethod names; Nie-Tan has none (reported by report_what_matlab_cannot_hold).
  static const char* matlab_type_reduction(TypeReduction method) {
    switch (method) {
      case TypeReduction::KarnikMendel: return "karnikmendel";
      case TypeReduction::EnhancedKarnikMendel: return "ekm";
      case TypeReduction::Eiasc: return "eiasc";
      case TypeReduction::NieTan: return "karnikmendel";
    }
    return "karnikmendel";
  }

  // `,LowerScale,[LowerLag LowerLag]` of a type-2 MF line: the footprint's own where it is MATLAB's, 1 and 0 for
  // zero width, else the closest MATLAB footprint (fit_scale_lag; reported by report_what_matlab_cannot_hold).
  static std::string lower_scale_lag(const Term& term, const Variable& variable) {
    double scale = 1.0, lag = 0.0;
    if (term.footprint && term.footprint->kind == FootprintKind::ScaleLag) {
      scale = term.footprint->first;
      lag = term.footprint->second;
    } else if (term.footprint && term.footprint->kind != FootprintKind::None) {
      const ScaleLagFit fit = fit_scale_lag(term, variable);
      scale = fit.scale;
      lag = fit.lag;
    }
    return "," + format_number(scale) + "," + vector_text({lag, lag});
  }

  // The MF a type-2 MF line names: MATLAB's upper MF.
  static MembershipFunction upper_mf(const Term& term) {
    if (!term.footprint) return term.mf;
    const Footprint& footprint = *term.footprint;
    switch (footprint.kind) {
      case FootprintKind::UncertainMean:
        return MembershipFunction{MfKind::Gaussian2,
                                  {term.mf.params[0], footprint.first, term.mf.params[0], footprint.second}};
      case FootprintKind::UncertainSd: return MembershipFunction{MfKind::Gaussian, {footprint.second, term.mf.params[1]}};
      case FootprintKind::None:
      case FootprintKind::ExplicitLower:
      case FootprintKind::ScaleLag:
      case FootprintKind::IntervalValue: break;
    }
    return term.mf;
  }

  static std::string variable(const char* section, std::size_t index, const Variable& variable, bool type2) {
    std::string out = "\n[" + std::string(section) + std::to_string(index) + "]\n";
    out += "Name=" + matlab_string(variable.name) + "\n";
    out += "Range=" + vector_text({variable.min, variable.max}) + "\n";
    out += "NumMFs=" + std::to_string(variable.terms.size()) + "\n";
    for (std::size_t k = 0; k < variable.terms.size(); ++k) {
      const Term& term = variable.terms[k];
      const MembershipFunction mf = type2 ? upper_mf(term) : term.mf;
      out += "MF" + std::to_string(k + 1) + "=" + matlab_string(term.name) + ":" + matlab_string(matlab_name(mf.kind)) +
             "," + vector_text(mf.params) + (type2 ? lower_scale_lag(term, variable) : "") + "\n";
    }
    return out;
  }

  SourceRange where(const SourceRange& range) const {
    if (range.valid() || !range.file.empty()) return range;
    return system_.range;
  }

  // What MATLAB's format drops without changing what fmpc computes from the file (names, units, descriptions,
  // Octave's spellings), and what changes the outputs when the file is read back (docs/matlab_fis.md, "Writing").
  void warn(const SourceRange& range, const std::string& message, std::vector<std::string> notes = {}) {
    diagnostics_.warning(where(range), kMatlabExport, message, std::move(notes));
  }
  void lose(const SourceRange& range, const std::string& message, std::vector<std::string> notes = {}) {
    diagnostics_.warning(where(range), kMatlabLossy, message, std::move(notes));
  }

  void report_what_matlab_cannot_hold() {
    const std::string system_name = "system '" + system_.name + "'";
    if (!system_.description.empty())
      warn(system_.range, "the description of " + system_name + " has no place in a .fis file and is dropped");
    if (system_.samples != 101)
      lose(system_.range,
           std::string("'samples ") + (system_.samples == 0 ? "exact" : std::to_string(system_.samples)) + "' of " +
               system_name + " is dropped: MATLAB always samples Mamdani outputs at 101 points");
    if (system_.no_fire == NoFirePolicy::Value)
      lose(system_.range, "the no-fire value " + format_number(system_.no_fire_value) + " of " + system_name +
                              " is dropped: MATLAB gives the middle of the output range when no rule fires");
    if (system_.no_fire == NoFirePolicy::Error)
      lose(system_.range, "the no-fire policy 'error' of " + system_name +
                              " is dropped: MATLAB gives the middle of the output range when no rule fires");
    const bool einstein = system_.and_method == TNorm::EinsteinProduct || system_.implication == TNorm::EinsteinProduct ||
                          system_.or_method == SNorm::EinsteinSum || system_.aggregation == SNorm::EinsteinSum;
    if (einstein)
      warn(system_.range, "Einstein norms of " + system_name +
                              " are written as Octave's einstein_product/einstein_sum, which MATLAB does not know");

    if (system_.interval_type2 && system_.type_reduction == TypeReduction::NieTan)
      lose(system_.range, "type reduction 'nie_tan' of " + system_name +
                              " has no MATLAB name and is written as 'karnikmendel'",
           {"MATLAB's TypeReductionMethod is karnikmendel, ekm, iasc or eiasc"});
    for (const auto* variables : {&system_.inputs, &system_.outputs}) {
      const char* role = variables == &system_.inputs ? "input" : "output";
      for (const Variable& variable : *variables) {
        for (const Term& term : variable.terms) {
          if (!term.footprint) continue;
          const FootprintKind kind = term.footprint->kind;
          const std::string what = "term '" + term.name + "' of " + role + " '" + variable.name + "'";
          if (kind == FootprintKind::IntervalValue) {
            lose(term.range, "the interval constant of " + what + " has no MATLAB form (sugenotype2 outputs are "
                                                                  "type-1); its midpoint is written");
          } else if (kind != FootprintKind::ScaleLag && kind != FootprintKind::None) {
            const ScaleLagFit fit = fit_scale_lag(term, variable);
            if (fit.largest_difference > 0.0)
              lose(term.range, "the footprint of " + what + " has no MATLAB form (MATLAB's lower MF is the upper one "
                                                          "scaled and lagged); it is written as its upper MF with "
                                                          "LowerScale " +
                                 format_number(fit.scale) + " and LowerLag " + format_number(fit.lag) +
                                 ", whose lower MF is up to " + format_number(fit.largest_difference) +
                                 " from the original's");
          }
        }
        if (!variable.unit.empty()) {
          // Scenes read a unit-less output as kPa (docs/scenes.md): an output in Pa or MPa would change E.
          const bool changes_modulus = variables == &system_.outputs && (variable.unit == "Pa" || variable.unit == "MPa");
          if (changes_modulus)
            lose(variable.range, std::string("the unit '") + variable.unit + "' of output '" + variable.name +
                                     "' has no place in a .fis file and is dropped; a scene reads an output "
                                     "without a unit as kPa, " +
                                     (variable.unit == "Pa" ? "1000 times" : "1000 times less than") +
                                     " its value in " + variable.unit);
          else
            warn(variable.range, std::string("the unit '") + variable.unit + "' of " + role + " '" + variable.name +
                                     "' has no place in a .fis file and is dropped");
        }
        if (!variable.description.empty())
          warn(variable.range, std::string("the description of ") + role + " '" + variable.name +
                                   "' has no place in a .fis file and is dropped");
      }
    }

    std::size_t labels = 0;
    std::size_t hedges = 0;
    for (std::size_t r = 0; r < system_.rules.size(); ++r) {
      const Rule& rule = system_.rules[r];
      if (!rule.label.empty()) ++labels;
      for (const auto* clauses : {&rule.antecedent, &rule.consequent})
        for (const Clause& clause : *clauses)
          if (clause.hedge != Hedge::None) ++hedges;
      if (rule.antecedent.empty())
        lose(rule.range, system_.rule_display_name(r) + " has no antecedent; MATLAB (and fmpc) reject a rule whose "
                                                        "inputs are all 0");
      if (system_.type == SystemType::Sugeno)
        for (const Clause& clause : rule.consequent)
          if (clause.negated)
            warn(clause.range, system_.rule_display_name(r) + " negates a Sugeno consequent; MATLAB rejects it and "
                                                              "Octave uses 1 - firing strength");
    }
    if (labels > 0)
      warn(system_.range, "rule labels of " + system_name + " have no place in a .fis file and are dropped",
           {"MATLAB numbers rules from 1 in the order written"});
    if (hedges > 0)
      warn(system_.range, "hedges of " + system_name + " are written as Octave's rule fractions (.05 somewhat, "
                                                       ".2 very, .3 extremely, .4 very very); MATLAB ignores them");
  }

  const FuzzySystem& system_;
  DiagnosticList& diagnostics_;
};

}  // namespace

std::string write_matlab_fis(const FuzzySystem& system, DiagnosticList& diagnostics) {
  return Writer(system, diagnostics).write();
}

}  // namespace fmpc
