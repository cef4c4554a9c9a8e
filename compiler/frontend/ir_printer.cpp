#include "compiler/frontend/ir_printer.h"

#include "compiler/frontend/fmpc_language.h"
#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

// The rule as canonical fmpc text, its folded grade inserted before the remaining clauses.
std::string rule_text(const FuzzySystem& system, std::size_t r) {
  const Rule& rule = system.rules[r];
  std::string body = format_rule_body(system, r);
  if (rule.folded_grade) {
    // Type-2 rules fold an interval: "<fixed [lower, upper]>".
    const std::string grade =
        rule.folded_grade_lower
            ? "[" + format_number(*rule.folded_grade_lower) + ", " + format_number(*rule.folded_grade) + "]"
            : format_number(*rule.folded_grade);
    const std::string fixed = "<fixed " + grade + ">";
    const std::size_t then = body.find("then ");
    const std::string conclusion = then == std::string::npos ? body : body.substr(then);
    if (rule.antecedent.empty()) {
      body = "if " + fixed + " " + conclusion;
    } else {
      const std::string joiner = rule.connective == Connective::And ? " and " : " or ";
      body = "if " + fixed + joiner + body.substr(body.rfind("if ", 0) == 0 ? 3 : 0);
    }
  }
  const std::string label = rule.label.empty() ? "" : rule.label + ": ";
  return "rule " + label + body;
}

}  // namespace

std::string print_ir(const FuzzySystem& system) {
  FuzzySystem header = system;
  header.rules.clear();
  RuleFile file;
  file.systems.push_back(std::move(header));
  std::string text = write_fmpc(file);
  if (!text.empty() && text.back() != '\n') text += '\n';
  text += "\n# " + std::to_string(system.rules.size()) + " rules\n";
  for (std::size_t r = 0; r < system.rules.size(); ++r) text += rule_text(system, r) + '\n';
  return text;
}

}  // namespace fmpc
