// ast::File -> RuleFile: settings with MATLAB's defaults, named MF arguments in MATLAB order, unit conversion,
// and name resolution in rules with "did you mean". Validity of the values themselves is check_system's.
#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include "compiler/frontend/fmpc_ast.h"
#include "compiler/frontend/fmpc_language.h"
#include "compiler/ir/system_names.h"
#include "compiler/ir/units.h"
#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

using ast::Argument;
using ast::ConnectiveToken;
using ast::FamilySignature;
using ast::File;
using ast::Item;
using ast::Name;
using ast::Setting;
using ast::SettingKind;
using ast::System;

std::string in_quotes(const std::string& text) { return "'" + text + "'"; }

std::string position_text(const SourceRange& range) {
  return std::to_string(range.line) + ":" + std::to_string(range.column);
}

std::string list_text(const std::vector<std::string>& names) {
  std::string text;
  for (std::size_t i = 0; i < names.size(); ++i) text += (i ? ", " : "") + names[i];
  return text;
}

std::vector<std::string> names_of(const std::vector<const char*>& names) {
  return std::vector<std::string>(names.begin(), names.end());
}

std::string join_words(const std::vector<const char*>& words) {
  std::string text;
  for (std::size_t i = 0; i < words.size(); ++i) text += (i ? " " : "") + std::string(words[i]);
  return text;
}

std::vector<std::string> did_you_mean(const std::string& name, const std::vector<std::string>& candidates) {
  if (auto suggestion = closest_name(name, candidates)) return {"did you mean " + in_quotes(*suggestion) + "?"};
  return {};
}

class SystemLowering {
 public:
  SystemLowering(const File& file, std::size_t system_index, DiagnosticList& diagnostics)
      : file_(file), source_(file.systems[system_index]), diagnostics_(diagnostics) {}

  FuzzySystem lower() {
    system_.name = source_.name.text;
    system_.description = source_.description.value_or("");
    system_.range = source_.range;
    lower_settings();
    settings_failed_ = diagnostics_.has_errors();
    for (const Item& item : source_.items)
      if (const auto* variable = std::get_if<ast::Variable>(&item)) lower_variable_header(*variable);
    names_.emplace(system_);  // the variables, for linear(...) coefficients
    std::size_t input_index = 0, output_index = 0;
    std::vector<std::pair<fmpc::Variable*, std::size_t>> failed_terms;
    for (const Item& item : source_.items) {
      const auto* variable = std::get_if<ast::Variable>(&item);
      if (!variable) continue;
      fmpc::Variable& target = variable->is_output ? system_.outputs[output_index++] : system_.inputs[input_index++];
      for (const ast::Term& term : variable->terms) {
        const std::size_t errors_before = diagnostics_.error_count();
        target.terms.push_back(lower_term(term, target));
        if (diagnostics_.error_count() > errors_before) failed_terms.emplace_back(&target, target.terms.size() - 1);
      }
    }
    names_.emplace(system_);  // and their terms, for the rules
    for (const Item& item : source_.items)
      if (const auto* rule = std::get_if<ast::Rule>(&item)) {
        const std::size_t errors_before = diagnostics_.error_count();
        lower_rule(*rule);
        if (diagnostics_.error_count() > errors_before) failed_rules_.push_back(system_.rules.size() - 1);
      }
    // So that check_system can still report every parameter error of the file in the same run (all errors at
    // once) without echoing the ones reported here: a term that failed gets a harmless shape and a rule that
    // failed is dropped. A system with errors is never evaluated, so the stand-ins never reach a number.
    for (auto [variable, term] : failed_terms) {
      fmpc::MembershipFunction& mf = variable->terms[term].mf;
      const double mid = 0.5 * (variable->min + variable->max);
      const bool sugeno_output = system_.type == SystemType::Sugeno &&
                                 variable >= system_.outputs.data() &&
                                 variable < system_.outputs.data() + system_.outputs.size();
      mf = sugeno_output ? fmpc::MembershipFunction{MfKind::Constant, {mid}}
                         : fmpc::MembershipFunction{MfKind::Triangle, {variable->min, mid, variable->max}};
    }
    for (auto it = failed_rules_.rbegin(); it != failed_rules_.rend(); ++it)
      system_.rules.erase(system_.rules.begin() + static_cast<std::ptrdiff_t>(*it));
    return system_;
  }

  // A misspelt type or operator makes every later check suspect (a Sugeno output in what now reads as a Mamdani
  // system), so such a system is not handed to check_system at all.
  bool settings_failed() const { return settings_failed_; }

 private:
  // --- settings ------------------------------------------------------------------------------------------------

  static const char* setting_name(SettingKind kind) {
    switch (kind) {
      case SettingKind::Type: return "type";
      case SettingKind::And: return "and";
      case SettingKind::Or: return "or";
      case SettingKind::Implication: return "implication";
      case SettingKind::Aggregation: return "aggregation";
      case SettingKind::Defuzzify: return "defuzzify";
      case SettingKind::NoFire: return "when no rule fires";
      case SettingKind::TypeReduction: return "type_reduction";
    }
    return "?";
  }

  void lower_settings() {
    std::map<SettingKind, SourceRange> first_set;
    for (const Setting& setting : source_.settings) {
      auto [it, inserted] = first_set.emplace(setting.kind, setting.range);
      if (!inserted)
        diagnostics_.error(setting.range,
                           in_quotes(setting_name(setting.kind)) + " is set twice in system " +
                               in_quotes(system_.name) + "; keep one",
                           {"first set here: " + position_text(it->second)});
    }
    for (const Setting& setting : source_.settings)
      if (setting.kind == SettingKind::Type) lower_type(setting);
    if (system_.type == SystemType::Sugeno) {
      // MATLAB's sugfis defaults.
      system_.and_method = TNorm::Product;
      system_.or_method = SNorm::ProbabilisticSum;
      system_.implication = TNorm::Product;
      system_.aggregation = SNorm::Sum;
      system_.defuzzifier = Defuzzifier::WeightedAverage;
    }
    for (const Setting& setting : source_.settings) {
      switch (setting.kind) {
        case SettingKind::Type: break;
        case SettingKind::And: lower_tnorm(setting, system_.and_method); break;
        case SettingKind::Implication: lower_tnorm(setting, system_.implication); break;
        case SettingKind::Or: lower_snorm(setting, system_.or_method); break;
        case SettingKind::Aggregation: lower_snorm(setting, system_.aggregation); break;
        case SettingKind::Defuzzify: lower_defuzzify(setting); break;
        case SettingKind::NoFire: lower_no_fire(setting); break;
        case SettingKind::TypeReduction: lower_type_reduction(setting); break;
      }
    }
  }

  void unknown_choice(const Setting& setting, const std::string& what, const std::vector<std::string>& choices) {
    std::vector<std::string> notes = did_you_mean(setting.value.text, choices);
    notes.push_back("choose one of: " + list_text(choices));
    std::string message = "unknown " + what + " " + in_quotes(setting.value.text);
    if (setting.kind != SettingKind::Type && setting.kind != SettingKind::Defuzzify)
      message += std::string(" for ") + in_quotes(setting_name(setting.kind));
    diagnostics_.error(setting.value.range, message, notes);
  }

  void lower_type(const Setting& setting) {
    system_.interval_type2 = setting.interval_type2;
    if (setting.value.text == "mamdani") system_.type = SystemType::Mamdani;
    else if (setting.value.text == "sugeno") system_.type = SystemType::Sugeno;
    else unknown_choice(setting, "system type", {"mamdani", "sugeno"});
  }

  void lower_type_reduction(const Setting& setting) {
    const std::vector<std::string> choices = {"karnik_mendel", "enhanced_karnik_mendel", "eiasc", "nie_tan"};
    if (auto method = type_reduction_from_string(setting.value.text)) system_.type_reduction = *method;
    else unknown_choice(setting, "type reduction", choices);
    if (!system_.interval_type2)
      diagnostics_.error(setting.range,
                         "'type_reduction' applies to interval type-2 systems only; declare `type interval_type2 " +
                             std::string(to_string(system_.type)) + "` or remove this line");
  }

  void lower_tnorm(const Setting& setting, TNorm& target) {
    if (auto norm = tnorm_from_string(setting.value.text)) target = *norm;
    else unknown_choice(setting, "t-norm", {"min", "prod", "einstein_product"});
  }

  void lower_snorm(const Setting& setting, SNorm& target) {
    if (auto norm = snorm_from_string(setting.value.text)) target = *norm;
    else unknown_choice(setting, "s-norm", {"max", "probor", "sum", "einstein_sum"});
  }

  void lower_defuzzify(const Setting& setting) {
    if (auto defuzzifier = defuzzifier_from_string(setting.value.text)) system_.defuzzifier = *defuzzifier;
    else unknown_choice(setting, "defuzzifier", {"centroid", "bisector", "mom", "som", "lom", "wtaver", "wtsum"});
    if (setting.samples_exact) {
      system_.samples = 0;
    } else if (setting.samples) {
      const double count = setting.samples->value;
      if (count != std::floor(count) || count < 2.0 || count > 100000000.0) {
        diagnostics_.error(setting.samples->range,
                           "samples must be a whole number from 2 to 100000000, or 'exact' for the exact centroid");
      } else {
        system_.samples = static_cast<int>(count);
      }
    }
  }

  void lower_no_fire(const Setting& setting) {
    if (setting.value.text == "midrange") {
      system_.no_fire = NoFirePolicy::Midrange;
    } else if (setting.value.text == "error") {
      system_.no_fire = NoFirePolicy::Error;
    } else {
      system_.no_fire = NoFirePolicy::Value;
      system_.no_fire_value = setting.no_fire_value ? setting.no_fire_value->value : 0.0;
    }
  }

  // --- variables and terms ------------------------------------------------------------------------------------

  void lower_variable_header(const ast::Variable& source) {
    fmpc::Variable variable;
    variable.name = source.name.text;
    variable.description = source.description.value_or("");
    variable.unit = source.unit ? source.unit->text : "";
    variable.min = source.min.value;
    variable.max = source.max.value;
    variable.range = source.range;
    variable.name_range = source.name.range;
    (source.is_output ? system_.outputs : system_.inputs).push_back(std::move(variable));
  }

  // `value` given in `unit` (when present), in the unit of `variable`; nullopt after reporting why not.
  std::optional<double> in_variable_unit(double value, const std::optional<Name>& unit, const std::string& parameter,
                                         const fmpc::Variable& variable) {
    if (!unit || unit->text == variable.unit) return value;
    const std::string what = in_quotes(unit->text) + " given for " + in_quotes(parameter);
    if (variable.unit.empty()) {
      diagnostics_.error(unit->range, what + ", but " + in_quotes(variable.name) + " has no unit",
                         {"give " + in_quotes(variable.name) + " a unit after its range (in [" +
                          format_number(variable.min) + ", " + format_number(variable.max) + "] " + unit->text +
                          ") or drop this one"});
      return std::nullopt;
    }
    const std::optional<UnitMeaning> from = unit_meaning(unit->text);
    const std::optional<UnitMeaning> to = unit_meaning(variable.unit);
    const std::string known = "fmpc converts Pa, m, s, N and g with SI prefixes (kPa, mm, ms, ...), % and "
                              "dimensionless";
    if (!from) {
      diagnostics_.error(unit->range, "unknown unit " + in_quotes(unit->text) + " for " + in_quotes(parameter) + "; " +
                                          in_quotes(variable.name) + " is in " + in_quotes(variable.unit),
                         {known});
      return std::nullopt;
    }
    if (!to) {
      diagnostics_.error(unit->range,
                         "unit " + in_quotes(unit->text) + " of " + in_quotes(parameter) + " does not convert to " +
                             in_quotes(variable.unit) + ", the unit of " + in_quotes(variable.name),
                         {known + "; write the value in " + variable.unit});
      return std::nullopt;
    }
    if (std::string(from->dimension) != to->dimension) {
      diagnostics_.error(unit->range, "unit " + in_quotes(unit->text) + " (" + from->dimension + ") of " +
                                          in_quotes(parameter) + " does not convert to " + in_quotes(variable.unit) +
                                          " (" + to->dimension + "), the unit of " + in_quotes(variable.name));
      return std::nullopt;
    }
    return scale_by_power_of_ten(value, from->exponent - to->exponent);
  }

  fmpc::Term lower_term(const ast::Term& source, const fmpc::Variable& variable) {
    fmpc::Term term;
    term.name = source.name.text;
    term.range = source.range;
    term.name_range = source.name.range;
    const FamilySignature* family = resolve_family(source.family);
    if (!family) return term;
    if (refuse_matlab_parameters(source.family, source.arguments, *family, source.call_range)) return term;
    term.mf.kind = family->kind;
    if (family->kind == MfKind::Linear) lower_linear(source.arguments, variable, term.mf);
    else lower_named_parameters(source, source.family, source.arguments, *family, variable, term.mf, &term);
    lower_footprint(source, variable, term);
    return term;
  }

  // `upper F(...) lower G(...)` and `lower scale S lag L`; intervals are lowered with the named parameters.
  void lower_footprint(const ast::Term& source, const fmpc::Variable& variable, fmpc::Term& term) {
    const bool has_lower = source.lower || source.lower_scale || source.lower_lag;
    if (!system_.interval_type2) {
      SourceRange where = source.lower_range;
      if (!has_lower && source.explicit_upper) where = source.family.range;
      for (const Argument& argument : source.arguments)
        if (argument.high && !has_lower) where = argument.range;
      if (has_lower || source.explicit_upper || term.footprint)
        diagnostics_.error(where,
                           "term " + in_quotes(source.name.text) + " has a footprint of uncertainty, but system " +
                               in_quotes(system_.name) + " is type-1; declare `type interval_type2 " +
                               to_string(system_.type) + "` to use interval type-2 terms");
      term.footprint.reset();
      return;
    }
    if (!has_lower) return;
    if (term.footprint) {
      diagnostics_.error(source.lower_range, "term " + in_quotes(source.name.text) +
                                                 " has an interval parameter and a lower MF; give one footprint: "
                                                 "an interval, or `upper F(...) lower G(...)`, or `lower scale S lag L`");
      return;
    }
    Footprint footprint;
    footprint.range = source.lower_range;
    if (source.lower) {
      footprint.kind = FootprintKind::ExplicitLower;
      const FamilySignature* family = ast::find_family_or_alias(source.lower->family.text);
      if (!family || family->kind == MfKind::Linear || family->kind == MfKind::Constant) {
        std::vector<std::string> notes = did_you_mean(source.lower->family.text, ast::family_names());
        notes.push_back("a lower MF is one of the input families: triangle, trapezoid, gauss, ...");
        diagnostics_.error(source.lower->family.range,
                           (family ? "'" + source.lower->family.text + "' cannot be a lower MF"
                                   : "unknown membership function " + in_quotes(source.lower->family.text)),
                           notes);
        return;
      }
      if (refuse_matlab_parameters(source.lower->family, source.lower->arguments, *family, source.lower->range)) return;
      footprint.lower.kind = family->kind;
      lower_named_parameters(source, source.lower->family, source.lower->arguments, *family, variable,
                             footprint.lower, nullptr);
    } else {
      footprint.kind = FootprintKind::ScaleLag;
      footprint.first = source.lower_scale ? source.lower_scale->value : 1.0;
      footprint.second = source.lower_lag ? source.lower_lag->value : 0.0;
    }
    term.footprint = footprint;
  }

  // The family named `name`: fmpc's, or MATLAB's name for it (`trimf` is `triangle`: docs/language.md, "MATLAB's
  // names"); nullptr after reporting an unknown name.
  const FamilySignature* resolve_family(const Name& name) {
    if (const FamilySignature* family = ast::find_family_or_alias(name.text)) return family;
    std::vector<std::string> candidates = ast::family_names();
    for (const std::string& alias : ast::matlab_family_names()) candidates.push_back(alias);
    std::vector<std::string> notes = did_you_mean(name.text, candidates);
    notes.push_back("membership functions: " + list_text(ast::family_names()));
    notes.push_back("MATLAB's names are accepted too: " + list_text(ast::matlab_family_names()));
    diagnostics_.error(name.range, "unknown membership function " + in_quotes(name.text), notes);
    return nullptr;
  }

  // MATLAB's spellings of parameters are refused with fmpc's (fmpc names them so that nobody confuses MATLAB's
  // [sigma c] order): positional values, `gaussmf(0.91, 7.64)` or `gaussmf [0.91 7.64]`, and MATLAB's own names,
  // `gaussmf(sigma 0.91, c 7.64)`. Positional values under a MATLAB name and MATLAB's names under any name have one
  // meaning, so the message spells the call out with fmpc's names and offers it as a fix-it; positional values
  // under an fmpc name imply no order and none is guessed. True after reporting.
  bool refuse_matlab_parameters(const Name& family_name, const std::vector<Argument>& arguments,
                                const FamilySignature& family, const SourceRange& call_range) {
    if (family.kind == MfKind::Linear) {
      for (const Argument& argument : arguments) {
        if (argument.name.text.empty() && !argument.name.quoted) {
          diagnostics_.error(argument.range, "the coefficients of linear(...) are named by input: "
                                             "linear(INPUT VALUE, ..., offset VALUE)");
          return true;
        }
      }
      return false;
    }
    std::size_t positional = 0, matlab_named = 0;
    for (const Argument& argument : arguments) {
      if (argument.name.text.empty() && !argument.name.quoted) ++positional;
      else if (matlab_position(family, argument.name.text)) ++matlab_named;
    }
    if (positional == 0 && (matlab_named == 0 || matlab_named != arguments.size())) return false;
    const std::string matlab_form = std::string(matlab_name(family.kind)) + " [" +
                                    join_words(family.matlab_parameters) + "]";
    std::vector<std::string> mapping;
    for (std::size_t i = 0; i < family.parameters.size(); ++i)
      mapping.push_back(std::string(family.parameters[i]) + " " +
                        family.matlab_parameters[static_cast<std::size_t>(family.matlab_index[i])]);
    const std::string mapping_note = "MATLAB's " + matlab_form + " is " + family.name + "(" + list_text(mapping) + ")";
    // The argument at each of MATLAB's positions, when the call has one meaning.
    std::vector<const Argument*> at(family.parameters.size(), nullptr);
    bool one_meaning = arguments.size() == family.parameters.size();
    for (std::size_t k = 0; k < arguments.size() && one_meaning; ++k) {
      const Argument& argument = arguments[k];
      std::optional<std::size_t> position = positional > 0 ? std::optional<std::size_t>(k)
                                                           : matlab_position(family, argument.name.text);
      one_meaning = !argument.high && position && *position < at.size() && !at[*position];
      if (one_meaning) at[*position] = &argument;
    }
    if (positional > 0) one_meaning = one_meaning && positional == arguments.size() && ast::find_matlab_family(family_name.text);
    if (!one_meaning) {
      std::vector<std::string> named;
      for (const char* parameter : family.parameters) named.push_back(std::string(parameter) + " VALUE");
      std::vector<std::string> notes{std::string(family.name) + " takes: " + list_text(names_of(family.parameters))};
      if (ast::find_matlab_family(family_name.text) || positional == 0) notes.push_back(mapping_note);
      diagnostics_.error(positional > 0 ? first_positional(arguments) : family_name.range,
                         "parameters are named in fmpc: write " + std::string(family.name) + "(" + list_text(named) +
                             ")",
                         notes);
      return true;
    }
    std::vector<std::string> parts;
    for (std::size_t i = 0; i < family.parameters.size(); ++i) {
      const Argument& argument = *at[static_cast<std::size_t>(family.matlab_index[i])];
      std::string part = std::string(family.parameters[i]) + " " + format_number(argument.value.value);
      if (argument.unit) part += " " + argument.unit->text;
      parts.push_back(part);
    }
    const std::string call = std::string(family.name) + "(" + list_text(parts) + ")";
    Diagnostic diagnostic;
    diagnostic.range = call_range;
    diagnostic.message = (positional > 0 ? "parameters are named in fmpc: write "
                                         : "these are MATLAB's parameter names; in fmpc write ") + call;
    diagnostic.notes.push_back(mapping_note);
    diagnostic.fix = FixIt{call_range, call};
    diagnostics_.add(std::move(diagnostic));
    return true;
  }

  // The position of MATLAB's parameter `name` in MATLAB's params vector of `family` (gaussmf: sigma 0, c 1), unless
  // `name` is also one of fmpc's names for the family.
  static std::optional<std::size_t> matlab_position(const FamilySignature& family, const std::string& name) {
    for (const char* parameter : family.parameters)
      if (name == parameter) return std::nullopt;
    for (std::size_t k = 0; k < family.matlab_parameters.size(); ++k)
      if (name == family.matlab_parameters[k]) return k;
    return std::nullopt;
  }

  static SourceRange first_positional(const std::vector<Argument>& arguments) {
    for (const Argument& argument : arguments)
      if (argument.name.text.empty() && !argument.name.quoted) return argument.range;
    return SourceRange{};
  }

  // `term` receives the footprint of an interval argument; null where intervals are not allowed (a lower MF).
  void lower_named_parameters(const ast::Term& source, const Name& family_name,
                              const std::vector<Argument>& arguments, const FamilySignature& family,
                              const fmpc::Variable& variable, MembershipFunction& mf, fmpc::Term* term) {
    const std::vector<std::string> names(family.parameters.begin(), family.parameters.end());
    const std::string takes = std::string(family.name) + " takes: " + list_text(names);
    mf.params.assign(names.size(), 0.0);
    std::vector<const Argument*> given(names.size(), nullptr);
    for (const Argument& argument : arguments) {
      const auto found = std::find(names.begin(), names.end(), argument.name.text);
      if (found == names.end()) {
        std::vector<std::string> notes = did_you_mean(argument.name.text, names);
        // MATLAB's own name for the parameter (gaussmf's sigma): say which fmpc name it is.
        for (std::size_t i = 0; i < names.size(); ++i) {
          const auto position = static_cast<std::size_t>(family.matlab_index[i]);
          if (position < family.matlab_parameters.size() && argument.name.text == family.matlab_parameters[position])
            notes = {"MATLAB's " + std::string(matlab_name(family.kind)) + " calls it " + argument.name.text +
                     "; fmpc calls it " + in_quotes(names[i])};
        }
        notes.push_back(takes);
        diagnostics_.error(argument.name.range,
                           in_quotes(family.name) + " has no parameter " + in_quotes(argument.name.text), notes);
        continue;
      }
      const auto index = static_cast<std::size_t>(found - names.begin());
      if (given[index]) {
        diagnostics_.error(argument.name.range, "parameter " + in_quotes(argument.name.text) + " is given twice",
                           {"first given here: " + position_text(given[index]->name.range)});
        continue;
      }
      given[index] = &argument;
      if (argument.unit && !family.takes_unit[index]) {
        diagnostics_.error(argument.unit->range,
                           in_quotes(argument.name.text) + " of " + family.name + " takes no unit (it is per unit of " +
                               in_quotes(variable.name) + "); remove " + in_quotes(argument.unit->text));
        continue;
      }
      std::optional<double> value = in_variable_unit(argument.value.value, argument.unit, argument.name.text, variable);
      if (argument.high && value) {
        const std::optional<double> high =
            in_variable_unit(argument.high->value, argument.unit, argument.name.text, variable);
        if (!high) continue;
        if (lower_interval(argument, family, *value, *high, term)) value = 0.5 * (*value + *high);
        else continue;
      }
      if (value) mf.params[static_cast<std::size_t>(family.matlab_index[index])] = *value;
    }
    std::vector<std::string> missing;
    for (std::size_t i = 0; i < names.size(); ++i)
      if (!given[i]) missing.push_back(in_quotes(names[i]));
    if (!missing.empty()) {
      std::string list;
      for (std::size_t i = 0; i < missing.size(); ++i)
        list += (i == 0 ? "" : i + 1 == missing.size() ? " and " : ", ") + missing[i];
      diagnostics_.error(family_name.range,
                         std::string(family.name) + "(...) of term " + in_quotes(source.name.text) + " is missing " +
                             (missing.size() == 1 ? "parameter " : "parameters ") + list,
                         {takes});
    }
  }

  // An interval argument: gauss mean or sd, constant value. Records the footprint; false after reporting.
  bool lower_interval(const Argument& argument, const FamilySignature& family, double low, double high,
                      fmpc::Term* term) {
    const std::string parameter = argument.name.text;
    FootprintKind kind = FootprintKind::None;
    if (family.kind == MfKind::Gaussian && parameter == "mean") kind = FootprintKind::UncertainMean;
    else if (family.kind == MfKind::Gaussian && parameter == "sd") kind = FootprintKind::UncertainSd;
    else if (family.kind == MfKind::Constant && parameter == "value") kind = FootprintKind::IntervalValue;
    if (kind == FootprintKind::None || term == nullptr) {
      diagnostics_.error(argument.range,
                         in_quotes(parameter) + " of " + family.name + " takes a number, not an interval",
                         {"intervals: gauss(mean [m1, m2], sd s), gauss(mean m, sd [s1, s2]) and, for sugeno "
                          "outputs, constant(value [c1, c2]); other families take `upper F(...) lower G(...)` or "
                          "`lower scale S lag L`"});
      return false;
    }
    if (term->footprint) {
      diagnostics_.error(argument.range, "term " + in_quotes(term->name) +
                                             " has two intervals; an uncertain gaussian has an uncertain mean or "
                                             "an uncertain sd, not both (use `upper gauss(...) lower gauss(...)`)");
      return false;
    }
    Footprint footprint;
    footprint.kind = kind;
    footprint.first = low;
    footprint.second = high;
    footprint.range = argument.range;
    term->footprint = footprint;
    return true;
  }

  const std::vector<std::string>& input_names() const { return names_->variable_names(false); }
  const std::vector<std::string>& output_names() const { return names_->variable_names(true); }

  void lower_linear(const std::vector<Argument>& arguments, const fmpc::Variable& variable, MembershipFunction& mf) {
    const std::size_t inputs = system_.inputs.size();
    mf.params.assign(inputs + 1, 0.0);
    std::vector<const Argument*> given(inputs + 1, nullptr);
    for (const Argument& argument : arguments) {
      if (argument.high)
        diagnostics_.error(argument.range, "the coefficients of linear(...) take numbers, not intervals",
                           {"an interval sugeno consequent is written constant(value [c1, c2])"});
      const bool is_offset = argument.name.text == "offset" && !argument.name.quoted;
      std::size_t index = inputs;
      if (!is_offset) {
        const int input = names_->variable(false, argument.name.text);
        if (input < 0) {
          std::vector<std::string> notes = did_you_mean(argument.name.text, input_names());
          notes.push_back("linear(...) takes one coefficient per input of " + in_quotes(system_.name) + " (" +
                          name_list_text(input_names()) + ") and an offset");
          diagnostics_.error(argument.name.range,
                             in_quotes(argument.name.text) + " is not an input of system " + in_quotes(system_.name),
                             notes);
          continue;
        }
        index = static_cast<std::size_t>(input);
      }
      if (given[index]) {
        diagnostics_.error(argument.name.range,
                           (is_offset ? std::string("the offset")
                                      : "the coefficient of " + in_quotes(argument.name.text)) +
                               " is given twice",
                           {"first given here: " + position_text(given[index]->name.range)});
        continue;
      }
      given[index] = &argument;
      if (!is_offset) {
        if (argument.unit)
          diagnostics_.error(argument.unit->range, "the coefficient of " + in_quotes(argument.name.text) +
                                                       " takes no unit; remove " + in_quotes(argument.unit->text));
        else mf.params[index] = argument.value.value;
      } else if (auto value = in_variable_unit(argument.value.value, argument.unit, "offset", variable)) {
        mf.params[index] = *value;
      }
    }
  }

  // --- rules --------------------------------------------------------------------------------------------------

  // The system of this file, other than this one, that has a variable called `name`, with its role. The other
  // systems' variables are indexed on the first unknown name, so that many unknown names cost one pass.
  std::optional<std::string> owner_elsewhere(const std::string& name) {
    if (!variables_elsewhere_) {
      variables_elsewhere_.emplace();
      for (const System& other : file_.systems) {
        if (&other == &source_ || other.name.text == source_.name.text) continue;
        for (const Item& item : other.items)
          if (const auto* variable = std::get_if<ast::Variable>(&item))
            variables_elsewhere_->emplace(variable->name.text, std::make_pair(&other, variable->is_output));
      }
    }
    const auto found = variables_elsewhere_->find(name);
    if (found == variables_elsewhere_->end()) return std::nullopt;
    const auto [other, is_output] = found->second;
    return in_quotes(name) + " is an " + (is_output ? "output" : "input") + " of system " +
           in_quotes(other->name.text) + "; a rule of " + in_quotes(source_.name.text) +
           " can only name its own variables";
  }

  // Resolves one clause; returns false after reporting when it does not resolve.
  bool lower_clause(const ast::Clause& source, bool consequent, const std::string& rule_name, fmpc::Clause& clause,
                    std::map<int, SourceRange>& used) {
    const std::vector<fmpc::Variable>& variables = consequent ? system_.outputs : system_.inputs;
    const char* role = consequent ? "output" : "input";
    const int index = names_->variable(consequent, source.variable.text);
    if (index < 0) {
      const int other_role = names_->variable(!consequent, source.variable.text);
      if (other_role >= 0) {
        diagnostics_.error(source.variable.range,
                           in_quotes(source.variable.text) + " is an " + (consequent ? "input" : "output") + " of " +
                               in_quotes(system_.name) + "; the " +
                               (consequent ? "conclusions after 'then' name outputs"
                                           : "conditions after 'if' name inputs"));
      } else if (auto elsewhere = owner_elsewhere(source.variable.text)) {
        diagnostics_.error(source.variable.range, *elsewhere);
      } else {
        diagnostics_.error(source.variable.range,
                           std::string("unknown ") + role + " " + in_quotes(source.variable.text) + " in system " +
                               in_quotes(system_.name),
                           did_you_mean(source.variable.text, consequent ? output_names() : input_names()));
      }
      return false;
    }
    const fmpc::Variable& variable = variables[static_cast<std::size_t>(index)];
    const auto [previous, inserted] = used.emplace(index, source.variable.range);
    if (!inserted) {
      diagnostics_.error(source.variable.range,
                         std::string(role) + " " + in_quotes(variable.name) + " appears twice in " + rule_name +
                             "; a rule names each " + role + " at most once",
                         {"first used here: " + position_text(previous->second)});
      return false;
    }
    const int term = names_->term(consequent, index, source.term.text);
    if (term < 0) {
      const std::vector<std::string>& term_names = names_->term_names(consequent, index);
      std::vector<std::string> notes = did_you_mean(source.term.text, term_names);
      notes.push_back("terms of " + in_quotes(variable.name) + ": " + name_list_text(term_names));
      diagnostics_.error(source.term.range,
                         std::string(role) + " " + in_quotes(variable.name) + " has no term " +
                             in_quotes(source.term.text),
                         notes);
      return false;
    }
    clause.variable = index;
    clause.term = term;
    clause.negated = source.negated;
    clause.hedge = source.hedge;
    clause.range = source.range;
    return true;
  }

  void lower_rule(const ast::Rule& source) {
    fmpc::Rule rule;
    rule.label = source.label ? source.label->text : "";
    rule.range = source.range;
    rule.weight = source.weight ? source.weight->value : 1.0;
    const std::string rule_name =
        source.label ? "rule " + in_quotes(source.label->text) : "rule " + std::to_string(system_.rules.size() + 1);
    if (!source.connectives.empty()) {
      rule.connective = source.connectives.front().connective;
      for (const ConnectiveToken& connective : source.connectives) {
        if (connective.connective != rule.connective) {
          diagnostics_.error(connective.range,
                             rule_name + " mixes 'and' and 'or'; a rule has one connective (as in MATLAB), so split "
                                         "it into several rules");
          break;
        }
      }
    }
    std::map<int, SourceRange> used_inputs, used_outputs;
    for (const ast::Clause& clause : source.antecedent) {
      fmpc::Clause lowered;
      if (lower_clause(clause, false, rule_name, lowered, used_inputs)) rule.antecedent.push_back(lowered);
    }
    for (const ast::Clause& clause : source.consequent) {
      fmpc::Clause lowered;
      if (lower_clause(clause, true, rule_name, lowered, used_outputs)) rule.consequent.push_back(lowered);
    }
    system_.rules.push_back(std::move(rule));
  }

  const File& file_;
  const System& source_;
  DiagnosticList& diagnostics_;
  FuzzySystem system_;
  std::optional<SystemNames> names_;  // system_'s names, indexed once its variables (then its terms) are lowered
  // The other systems' variables by name: the first system that has it, and whether it is an output there.
  std::optional<std::unordered_map<std::string, std::pair<const System*, bool>>> variables_elsewhere_;
  bool settings_failed_ = false;
  std::vector<std::size_t> failed_rules_;
};

}  // namespace

RuleFile ast::lower_fmpc(const File& file, DiagnosticList& diagnostics) {
  RuleFile result;
  result.path = file.path;
  std::map<std::string, SourceRange> system_names;
  for (std::size_t i = 0; i < file.systems.size(); ++i) {
    const System& system = file.systems[i];
    DiagnosticList system_diagnostics;
    const auto [first, inserted] = system_names.emplace(system.name.text, system.name.range);
    if (!inserted)
      system_diagnostics.error(system.name.range,
                               "system " + in_quotes(system.name.text) + " is defined twice in this file; rename one",
                               {"first defined here: " + position_text(first->second)});
    SystemLowering lowering(file, i, system_diagnostics);
    FuzzySystem lowered = lowering.lower();
    if (inserted && !lowering.settings_failed()) result.systems.push_back(std::move(lowered));
    diagnostics.append(system_diagnostics);
  }
  return result;
}

RuleFile read_fmpc(const std::string& path, const std::string& text, DiagnosticList& diagnostics) {
  DiagnosticList local;
  std::optional<ast::File> file = ast::parse_fmpc(path, text, local);
  RuleFile result;
  result.path = path;
  if (file) result = ast::lower_fmpc(*file, local);
  local.sort_by_position();
  diagnostics.append(local);
  return result;
}

}  // namespace fmpc
