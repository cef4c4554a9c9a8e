#include "compiler/passes/drop_dead_terms.h"

#include <string>

namespace fmpc {

namespace {

// Keeps the used terms of `variables`; returns per variable the old -> new term index (-1 = dropped).
std::vector<std::vector<int>> drop_unused(std::vector<Variable>& variables, const std::vector<std::vector<bool>>& used,
                                          const char* role, std::vector<std::string>& details) {
  std::vector<std::vector<int>> renumbering(variables.size());
  for (std::size_t v = 0; v < variables.size(); ++v) {
    std::vector<Term> kept;
    for (std::size_t t = 0; t < variables[v].terms.size(); ++t) {
      if (!used[v][t]) {
        renumbering[v].push_back(-1);
        details.push_back(std::string(role) + " '" + variables[v].name + "': term '" + variables[v].terms[t].name +
                          "' (no rule names it)");
        continue;
      }
      renumbering[v].push_back(static_cast<int>(kept.size()));
      kept.push_back(std::move(variables[v].terms[t]));
    }
    variables[v].terms = std::move(kept);
  }
  return renumbering;
}

std::vector<std::vector<bool>> usage(const std::vector<Variable>& variables) {
  std::vector<std::vector<bool>> used;
  for (const Variable& v : variables) used.emplace_back(v.terms.size(), false);
  return used;
}

}  // namespace

PassReport drop_dead_terms(FuzzySystem& system) {
  PassReport report;
  report.pass = "drop_dead_terms";
  std::vector<std::vector<bool>> inputs_used = usage(system.inputs), outputs_used = usage(system.outputs);
  for (const Rule& rule : system.rules) {
    for (const Clause& c : rule.antecedent)
      inputs_used[static_cast<std::size_t>(c.variable)][static_cast<std::size_t>(c.term)] = true;
    for (const Clause& c : rule.consequent)
      outputs_used[static_cast<std::size_t>(c.variable)][static_cast<std::size_t>(c.term)] = true;
  }
  const auto input_numbers = drop_unused(system.inputs, inputs_used, "input", report.details);
  const auto output_numbers = drop_unused(system.outputs, outputs_used, "output", report.details);
  for (Rule& rule : system.rules) {
    for (Clause& c : rule.antecedent)
      c.term = input_numbers[static_cast<std::size_t>(c.variable)][static_cast<std::size_t>(c.term)];
    for (Clause& c : rule.consequent)
      c.term = output_numbers[static_cast<std::size_t>(c.variable)][static_cast<std::size_t>(c.term)];
  }
  for (std::size_t i = 0; i < system.inputs.size(); ++i)
    if (system.inputs[i].terms.empty())
      report.details.push_back("input '" + system.inputs[i].name +
                               "' is named in no rule's antecedent");
  std::size_t removed = 0;
  for (const auto& numbers : {input_numbers, output_numbers})
    for (const auto& variable : numbers)
      for (int n : variable) removed += n < 0 ? 1 : 0;
  report.summary = "removed " + std::to_string(removed) + " terms";
  report.error_bound = 0.0;
  report.error_note = "exact";
  return report;
}

}  // namespace fmpc
