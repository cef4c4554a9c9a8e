#include "tools/studio/studio_rule_model.h"

#include <algorithm>
#include <cmath>

#include "compiler/eval/interpreter.h"
#include "compiler/frontend/fmpc_ast.h"
#include "compiler/frontend/fmpc_language.h"
#include "compiler/sema/coverage.h"
#include "compiler/sema/lint.h"
#include "diagnostics/number_format.h"

namespace fmpc::studio {

namespace {

Json clause_json(const FuzzySystem& system, const Clause& clause, bool consequent) {
  const std::vector<Variable>& variables = consequent ? system.outputs : system.inputs;
  const Variable& variable = variables[static_cast<std::size_t>(clause.variable)];
  Json json;
  json["variable"] = variable.name;
  json["term"] = variable.terms[static_cast<std::size_t>(clause.term)].name;
  json["negated"] = clause.negated;
  json["hedge"] = to_string(clause.hedge);
  return json;
}

std::string clause_words(const FuzzySystem& system, const Clause& clause, bool consequent) {
  const std::vector<Variable>& variables = consequent ? system.outputs : system.inputs;
  const Variable& variable = variables[static_cast<std::size_t>(clause.variable)];
  std::string words = variable.name + " is ";
  if (clause.negated) words += "not ";
  if (clause.hedge != Hedge::None) words += std::string(to_string(clause.hedge)) + " ";
  return words + variable.terms[static_cast<std::size_t>(clause.term)].name;
}

Json term_json(const FuzzySystem& system, const Term& term) {
  Json json;
  json["name"] = term.name;
  json["matlab"] = matlab_name(term.mf.kind);
  json["range"] = range_json(term.range);
  json["type2"] = term.footprint.has_value();
  Json parameters = Json::array();
  if (term.mf.kind == MfKind::Linear) {
    json["family"] = "linear";
    for (std::size_t i = 0; i < term.mf.params.size(); ++i)
      parameters.push_back({{"name", i < system.inputs.size() ? system.inputs[i].name : std::string("offset")},
                            {"value", term.mf.params[i]},
                            {"role", "slope"}});
  } else {
    const ast::FamilySignature& family = ast::family_of(term.mf.kind);
    json["family"] = family.name;
    for (std::size_t p = 0; p < family.parameters.size(); ++p) {
      const auto index = static_cast<std::size_t>(family.matlab_index[p]);
      // How the page lets a user drag it: a position on the variable's axis, a width (sd, a bell's width) or a
      // slope, which has no place on the axis and is typed only.
      const std::string name = family.parameters[p];
      const bool width = name == "sd" || name == "sd1" || name == "sd2" || name == "width";
      parameters.push_back({{"name", name},
                            {"value", index < term.mf.params.size() ? term.mf.params[index] : std::nan("")},
                            {"role", !family.takes_unit[p] ? "slope" : width ? "width" : "position"}});
    }
  }
  json["parameters"] = parameters;
  return json;
}

Json variable_json(const FuzzySystem& system, const Variable& variable, bool output) {
  Json json;
  json["name"] = variable.name;
  json["description"] = variable.description;
  json["unit"] = variable.unit;
  json["min"] = variable.min;
  json["max"] = variable.max;
  json["range"] = range_json(variable.range);
  Json terms = Json::array();
  for (const Term& term : variable.terms) terms.push_back(term_json(system, term));
  json["terms"] = terms;
  if (!output) {
    // Lint's per-input check at its default threshold and resolution (docs/lint.md, coverage-hole).
    const LintOptions lint;
    Json holes = Json::array();
    for (const CoverageInterval& hole :
         input_coverage_holes(variable, lint.coverage_threshold, lint.coverage_points_per_input))
      holes.push_back({hole.from, hole.to});
    json["coverage_holes"] = holes;
    json["coverage_threshold"] = lint.coverage_threshold;
  }
  return json;
}

}  // namespace

sim::LoadedRuleFile load_rule_text(const std::string& path, const std::string& text) {
  sim::LoadedRuleFile file;
  file.path = path;
  file.readable = true;
  file.sources.add(path, text);
  file.dialect = detect_dialect(text);
  file.rules = load_rule_file(path, text, file.diagnostics);
  sim::lint_rule_file(file, LintOptions{});
  return file;
}

Json range_json(const SourceRange& range) {
  return Json{{"line", range.line}, {"column", range.column}, {"end_line", range.end_line},
              {"end_column", range.end_column}};
}

Json check_json(const sim::LoadedRuleFile& file) {
  Json diagnostics = Json::array();
  for (const Diagnostic& d : file.diagnostics.items()) {
    Json item = range_json(d.range);
    item["severity"] = severity_name(d.severity);
    item["message"] = d.message;
    item["code"] = d.code;
    item["notes"] = d.notes;
    if (d.fix) item["fix"] = Json{{"range", range_json(d.fix->range)}, {"replacement", d.fix->replacement}};
    item["text"] = render(d, file.sources);
    diagnostics.push_back(item);
  }
  Json json;
  json["dialect"] = dialect_name(file.dialect);
  json["diagnostics"] = diagnostics;
  json["errors"] = file.diagnostics.error_count();
  json["warnings"] = file.diagnostics.warning_count();
  Json systems = Json::array();
  if (!file.diagnostics.has_errors())
    for (const FuzzySystem& system : file.rules.systems) systems.push_back(system_json(system));
  json["systems"] = systems;
  return json;
}

Json system_json(const FuzzySystem& system) {
  Json json;
  json["name"] = system.name;
  json["description"] = system.description;
  json["type"] = std::string(system.interval_type2 ? "interval type-2 " : "") + to_string(system.type);
  json["sugeno"] = system.type == SystemType::Sugeno;
  json["interval_type2"] = system.interval_type2;
  json["defuzzifier"] = to_string(system.defuzzifier);
  Json inputs = Json::array(), outputs = Json::array(), rules = Json::array();
  for (const Variable& v : system.inputs) inputs.push_back(variable_json(system, v, false));
  for (const Variable& v : system.outputs) outputs.push_back(variable_json(system, v, true));
  for (std::size_t r = 0; r < system.rules.size(); ++r) {
    const Rule& rule = system.rules[r];
    Json item;
    item["index"] = r;
    item["label"] = rule.label;
    item["name"] = system.rule_display_name(r);
    item["text"] = format_rule_body(system, r);
    item["sentence"] = rule_sentence(system, r);
    item["connective"] = rule.connective == Connective::And ? "and" : "or";
    item["weight"] = rule.weight;
    item["range"] = range_json(rule.range);
    Json antecedent = Json::array(), consequent = Json::array();
    for (const Clause& c : rule.antecedent) antecedent.push_back(clause_json(system, c, false));
    for (const Clause& c : rule.consequent) consequent.push_back(clause_json(system, c, true));
    item["antecedent"] = antecedent;
    item["consequent"] = consequent;
    rules.push_back(item);
  }
  json["inputs"] = inputs;
  json["outputs"] = outputs;
  json["rules"] = rules;
  return json;
}

Json membership_curves_json(const FuzzySystem& system, const Variable& variable, bool output, int samples) {
  std::vector<double> x;
  for (int k = 0; k < samples; ++k)
    x.push_back(variable.min + (variable.max - variable.min) * k / (samples - 1));
  // The corners of piecewise-linear shapes, so that a drawn triangle has its peak.
  for (const Term& term : variable.terms)
    for (double p : term.mf.params)
      if (p > variable.min && p < variable.max) x.push_back(p);
  std::sort(x.begin(), x.end());
  x.erase(std::unique(x.begin(), x.end()), x.end());
  Json terms = Json::array();
  const bool sugeno_output = output && system.type == SystemType::Sugeno;
  for (const Term& term : variable.terms) {
    // The term's parameters with its curve, so that handles and curves always come from the same text.
    Json curve = term_json(system, term);
    if (sugeno_output) {
      curve["constant"] = term.mf.kind == MfKind::Constant && !term.mf.params.empty();
      terms.push_back(curve);
      continue;
    }
    Json upper = Json::array(), lower = Json::array();
    for (double v : x) {
      const GradeInterval<double> grade = term_membership(term, v);
      upper.push_back(grade.upper);
      if (term.footprint) lower.push_back(grade.lower);
    }
    curve["upper"] = upper;
    if (term.footprint) curve["lower"] = lower;
    terms.push_back(curve);
  }
  return Json{{"variable", variable.name}, {"output", output}, {"x", x}, {"terms", terms}};
}

std::string rule_sentence(const FuzzySystem& system, std::size_t index) {
  const Rule& rule = system.rules[index];
  std::string text = "If ";
  for (std::size_t c = 0; c < rule.antecedent.size(); ++c) {
    if (c > 0) text += rule.connective == Connective::And ? " and " : " or ";
    text += clause_words(system, rule.antecedent[c], false);
  }
  text += ", then ";
  for (std::size_t c = 0; c < rule.consequent.size(); ++c) {
    if (c > 0) text += " and ";
    text += clause_words(system, rule.consequent[c], true);
  }
  text += ".";
  if (rule.weight != 1.0) text += " (weight " + format_number(rule.weight) + ")";
  return text;
}

const FuzzySystem* find_system(const RuleFile& file, const std::string& name) {
  if (file.systems.empty()) return nullptr;
  if (name.empty()) return &file.systems.front();
  for (const FuzzySystem& system : file.systems)
    if (system.name == name) return &system;
  return nullptr;
}

}  // namespace fmpc::studio
