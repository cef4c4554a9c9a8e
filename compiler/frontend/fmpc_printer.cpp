// The canonical layout of fmpc text (docs/language.md, "Canonical layout"). format_fmpc prints the AST of a file,
// comments included; write_fmpc turns an IR into an AST first, so both produce the same layout by construction.
#include <algorithm>
#include <cctype>

#include "compiler/frontend/fmpc_ast.h"
#include "compiler/frontend/fmpc_language.h"
#include "diagnostics/number_format.h"

namespace fmpc {

namespace ast {

namespace {

bool is_identifier(const std::string& text) {
  if (text.empty()) return false;
  const auto first = static_cast<unsigned char>(text[0]);
  if (!(std::isalpha(first) || first == '_') || first >= 0x80) return false;
  return std::all_of(text.begin(), text.end(), [](char c) {
    const auto byte = static_cast<unsigned char>(c);
    return byte < 0x80 && (std::isalnum(byte) || byte == '_');
  });
}

std::string name_text(const Name& name) { return name_as_written(name.text); }

std::string unit_text(const Name& unit) { return unit.text == "%" ? unit.text : name_text(unit); }

bool samples_apply(const std::string& defuzzifier) {
  return defuzzifier == "centroid" || defuzzifier == "bisector" || defuzzifier == "mom" || defuzzifier == "som" ||
         defuzzifier == "lom";
}

class Printer {
 public:
  std::string print(const File& file) {
    for (std::size_t i = 0; i < file.systems.size(); ++i) print_system(file.systems[i], i == 0);
    if (!file.end_comments.leading.empty()) {
      if (file.end_comments.blank_line_before && !out_.empty()) out_ += '\n';
      for (const std::string& comment : file.end_comments.leading) out_ += comment + '\n';  // "" is a blank line
    }
    return aligned_trailing_comments();
  }

 private:
  // A line that ends in a comment: where it starts, where its code ends and where its '\n' is, in out_.
  struct TrailingComment {
    std::size_t start, code_end, line_end;
  };

  static std::size_t code_points(const std::string& text, std::size_t from, std::size_t to) {
    std::size_t count = 0;
    for (std::size_t i = from; i < to; ++i) count += (static_cast<unsigned char>(text[i]) & 0xC0) != 0x80;
    return count;
  }

  // The trailing comments of consecutive lines start in one column, two spaces after the longest line's code, as
  // gofmt aligns them, so that a hand-aligned column survives `fmpc fmt`; a blank line, a comment line or a line
  // without a trailing comment ends the run.
  std::string aligned_trailing_comments() const {
    if (trailing_.empty()) return out_;
    std::string aligned;
    aligned.reserve(out_.size() + out_.size() / 8);
    std::size_t copied = 0;
    for (std::size_t first = 0; first < trailing_.size();) {
      std::size_t last = first;
      while (last + 1 < trailing_.size() && trailing_[last + 1].start == trailing_[last].line_end + 1) ++last;
      std::size_t width = 0;
      for (std::size_t i = first; i <= last; ++i)
        width = std::max(width, code_points(out_, trailing_[i].start, trailing_[i].code_end));
      for (std::size_t i = first; i <= last; ++i) {
        const TrailingComment& line = trailing_[i];
        aligned.append(out_, copied, line.code_end - copied);
        aligned.append(width - code_points(out_, line.start, line.code_end) + 2, ' ');
        copied = line.code_end;
      }
      first = last + 1;
    }
    aligned.append(out_, copied, std::string::npos);
    return aligned;
  }

  void leading(const Comments& comments, const char* indent) {
    for (const std::string& comment : comments.leading) out_ += (comment.empty() ? "" : indent + comment) + '\n';
  }

  void line(const Comments& comments, const char* indent, const std::string& text) {
    leading(comments, indent);
    const std::size_t start = out_.size();
    out_ += indent + text;
    if (!comments.trailing.empty()) {
      const std::size_t code_end = out_.size();
      out_ += comments.trailing;
      trailing_.push_back({start, code_end, out_.size()});
    }
    out_ += '\n';
  }

  void print_system(const System& system, bool first) {
    if (!first) out_ += '\n';
    std::string header = "system " + name_text(system.name);
    if (system.description) header += " \"" + *system.description + "\"";
    line(system.comments, "", header);
    print_settings(system);
    std::vector<std::string> inputs;
    for (const Item& item : system.items)
      if (const auto* variable = std::get_if<Variable>(&item); variable && !variable->is_output)
        inputs.push_back(variable->name.text);
    bool after_rule = false;
    for (const Item& item : system.items) {
      if (const auto* variable = std::get_if<Variable>(&item)) {
        print_variable(*variable, inputs);
        after_rule = false;
      } else {
        const Rule& rule = std::get<Rule>(item);
        if (!after_rule || rule.comments.blank_line_before) out_ += '\n';
        print_rule(rule);
        after_rule = true;
      }
    }
  }

  void print_settings(const System& system) {
    bool sugeno = false;
    bool interval_type2 = false;
    for (const Setting& setting : system.settings) {
      if (setting.kind == SettingKind::Type && setting.value.text == "sugeno") sugeno = true;
      if (setting.kind == SettingKind::Type && setting.interval_type2) interval_type2 = true;
    }
    for (SettingKind kind : {SettingKind::Type, SettingKind::TypeReduction, SettingKind::And, SettingKind::Or,
                             SettingKind::Implication, SettingKind::Aggregation, SettingKind::Defuzzify,
                             SettingKind::NoFire}) {
      bool present = false;
      for (const Setting& setting : system.settings) {
        if (setting.kind != kind) continue;
        present = true;
        line(setting.comments, "  ", setting_text(setting));
      }
      // A type-1 system has no type reduction: its default line would only make it look type-2.
      if (!present && (kind != SettingKind::TypeReduction || interval_type2))
        out_ += "  " + setting_text(default_setting(kind, sugeno)) + '\n';
    }
  }

  // MATLAB's defaults for mamfis and sugfis (docs/language.md, "Settings").
  static Setting default_setting(SettingKind kind, bool sugeno) {
    Setting setting;
    setting.kind = kind;
    switch (kind) {
      case SettingKind::Type: setting.value.text = "mamdani"; break;
      case SettingKind::And: setting.value.text = sugeno ? "prod" : "min"; break;
      case SettingKind::Or: setting.value.text = sugeno ? "probor" : "max"; break;
      case SettingKind::Implication: setting.value.text = sugeno ? "prod" : "min"; break;
      case SettingKind::Aggregation: setting.value.text = sugeno ? "sum" : "max"; break;
      case SettingKind::Defuzzify: setting.value.text = sugeno ? "wtaver" : "centroid"; break;
      case SettingKind::NoFire: setting.value.text = "midrange"; break;
      case SettingKind::TypeReduction: setting.value.text = "karnik_mendel"; break;
    }
    return setting;
  }

  static std::string setting_text(const Setting& setting) {
    switch (setting.kind) {
      case SettingKind::Type:
        return std::string("type ") + (setting.interval_type2 ? "interval_type2 " : "") + name_text(setting.value);
      case SettingKind::TypeReduction: return "type_reduction " + name_text(setting.value);
      case SettingKind::And: return "and " + name_text(setting.value);
      case SettingKind::Or: return "or " + name_text(setting.value);
      case SettingKind::Implication: return "implication " + name_text(setting.value);
      case SettingKind::Aggregation: return "aggregation " + name_text(setting.value);
      case SettingKind::Defuzzify: {
        std::string text = "defuzzify " + name_text(setting.value);
        if (setting.samples_exact) text += " samples exact";
        else if (setting.samples) text += " samples " + format_number(setting.samples->value);
        else if (samples_apply(setting.value.text)) text += " samples 101";
        return text;
      }
      case SettingKind::NoFire: {
        std::string text = "when no rule fires: " + setting.value.text;
        if (setting.no_fire_value) text += " " + format_number(setting.no_fire_value->value);
        return text;
      }
    }
    return "";
  }

  void print_variable(const Variable& variable, const std::vector<std::string>& inputs) {
    out_ += '\n';
    std::string header = (variable.is_output ? "output " : "input ") + name_text(variable.name);
    if (variable.description) header += " \"" + *variable.description + "\"";
    header += " in [" + format_number(variable.min.value) + ", " + format_number(variable.max.value) + "]";
    if (variable.unit) header += " " + unit_text(*variable.unit);
    line(variable.comments, "", header);
    for (const Term& term : variable.terms) {
      if (term.comments.blank_line_before) out_ += '\n';
      line(term.comments, "  ", term_text(term, inputs));
    }
  }

  // Arguments in the family's order (linear: the inputs' order, then the offset); names it does not know last.
  static std::string call_text(const Name& family_name, const std::vector<Argument>& source_arguments,
                               const std::vector<std::string>& inputs) {
    const bool linear = family_name.text == "linear";
    const bool positional = std::any_of(source_arguments.begin(), source_arguments.end(), [](const Argument& a) {
      return a.name.text.empty() && !a.name.quoted;
    });
    std::vector<std::string> order;
    Name shown_family = family_name;
    if (linear) {
      order = inputs;
    } else if (const FamilySignature* family = find_family_or_alias(family_name.text)) {
      order.assign(family->parameters.begin(), family->parameters.end());
      // MATLAB's name (trimf) is written as fmpc's (triangle), unless positional parameters keep MATLAB's order
      // meaningful (sema refuses those, with the named spelling).
      if (!positional) shown_family.text = family->name;
    }
    std::vector<const Argument*> arguments;
    for (const Argument& argument : source_arguments) arguments.push_back(&argument);
    const auto rank = [&](const Argument* argument) {
      if (linear && argument->name.text == "offset" && !argument->name.quoted) return order.size();
      const auto found = std::find(order.begin(), order.end(), argument->name.text);
      return found == order.end() ? order.size() + 1 : static_cast<std::size_t>(found - order.begin());
    };
    std::stable_sort(arguments.begin(), arguments.end(),
                     [&](const Argument* a, const Argument* b) { return rank(a) < rank(b); });
    std::string text = name_text(shown_family) + "(";
    for (std::size_t i = 0; i < arguments.size(); ++i) {
      const Argument& argument = *arguments[i];
      if (i > 0) text += ", ";
      // In linear(...) a quoted "offset" is an input of that name, a bare one the constant term.
      const bool quote = argument.name.quoted && argument.name.text == "offset";
      const bool named = !argument.name.text.empty() || argument.name.quoted;
      text += quote ? "\"offset\" " : named ? name_text(argument.name) + " " : "";
      if (argument.high)
        text += "[" + format_number(argument.value.value) + ", " + format_number(argument.high->value) + "]";
      else
        text += format_number(argument.value.value);
      if (argument.unit) text += " " + unit_text(*argument.unit);
    }
    return text + ")";
  }

  static std::string term_text(const Term& term, const std::vector<std::string>& inputs) {
    std::string text = name_text(term.name) + " is ";
    if (term.explicit_upper || term.lower) text += "upper ";
    text += call_text(term.family, term.arguments, inputs);
    if (term.lower) text += " lower " + call_text(term.lower->family, term.lower->arguments, inputs);
    if (term.lower_scale || term.lower_lag) {
      text += " lower";
      if (term.lower_scale) text += " scale " + format_number(term.lower_scale->value);
      if (term.lower_lag) text += " lag " + format_number(term.lower_lag->value);
    }
    return text;
  }

  static std::string clause_text(const Clause& clause) {
    std::string text = name_text(clause.variable) + " is ";
    if (clause.negated) text += "not ";
    if (clause.hedge != Hedge::None) text += std::string(to_string(clause.hedge)) + " ";
    return text + name_text(clause.term);
  }

  void print_rule(const Rule& rule) {
    std::string text = "rule";
    if (rule.label) text += " " + name_text(*rule.label);
    line(rule.comments, "", text + ": " + rule_body(rule));
  }

 public:
  // "if ... then ... [weight W]"
  static std::string rule_body(const Rule& rule) {
    std::string text = "if ";
    for (std::size_t i = 0; i < rule.antecedent.size(); ++i) {
      if (i > 0) {
        const bool is_or = i - 1 < rule.connectives.size() && rule.connectives[i - 1].connective == Connective::Or;
        text += is_or ? " or " : " and ";
      }
      text += clause_text(rule.antecedent[i]);
    }
    text += " then ";
    for (std::size_t i = 0; i < rule.consequent.size(); ++i)
      text += (i > 0 ? " and " : "") + clause_text(rule.consequent[i]);
    if (rule.weight) text += " weight " + format_number(rule.weight->value);
    return text;
  }

 private:
  std::string out_;
  std::vector<TrailingComment> trailing_;
};

// A description or name that the language cannot hold verbatim: '"' becomes '\'', line breaks become spaces.
std::string printable(std::string text) {
  for (char& c : text) {
    if (c == '"') c = '\'';
    else if (c == '\n' || c == '\r') c = ' ';
  }
  return text;
}

Name name_of(const std::string& text) { return Name{printable(text), {}, false}; }

Number number_of(double value) { return Number{value, {}}; }

std::optional<std::string> description_of(const std::string& description) {
  if (description.empty()) return std::nullopt;
  return printable(description);
}

// The named arguments of a type-1 MF in the family's order (linear: one coefficient per input, then the offset).
std::vector<Argument> arguments_of(const fmpc::MembershipFunction& mf, const FuzzySystem& system) {
  std::vector<Argument> arguments;
  const FamilySignature& family = family_of(mf.kind);
  const std::vector<double>& params = mf.params;
  const auto param = [&](std::size_t index) { return index < params.size() ? params[index] : 0.0; };
  if (mf.kind == MfKind::Linear) {
    for (std::size_t i = 0; i < system.inputs.size(); ++i) {
      Argument argument{name_of(system.inputs[i].name), number_of(param(i)), std::nullopt, {}};
      argument.name.quoted = argument.name.text == "offset";
      arguments.push_back(argument);
    }
    arguments.push_back(Argument{name_of("offset"), number_of(param(system.inputs.size())), std::nullopt, {}});
  } else {
    for (std::size_t i = 0; i < family.parameters.size(); ++i)
      arguments.push_back(Argument{name_of(family.parameters[i]),
                                   number_of(param(static_cast<std::size_t>(family.matlab_index[i]))),
                                   std::nullopt,
                                   {}});
  }
  return arguments;
}

Variable variable_of(const fmpc::Variable& source, bool is_output, const FuzzySystem& system) {
  Variable variable;
  variable.is_output = is_output;
  variable.name = name_of(source.name);
  variable.description = description_of(source.description);
  variable.min = number_of(source.min);
  variable.max = number_of(source.max);
  if (!source.unit.empty()) variable.unit = name_of(source.unit);
  for (const fmpc::Term& source_term : source.terms) {
    Term term;
    term.name = name_of(source_term.name);
    term.family = name_of(family_of(source_term.mf.kind).name);
    term.arguments = arguments_of(source_term.mf, system);
    if (const std::optional<fmpc::Footprint>& footprint = source_term.footprint) {
      // The interval replaces the parameter it makes uncertain (docs/language.md, "Interval type-2").
      const auto widen = [&](const char* parameter) {
        for (Argument& argument : term.arguments)
          if (argument.name.text == parameter) {
            argument.value = number_of(footprint->first);
            argument.high = number_of(footprint->second);
          }
      };
      switch (footprint->kind) {
        case FootprintKind::UncertainMean: widen("mean"); break;
        case FootprintKind::UncertainSd: widen("sd"); break;
        case FootprintKind::IntervalValue: widen("value"); break;
        case FootprintKind::ExplicitLower: {
          LowerCall lower;
          lower.family = name_of(family_of(footprint->lower.kind).name);
          lower.arguments = arguments_of(footprint->lower, system);
          term.lower = std::move(lower);
          term.explicit_upper = true;
          break;
        }
        case FootprintKind::ScaleLag:
          if (footprint->first != 1.0) term.lower_scale = number_of(footprint->first);
          if (footprint->second != 0.0 || footprint->first == 1.0) term.lower_lag = number_of(footprint->second);
          break;
        case FootprintKind::None: break;
      }
    }
    variable.terms.push_back(std::move(term));
  }
  return variable;
}

Clause clause_of(const fmpc::Clause& source, const std::vector<fmpc::Variable>& variables) {
  Clause clause;
  const bool valid_variable = source.variable >= 0 && static_cast<std::size_t>(source.variable) < variables.size();
  const fmpc::Variable* variable = valid_variable ? &variables[static_cast<std::size_t>(source.variable)] : nullptr;
  clause.variable = name_of(variable ? variable->name : "?");
  const bool valid_term = variable && source.term >= 0 && static_cast<std::size_t>(source.term) < variable->terms.size();
  clause.term = name_of(valid_term ? variable->terms[static_cast<std::size_t>(source.term)].name : "?");
  clause.negated = source.negated;
  clause.hedge = source.hedge;
  return clause;
}

Rule rule_of(const fmpc::Rule& source_rule, const FuzzySystem& source) {
  Rule rule;
  if (!source_rule.label.empty()) rule.label = name_of(source_rule.label);
  for (const fmpc::Clause& clause : source_rule.antecedent) rule.antecedent.push_back(clause_of(clause, source.inputs));
  for (std::size_t i = 1; i < rule.antecedent.size(); ++i)
    rule.connectives.push_back(ConnectiveToken{source_rule.connective, {}});
  for (const fmpc::Clause& clause : source_rule.consequent) rule.consequent.push_back(clause_of(clause, source.outputs));
  if (source_rule.weight != 1.0) rule.weight = number_of(source_rule.weight);
  return rule;
}

System system_of(const FuzzySystem& source) {
  System system;
  system.name = name_of(source.name);
  system.description = description_of(source.description);
  const auto setting = [&](SettingKind kind, const std::string& value) {
    Setting result;
    result.kind = kind;
    result.value = name_of(value);
    return result;
  };
  Setting type = setting(SettingKind::Type, to_string(source.type));
  type.interval_type2 = source.interval_type2;
  system.settings.push_back(type);
  if (source.interval_type2)
    system.settings.push_back(setting(SettingKind::TypeReduction, to_string(source.type_reduction)));
  system.settings.push_back(setting(SettingKind::And, to_string(source.and_method)));
  system.settings.push_back(setting(SettingKind::Or, to_string(source.or_method)));
  system.settings.push_back(setting(SettingKind::Implication, to_string(source.implication)));
  system.settings.push_back(setting(SettingKind::Aggregation, to_string(source.aggregation)));
  Setting defuzzify = setting(SettingKind::Defuzzify, to_string(source.defuzzifier));
  if (source.samples == 0) defuzzify.samples_exact = true;
  else if (samples_apply(defuzzify.value.text) || source.samples != 101)
    defuzzify.samples = number_of(source.samples);
  system.settings.push_back(defuzzify);
  switch (source.no_fire) {
    case NoFirePolicy::Midrange: system.settings.push_back(setting(SettingKind::NoFire, "midrange")); break;
    case NoFirePolicy::Error: system.settings.push_back(setting(SettingKind::NoFire, "error")); break;
    case NoFirePolicy::Value: {
      Setting value = setting(SettingKind::NoFire, "value");
      value.no_fire_value = number_of(source.no_fire_value);
      system.settings.push_back(value);
      break;
    }
  }
  for (const fmpc::Variable& input : source.inputs) system.items.emplace_back(variable_of(input, false, source));
  for (const fmpc::Variable& output : source.outputs) system.items.emplace_back(variable_of(output, true, source));
  for (const fmpc::Rule& source_rule : source.rules) system.items.emplace_back(rule_of(source_rule, source));
  return system;
}

}  // namespace

std::string name_as_written(const std::string& name) {
  if (is_identifier(name) && !is_reserved_word(name)) return name;
  return "\"" + name + "\"";
}

std::string print_fmpc(const File& file) { return Printer().print(file); }

}  // namespace ast

std::optional<std::string> format_fmpc(const std::string& path, const std::string& text,
                                       DiagnosticList& diagnostics) {
  DiagnosticList syntax;
  std::optional<ast::File> file = ast::parse_fmpc(path, text, syntax);
  diagnostics.append(syntax);
  // A file read through repairs is not what its text says: the fix-its are the user's to make.
  if (!file || syntax.has_errors()) return std::nullopt;
  return ast::print_fmpc(*file);
}

std::string format_rule_body(const FuzzySystem& system, std::size_t rule_index) {
  if (rule_index >= system.rules.size()) return "";
  return ast::Printer::rule_body(ast::rule_of(system.rules[rule_index], system));
}

std::string write_fmpc(const RuleFile& file) {
  ast::File tree;
  tree.path = file.path;
  for (const FuzzySystem& system : file.systems) tree.systems.push_back(ast::system_of(system));
  return ast::print_fmpc(tree);
}

}  // namespace fmpc
