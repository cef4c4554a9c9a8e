#include "compiler/sema/check.h"

#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

std::string in_quotes(const std::string& name) { return "'" + name + "'"; }

std::string position_text(const SourceRange& range) {
  return std::to_string(range.line) + ":" + std::to_string(range.column);
}

// Names of each family's parameters in MATLAB order, as the messages call them.
std::vector<std::string> parameter_names(MfKind kind) {
  switch (kind) {
    case MfKind::Triangle: return {"a", "b", "c"};
    case MfKind::Trapezoid: return {"a", "b", "c", "d"};
    case MfKind::Gaussian: return {"sd", "mean"};
    case MfKind::Gaussian2: return {"sd1", "mean1", "sd2", "mean2"};
    case MfKind::GeneralizedBell: return {"a", "b", "c"};
    case MfKind::Sigmoid: return {"a", "c"};
    case MfKind::DifferenceSigmoid:
    case MfKind::ProductSigmoid: return {"a1", "c1", "a2", "c2"};
    case MfKind::ZShape:
    case MfKind::SShape:
    case MfKind::LinearS:
    case MfKind::LinearZ: return {"a", "b"};
    case MfKind::PiShape: return {"a", "b", "c", "d"};
    case MfKind::Constant: return {"c"};
    case MfKind::Linear: return {};
  }
  return {};
}

std::string joined(const std::vector<std::string>& words, const char* separator) {
  std::string text;
  for (std::size_t i = 0; i < words.size(); ++i) text += (i ? separator : "") + words[i];
  return text;
}

// "a 3, b 2, c 5": the parameters as the messages show them.
std::string named_values(MfKind kind, const std::vector<double>& params) {
  const std::vector<std::string> names = parameter_names(kind);
  std::vector<std::string> parts;
  for (std::size_t i = 0; i < names.size() && i < params.size(); ++i)
    parts.push_back(names[i] + " " + format_number(params[i]));
  return joined(parts, ", ");
}

bool is_sugeno_output_kind(MfKind kind) { return kind == MfKind::Constant || kind == MfKind::Linear; }

enum class Role { Input, Output };

const char* role_name(Role role) { return role == Role::Input ? "input" : "output"; }

class SystemChecker {
 public:
  SystemChecker(const FuzzySystem& system, const CheckOptions& options, DiagnosticList& diagnostics)
      : system_(system), options_(options), diagnostics_(diagnostics) {}

  void run() {
    check_settings();
    check_variable_names();
    for (const Variable& variable : system_.inputs) check_variable(variable, Role::Input);
    for (const Variable& variable : system_.outputs) check_variable(variable, Role::Output);
    for (std::size_t r = 0; r < system_.rules.size(); ++r) check_rule(r);
  }

 private:
  void check_settings() {
    const bool sugeno = system_.type == SystemType::Sugeno;
    const bool sugeno_defuzzifier = system_.defuzzifier == Defuzzifier::WeightedAverage ||
                                    system_.defuzzifier == Defuzzifier::WeightedSum;
    if (sugeno && !sugeno_defuzzifier)
      diagnostics_.error(system_.range, std::string("defuzzifier '") + to_string(system_.defuzzifier) +
                                            "' is for mamdani systems; a sugeno system uses 'wtaver' or 'wtsum'");
    if (!sugeno && sugeno_defuzzifier)
      diagnostics_.error(system_.range,
                         std::string("defuzzifier '") + to_string(system_.defuzzifier) +
                             "' is for sugeno systems; a mamdani system uses 'centroid', 'bisector', 'mom', 'som' "
                             "or 'lom'");
    if (system_.samples != 0 && system_.samples < 2)
      diagnostics_.error(system_.range, "samples is " + std::to_string(system_.samples) +
                                            "; use at least 2 output samples, or 'exact'");
    if (system_.outputs.empty())
      diagnostics_.error(system_.range, "system " + in_quotes(system_.name) + " has no output; add one");
    if (system_.interval_type2 && !sugeno && system_.defuzzifier != Defuzzifier::Centroid)
      diagnostics_.error(system_.range, std::string("defuzzifier '") + to_string(system_.defuzzifier) +
                                            "' has no interval type-2 form; an interval type-2 mamdani system "
                                            "type-reduces its centroid: use 'defuzzify centroid'");
    if (system_.interval_type2 && !sugeno && system_.samples == 0)
      diagnostics_.error(system_.range, "'samples exact' is not available for interval type-2 systems; type "
                                        "reduction works on sampled sets: give 'samples N' (101 is MATLAB's)");
    if (system_.no_fire == NoFirePolicy::Value) {
      if (!std::isfinite(system_.no_fire_value)) {
        diagnostics_.error(system_.range, "the value used when no rule fires is " +
                                              format_number(system_.no_fire_value) + "; give a finite number");
      } else {
        for (const Variable& output : system_.outputs) {
          if (!std::isfinite(output.min) || !std::isfinite(output.max) || output.min > output.max) continue;
          if (system_.no_fire_value < output.min || system_.no_fire_value > output.max)
            diagnostics_.warning(system_.range, "no-fire-out-of-range",
                                 "the value used when no rule fires, " + format_number(system_.no_fire_value) +
                                     ", lies outside the range [" + format_number(output.min) + ", " +
                                     format_number(output.max) + "] of output " + in_quotes(output.name) +
                                     "; pick a value inside it");
        }
      }
    }
  }

  void check_variable_names() {
    std::map<std::string, std::pair<Role, std::size_t>> first;
    auto visit = [&](const std::vector<Variable>& variables, Role role) {
      for (std::size_t i = 0; i < variables.size(); ++i) {
        const Variable& variable = variables[i];
        auto [it, inserted] = first.emplace(variable.name, std::make_pair(role, i));
        if (inserted) continue;
        const Variable& earlier =
            (it->second.first == Role::Input ? system_.inputs : system_.outputs)[it->second.second];
        const std::string note =
            earlier.name_range.valid()
                ? "first defined here: " + position_text(earlier.name_range)
                : std::string("first defined as ") + role_name(it->second.first) + " " +
                      std::to_string(it->second.second + 1);
        diagnostics_.error(variable.name_range,
                           "variable " + in_quotes(variable.name) +
                               " is defined twice (inputs and outputs share one namespace); rename one of them",
                           {note});
      }
    };
    visit(system_.inputs, Role::Input);
    visit(system_.outputs, Role::Output);
  }

  void check_variable(const Variable& variable, Role role) {
    const std::string name = role_name(role) + std::string(" ") + in_quotes(variable.name);
    const bool sugeno_output = role == Role::Output && system_.type == SystemType::Sugeno;
    if (!std::isfinite(variable.min) || !std::isfinite(variable.max)) {
      diagnostics_.error(variable.range, "the range [" + format_number(variable.min) + ", " +
                                             format_number(variable.max) + "] of " + name +
                                             " is not finite; give finite bounds");
    } else if (variable.min > variable.max) {
      diagnostics_.error(variable.range, "the range [" + format_number(variable.min) + ", " +
                                             format_number(variable.max) + "] of " + name +
                                             " is inverted; write the smaller bound first");
    } else if (variable.min == variable.max && !sugeno_output) {
      // A Sugeno output's range is never sampled, and MATLAB's own juggler.fis gives one as [0 0].
      diagnostics_.error(variable.range, "the range [" + format_number(variable.min) + ", " +
                                             format_number(variable.max) + "] of " + name +
                                             " is empty; the upper bound must be greater than the lower one");
    }

    std::map<std::string, std::size_t> first_term;
    for (std::size_t t = 0; t < variable.terms.size(); ++t) {
      const Term& term = variable.terms[t];
      auto [it, inserted] = first_term.emplace(term.name, t);
      if (!inserted) {
        const Term& earlier = variable.terms[it->second];
        const std::string note = earlier.name_range.valid()
                                     ? "first defined here: " + position_text(earlier.name_range)
                                     : "first defined as term " + std::to_string(it->second + 1);
        if (options_.terms_named_by_index)
          diagnostics_.warning(term.name_range, "duplicate-term",
                               "term " + in_quotes(term.name) + " is defined twice in " + name +
                                   "; rules refer to it by number here, but give each term its own name",
                               {note});
        else
          diagnostics_.error(term.name_range,
                             "term " + in_quotes(term.name) + " is defined twice in " + name + "; rename one of them",
                             {note});
      }
      check_term(variable, term, role);
    }
  }

  void check_term(const Variable& variable, const Term& term, Role role) {
    const MfKind kind = term.mf.kind;
    const std::vector<double>& params = term.mf.params;
    const std::string what = "term " + in_quotes(term.name) + " of " + in_quotes(variable.name);
    const char* kind_name = matlab_name(kind);

    if (role == Role::Input && is_sugeno_output_kind(kind)) {
      diagnostics_.error(term.range, what + " is '" + kind_name +
                                         "', which only a sugeno output can be; give the input a membership "
                                         "function such as 'trimf' or 'gaussmf'");
      return;
    }
    if (role == Role::Output && system_.type == SystemType::Sugeno && !is_sugeno_output_kind(kind)) {
      diagnostics_.error(term.range, what + " is '" + kind_name +
                                         "', but the outputs of a sugeno system are 'constant' or 'linear'; "
                                         "use one of those or make the system mamdani");
      return;
    }
    if (role == Role::Output && system_.type == SystemType::Mamdani && is_sugeno_output_kind(kind)) {
      diagnostics_.error(term.range, what + " is '" + kind_name +
                                         "', which only a sugeno output can be; use a membership function such "
                                         "as 'trimf' or 'gaussmf', or make the system sugeno");
      return;
    }

    if (kind == MfKind::Linear) {
      const std::size_t needed = system_.inputs.size() + 1;
      if (params.size() != needed) {
        diagnostics_.error(term.range, what + " is 'linear' with " + std::to_string(params.size()) +
                                           " coefficients; it needs " + std::to_string(needed) +
                                           " (one per input, in input order, then the constant)");
        return;
      }
    } else {
      const std::size_t needed = static_cast<std::size_t>(mf_param_count(kind));
      bool padding_only = params.size() >= needed;
      // MATLAB stores every row of parameters padded with zeros to the longest one ("trimf [0 1 2 0]").
      for (std::size_t i = needed; i < params.size(); ++i) padding_only = padding_only && params[i] == 0.0;
      if (!padding_only) {
        diagnostics_.error(term.range, what + " is '" + kind_name + "' with " + std::to_string(params.size()) +
                                           " parameters; it takes " + std::to_string(needed) + " (" +
                                           joined(parameter_names(kind), " ") + ")");
        return;
      }
    }

    for (std::size_t i = 0; i < params.size(); ++i) {
      if (std::isfinite(params[i])) continue;
      const std::vector<std::string> names = parameter_names(kind);
      const std::string parameter =
          i < names.size() ? "parameter " + names[i] : "coefficient " + std::to_string(i + 1);
      diagnostics_.error(term.range, parameter + " of " + what + " is " + format_number(params[i]) +
                                         "; parameters must be finite numbers");
      return;
    }
    check_parameter_domain(term, what);
    if (term.footprint) check_footprint(variable, term, role, what);
  }

  // docs/language.md, "Interval type-2": which footprint fits where, and its numbers.
  void check_footprint(const Variable& variable, const Term& term, Role role, const std::string& what) {
    const Footprint& footprint = *term.footprint;
    const SourceRange& where = footprint.range.valid() ? footprint.range : term.range;
    auto error = [&](const std::string& message) { diagnostics_.error(where, message); };
    if (!system_.interval_type2) {
      error(what + " has a footprint of uncertainty, but system " + in_quotes(system_.name) +
            " is type-1; declare `type interval_type2 " + to_string(system_.type) + "`");
      return;
    }
    const bool sugeno_output = role == Role::Output && system_.type == SystemType::Sugeno;
    if (sugeno_output != (footprint.kind == FootprintKind::IntervalValue)) {
      error(sugeno_output ? what + " is a sugeno consequent; its only footprint is an interval constant, "
                                   "constant(value [c1, c2])"
                          : what + " has an interval constant, which only a sugeno output term can have");
      return;
    }
    const std::string interval = "[" + format_number(footprint.first) + ", " + format_number(footprint.second) + "]";
    const bool finite = std::isfinite(footprint.first) && std::isfinite(footprint.second);
    switch (footprint.kind) {
      case FootprintKind::UncertainMean:
      case FootprintKind::UncertainSd:
      case FootprintKind::IntervalValue: {
        const bool gaussian = term.mf.kind == MfKind::Gaussian;
        if (footprint.kind != FootprintKind::IntervalValue && !gaussian) {
          error(what + " has an uncertain mean or sd, which only a gaussian can have");
          return;
        }
        const char* parameter = footprint.kind == FootprintKind::UncertainMean ? "mean"
                                : footprint.kind == FootprintKind::UncertainSd ? "sd"
                                                                              : "value";
        if (!finite) {
          error("the " + std::string(parameter) + " interval " + interval + " of " + what +
                " is not finite; give finite ends");
        } else if (footprint.first > footprint.second) {
          error("the " + std::string(parameter) + " interval " + interval + " of " + what +
                " is reversed; write the smaller end first");
        } else if (footprint.kind == FootprintKind::UncertainSd && !(footprint.first > 0.0)) {
          error("the sd interval " + interval + " of " + what + " reaches " + format_number(footprint.first) +
                "; both sds of a gaussian must be greater than 0");
        }
        break;
      }
      case FootprintKind::ScaleLag:
        if (!(footprint.first > 0.0 && footprint.first <= 1.0))
          error("the lower scale of " + what + " is " + format_number(footprint.first) +
                "; it is the height of the lower MF and lies in (0, 1]");
        if (!(footprint.second >= 0.0 && footprint.second < 1.0))
          error("the lower lag of " + what + " is " + format_number(footprint.second) +
                "; it is the upper grade where the lower MF starts rising and lies in [0, 1)");
        break;
      case FootprintKind::ExplicitLower: {
        Term lower;
        lower.name = term.name + " (lower MF)";
        lower.mf = footprint.lower;
        lower.range = where;
        lower.name_range = term.name_range;
        // The lower MF is a grade of x whatever the role, so it is checked as an input MF.
        check_term(variable, lower, Role::Input);
        break;
      }
      case FootprintKind::None: break;
    }
  }

  // MATLAB's own checks (fis.c: trimf/trapmf order, gaussmf/gauss2mf sigma != 0, gbellmf a != 0) plus the ones
  // that catch typos MATLAB evaluates silently: negative sds, reversed zmf/smf/pimf breakpoints.
  void check_parameter_domain(const Term& term, const std::string& what) {
    const MfKind kind = term.mf.kind;
    const std::vector<double>& p = term.mf.params;
    auto error = [&](const std::string& message) { diagnostics_.error(term.range, message); };
    auto ordered_message = [&](const char* order) {
      return "the parameters of " + what + " are out of order (" + named_values(kind, p) + "); '" +
             matlab_name(kind) + "' needs " + order;
    };
    switch (kind) {
      case MfKind::Triangle:
        if (!(p[0] <= p[1] && p[1] <= p[2])) error(ordered_message("a <= b <= c (feet a and c, peak b)"));
        break;
      case MfKind::Trapezoid:
        if (!(p[0] <= p[1] && p[1] <= p[2] && p[2] <= p[3]))
          error(ordered_message("a <= b <= c <= d (feet a and d, shoulders b and c)"));
        break;
      case MfKind::PiShape:
        if (!(p[0] <= p[1] && p[1] <= p[2] && p[2] <= p[3]))
          error(ordered_message("a <= b <= c <= d (feet a and d, shoulders b and c)"));
        break;
      case MfKind::Gaussian:
        if (!(p[0] > 0.0))
          error(what + " has sd " + format_number(p[0]) + "; the sd of a gaussian must be greater than 0");
        break;
      case MfKind::Gaussian2:
        if (!(p[0] > 0.0) || !(p[2] > 0.0))
          error(what + " has sd1 " + format_number(p[0]) + " and sd2 " + format_number(p[2]) +
                "; both sds of a 'gauss2mf' must be greater than 0");
        break;
      case MfKind::GeneralizedBell:
        if (p[0] == 0.0) error(what + " has width a 0; the width of a 'gbellmf' must not be 0");
        break;
      case MfKind::ZShape:
      case MfKind::SShape:
      case MfKind::LinearS:
      case MfKind::LinearZ:
        // a == b is a crisp step (MATLAB documents it for linsmf/linzmf and evaluates zmf/smf the same way);
        // a > b is almost always swapped breakpoints, which MATLAB would silently turn into a step.
        if (p[0] > p[1])
          error(ordered_message("a <= b (a == b for a crisp step)"));
        break;
      case MfKind::Sigmoid:
      case MfKind::DifferenceSigmoid:
      case MfKind::ProductSigmoid:
      case MfKind::Constant:
      case MfKind::Linear:
        break;
    }
  }

  void check_rule(std::size_t rule_index) {
    const Rule& rule = system_.rules[rule_index];
    const std::string name = system_.rule_display_name(rule_index);
    if (rule.antecedent.empty())
      diagnostics_.error(rule.range, name + " has no condition; give it at least one 'if INPUT is TERM'");
    if (rule.consequent.empty())
      diagnostics_.error(rule.range, name + " has no conclusion; give it at least one 'then OUTPUT is TERM'");
    if (!(rule.weight >= 0.0 && rule.weight <= 1.0))
      diagnostics_.error(rule.range, "the weight of " + name + " is " + format_number(rule.weight) +
                                         "; weights lie between 0 and 1");
    check_clauses(rule.antecedent, system_.inputs, Role::Input, name);
    check_clauses(rule.consequent, system_.outputs, Role::Output, name);
  }

  void check_clauses(const std::vector<Clause>& clauses, const std::vector<Variable>& variables, Role role,
                     const std::string& rule_name) {
    std::map<int, std::size_t> seen;
    for (std::size_t c = 0; c < clauses.size(); ++c) {
      const Clause& clause = clauses[c];
      if (clause.variable < 0 || static_cast<std::size_t>(clause.variable) >= variables.size()) {
        diagnostics_.error(clause.range, rule_name + " refers to " + role_name(role) + " number " +
                                             std::to_string(clause.variable + 1) + ", but the system has " +
                                             std::to_string(variables.size()) + " " + role_name(role) +
                                             (variables.size() == 1 ? "" : "s") + "; name an existing one");
        continue;
      }
      const Variable& variable = variables[static_cast<std::size_t>(clause.variable)];
      if (clause.term < 0 || static_cast<std::size_t>(clause.term) >= variable.terms.size()) {
        diagnostics_.error(clause.range, rule_name + " refers to term number " + std::to_string(clause.term + 1) +
                                             " of " + in_quotes(variable.name) + ", which has " +
                                             std::to_string(variable.terms.size()) + " term" +
                                             (variable.terms.size() == 1 ? "" : "s") + "; name an existing one");
      }
      auto [it, inserted] = seen.emplace(clause.variable, c);
      if (!inserted) {
        const SourceRange& earlier = clauses[it->second].range;
        std::vector<std::string> notes;
        if (earlier.valid()) notes.push_back("first mentioned here: " + position_text(earlier));
        diagnostics_.error(clause.range,
                           rule_name + " mentions " + in_quotes(variable.name) +
                               " twice; a rule takes one clause per variable, so split it into two rules",
                           notes);
      }
    }
  }

  const FuzzySystem& system_;
  const CheckOptions& options_;
  DiagnosticList& diagnostics_;
};

}  // namespace

void check_system(const FuzzySystem& system, DiagnosticList& diagnostics) {
  check_system(system, CheckOptions{}, diagnostics);
}

void check_system(const FuzzySystem& system, const CheckOptions& options, DiagnosticList& diagnostics) {
  SystemChecker(system, options, diagnostics).run();
}

}  // namespace fmpc
