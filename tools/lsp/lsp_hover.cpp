// Hover (LSP 3.17 textDocument/hover): what the name or number under the cursor means, with numbers from the IR
// (units converted, parameters in MATLAB's order) and grades from the interpreter's own membership functions.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "compiler/eval/interpreter.h"
#include "compiler/frontend/fmpc_ast.h"
#include "compiler/frontend/fmpc_language.h"
#include "compiler/sema/term_shape.h"
#include "diagnostics/number_format.h"
#include "tools/lsp/hover_text.h"
#include "tools/lsp/lsp_document.h"

namespace fmpc::lsp {

namespace {

std::string digits4(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", value);
  return text;
}

std::string grade_text(const GradeInterval<double>& grade) {
  if (grade.lower == grade.upper) return digits4(grade.upper);
  return "[" + digits4(grade.lower) + ", " + digits4(grade.upper) + "]";
}

std::string with_unit(const std::string& number, const Variable& variable) {
  const bool unit = !variable.unit.empty() && variable.unit != "dimensionless";
  return number + (unit ? (variable.unit == "%" ? "" : " ") + variable.unit : "");
}

std::string with_unit(double value, const Variable& variable) { return with_unit(format_number(value), variable); }

// A point computed from the parameters (a Gaussian's mean - sd): 12 significant digits, so that 7.64 - 0.91 reads
// 6.73, not its binary neighbour 6.7299999999999995.
std::string computed_point(double value, const Variable& variable) {
  char text[32];
  std::snprintf(text, sizeof text, "%.12g", value);
  return with_unit(text, variable);
}

std::string range_text(const Variable& variable) {
  return "[" + format_number(variable.min) + ", " + format_number(variable.max) + "]" +
         (variable.unit.empty() ? "" : " " + variable.unit);
}

bool gradable(const Term& term) { return term.mf.kind != MfKind::Constant && term.mf.kind != MfKind::Linear; }

// The term's upper grade sampled across the variable's range, drawn with block characters (an estimate of the
// shape, not a bound: the numbers in the table above it are exact).
std::string sparkline(const Term& term, const Variable& variable) {
  static const char* const kBlocks[] = {"▁", "▂", "▃", "▄", "▅", "▆", "▇", "█"};
  constexpr int kSamples = 48;
  std::string line;
  for (int i = 0; i < kSamples; ++i) {
    const double x = variable.min + (variable.max - variable.min) * i / (kSamples - 1);
    const double grade = std::clamp(term_membership(term, x).upper, 0.0, 1.0);
    line += kBlocks[static_cast<int>(std::lround(grade * 7.0))];
  }
  return line;
}

// Where a family's shape turns, from its MATLAB parameter vector (kernels/fuzzy_kinds.h gives the orders).
std::vector<double> turning_points(const MembershipFunction& mf) {
  const std::vector<double>& p = mf.params;
  const auto at = [&](std::initializer_list<std::size_t> indices) {
    std::vector<double> points;
    for (std::size_t i : indices)
      if (i < p.size()) points.push_back(p[i]);
    return points;
  };
  switch (mf.kind) {
    case MfKind::Gaussian:
      if (p.size() >= 2) return {p[1] - p[0], p[1], p[1] + p[0]};
      return {};
    case MfKind::Gaussian2: return at({1, 3});
    case MfKind::GeneralizedBell:
      if (p.size() >= 3) return {p[2] - p[0], p[2], p[2] + p[0]};
      return {};
    case MfKind::Sigmoid: return at({1});
    case MfKind::DifferenceSigmoid:
    case MfKind::ProductSigmoid: return at({1, 3});
    case MfKind::Constant:
    case MfKind::Linear: return {};
    default: return p;  // triangle, trapezoid, pi, z, s, linear_s, linear_z: every parameter is a breakpoint
  }
}

std::string hedge_text(const std::string& word) {
  if (word == "somewhat") return "**somewhat**: the square root of the grade (exponent 0.5; Zadeh's dilation)";
  if (word == "very")
    return "**very**: the grade squared (exponent 2; Zadeh's concentration); `very very` is the fourth power";
  return "**extremely**: the grade cubed (exponent 3)";
}

}  // namespace

Json markdown_hover(const std::string& text, const Json& range) {
  return Json{{"contents", {{"kind", "markdown"}, {"value", text}}}, {"range", range}};
}

const Variable* find_variable(const FuzzySystem& system, const std::string& name, bool* is_output) {
  for (const auto* variables : {&system.inputs, &system.outputs})
    for (const Variable& variable : *variables)
      if (variable.name == name) {
        if (is_output) *is_output = variables == &system.outputs;
        return &variable;
      }
  return nullptr;
}

std::string term_hover_text(const Variable& variable, const Term& term) {
  std::string vector;
  for (double p : term.mf.params) vector += (vector.empty() ? "" : " ") + format_number(p);
  std::string text = "MATLAB's `" + std::string(matlab_name(term.mf.kind)) + " [" + vector + "]`" +
                     (variable.unit.empty() ? "" : " in " + variable.unit);
  if (!gradable(term)) return text;
  // Exact grades at the range's ends and where the shape turns (its feet, peaks, centres; a Gaussian's mean and
  // one sd either side), inside the range.
  std::set<double> at{variable.min, variable.max};
  for (double p : turning_points(term.mf))
    if (std::isfinite(p) && p > variable.min && p < variable.max) at.insert(p);
  if (const std::optional<CoreInterval> core = term_core(term)) {
    if (std::isfinite(core->lo) && core->lo > variable.min && core->lo < variable.max) at.insert(core->lo);
    if (std::isfinite(core->hi) && core->hi > variable.min && core->hi < variable.max) at.insert(core->hi);
  }
  text += "\n\n| " + variable.name + " | grade |\n|---:|---:|\n";
  for (double x : at) text += "| " + computed_point(x, variable) + " | " + grade_text(term_membership(term, x)) + " |\n";
  text += "\n`" + sparkline(term, variable) + "` over " + range_text(variable) + " (sampled at 48 points)";
  return text;
}

std::string value_hover_text(const Variable& variable, double value) {
  std::string text = "**" + variable.name + " = " + with_unit(value, variable) + "**";
  if (value < variable.min || value > variable.max)
    text += " (outside " + range_text(variable) + ": evaluated as given)";
  bool any = false;
  std::string table = "\n\n| term | grade |\n|---|---:|\n";
  for (const Term& term : variable.terms) {
    if (!gradable(term)) continue;
    any = true;
    table += "| " + term.name + " | " + grade_text(term_membership(term, value)) + " |\n";
  }
  if (any) text += table;
  return text;
}

std::string variable_hover_text(const FuzzySystem& system, const Variable& variable, bool is_output) {
  std::string text = std::string("**") + (is_output ? "output" : "input") + " " + variable.name + "**";
  if (!variable.description.empty()) text += ": " + variable.description;
  std::string terms;
  for (const Term& term : variable.terms) terms += (terms.empty() ? "" : ", ") + term.name;
  text += "\n\nrange " + range_text(variable) + "; " + std::to_string(variable.terms.size()) + " term" +
          (variable.terms.size() == 1 ? "" : "s") + (terms.empty() ? "" : ": " + terms);
  std::size_t rules = 0;
  const int index = is_output ? system.find_output(variable.name) : system.find_input(variable.name);
  for (const Rule& rule : system.rules)
    for (const Clause& clause : is_output ? rule.consequent : rule.antecedent)
      if (clause.variable == index) ++rules;
  text += "\n\nnamed by " + std::to_string(rules) + " of " + std::to_string(system.rules.size()) + " rules";
  return text;
}

std::string family_hover_text(const std::string& written) {
  bool alias = false;
  const ast::FamilySignature* family = ast::find_family_or_alias(written, &alias);
  if (!family) {
    // A MATLAB name that is also fmpc's spelling of another family (`constant`, `linear`) or one fmpc lacks.
    const std::optional<MfKind> kind = mf_kind_from_matlab_name(written);
    if (!kind) return "";
    family = &ast::family_of(*kind);
    alias = true;
  }
  std::string parameters;
  for (const char* parameter : family->parameters) parameters += (parameters.empty() ? "" : ", ") + std::string(parameter);
  if (family->kind == MfKind::Linear) parameters = "INPUT coefficient ..., offset";
  std::string text = "`" + std::string(family->name) + "(" + parameters + ")`";
  if (alias && written != family->name) text += ": MATLAB's name for fmpc's `" + std::string(family->name) + "`";
  std::string matlab;
  for (const char* parameter : family->matlab_parameters) matlab += (matlab.empty() ? "" : " ") + std::string(parameter);
  text += "\n\nMATLAB: `" + std::string(matlab_name(family->kind)) + " [" + matlab + "]`";
  return text;
}

Json Document::hover(const Position& position) const {
  if (dialect_ == Dialect::Matlab) return matlab_hover(position);
  if (!outline_) return nullptr;
  const std::optional<std::size_t> token = outline_->token_at(positions_.offset(position), true);
  if (!token) return nullptr;
  const TokenRole role = outline_->role_of(*token);
  const FmpcToken& t = outline_->tokens()[*token];
  const Json range = range_json(t.range);
  switch (role.kind) {
    case TokenRole::Kind::TermName:
    case TokenRole::Kind::TermReference: return hover_term(role);
    case TokenRole::Kind::Number: return hover_number(role);
    case TokenRole::Kind::VariableName:
    case TokenRole::Kind::VariableReference: return hover_variable(role);
    case TokenRole::Kind::Hedge: return markdown_hover(hedge_text(t.text), range);
    case TokenRole::Kind::Family: {
      const std::string text = family_hover_text(t.text);
      return text.empty() ? Json(nullptr) : markdown_hover(text, range);
    }
    case TokenRole::Kind::RuleLabel: {
      if (!role.system || !role.rule) return nullptr;
      const FuzzySystem* system = lowered_system(role.system->name);
      if (system)
        for (std::size_t r = 0; r < system->rules.size(); ++r)
          if (system->rules[r].label == role.rule->label)
            return markdown_hover("**rule " + role.rule->label + "**: `" + format_rule_body(*system, r) + "`", range);
      return nullptr;
    }
    default: return nullptr;
  }
}

Json Document::hover_term(const TokenRole& role) const {
  const FmpcToken& t = outline_->tokens()[role.token];
  const Json range = range_json(t.range);
  const std::string name = unquoted_name(t);
  if (!role.variable) return nullptr;
  const FuzzySystem* system = role.system ? lowered_system(role.system->name) : nullptr;
  bool is_output = role.variable->is_output;
  const Variable* variable = system ? find_variable(*system, role.variable->name, &is_output) : nullptr;
  const int index = variable ? variable->find_term(name) : -1;
  std::string text = "**" + name + "**, a term of " + (is_output ? "output" : "input") + " **" + role.variable->name + "**";
  if (role.term) {
    // The term as written (units as the writer gave them).
    const std::vector<FmpcToken>& tokens = outline_->tokens();
    std::string written;
    for (std::size_t i = role.term->family_token; i <= role.term->last_token && role.term->family_token != role.term->name_token; ++i) {
      if (tokens[i].kind == FmpcTokenKind::Comment) continue;
      if (!written.empty() && tokens[i].begin > tokens[i - 1].end) written += ' ';
      written += tokens[i].text;
    }
    if (!written.empty()) text += "\n\n`" + written + "`";
  } else {
    text += "\n\n*no term of that name*";
  }
  if (!variable || index < 0) {
    if (role.term) text += "\n\n*Grades are shown once the system has no errors.*";
    return markdown_hover(text, range);
  }
  return markdown_hover(text + " is " + term_hover_text(*variable, variable->terms[static_cast<std::size_t>(index)]),
                        range);
}

Json Document::hover_number(const TokenRole& role) const {
  const FmpcToken& t = outline_->tokens()[role.token];
  const Json range = range_json(t.range);
  if (!role.variable || role.rule || !role.system) return nullptr;
  const FuzzySystem* system = lowered_system(role.system->name);
  bool is_output = false;
  const Variable* variable = system ? find_variable(*system, role.variable->name, &is_output) : nullptr;
  if (!variable) return nullptr;
  // A unit written after the number other than the variable's own: the value is not in the variable's unit.
  const std::vector<FmpcToken>& tokens = outline_->tokens();
  if (role.token + 1 < tokens.size()) {
    const FmpcToken& next = tokens[role.token + 1];
    if ((is_name_token(next) || next.text == "%") && next.range.line == t.range.line && unquoted_name(next) != variable->unit &&
        next.text != "," && next.text != ")" && !variable->unit.empty())
      return markdown_hover("A value in " + unquoted_name(next) + "; grades are shown for values in the unit of **" +
                                variable->name + "** (" + variable->unit + ")",
                            range);
  }
  return markdown_hover(value_hover_text(*variable, std::strtod(t.text.c_str(), nullptr)), range);
}

Json Document::hover_variable(const TokenRole& role) const {
  const FmpcToken& t = outline_->tokens()[role.token];
  const Json range = range_json(t.range);
  if (!role.variable) return markdown_hover("*no variable called " + unquoted_name(t) + " in this system*", range);
  const FuzzySystem* system = role.system ? lowered_system(role.system->name) : nullptr;
  bool is_output = role.variable->is_output;
  const Variable* variable = system ? find_variable(*system, role.variable->name, &is_output) : nullptr;
  if (!variable) {
    std::string terms;
    for (const OutlineTerm& term : role.variable->terms) terms += (terms.empty() ? "" : ", ") + term.name;
    return markdown_hover(std::string("**") + (is_output ? "output" : "input") + " " + role.variable->name +
                              "**\n\nterms: " + (terms.empty() ? "none" : terms),
                          range);
  }
  return markdown_hover(variable_hover_text(*system, *variable, is_output), range);
}

}  // namespace fmpc::lsp
