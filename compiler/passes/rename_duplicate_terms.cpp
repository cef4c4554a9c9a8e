#include "compiler/passes/rename_duplicate_terms.h"

#include <set>

namespace fmpc {

namespace {

void rename_in(Variable& variable, const char* role, std::vector<std::string>& renames) {
  std::set<std::string> used;
  for (const Term& term : variable.terms) used.insert(term.name);
  std::set<std::string> seen;
  for (std::size_t t = 0; t < variable.terms.size(); ++t) {
    Term& term = variable.terms[t];
    if (seen.insert(term.name).second) continue;
    std::string candidate;
    for (int suffix = 2;; ++suffix) {
      candidate = term.name + "_" + std::to_string(suffix);
      if (!used.count(candidate)) break;
    }
    renames.push_back(std::string(role) + " '" + variable.name + "': term " + std::to_string(t + 1) + " '" +
                      term.name + "' -> '" + candidate + "'");
    used.insert(candidate);
    seen.insert(candidate);
    term.name = candidate;
  }
}

}  // namespace

std::vector<std::string> rename_duplicate_terms(FuzzySystem& system) {
  std::vector<std::string> renames;
  for (Variable& input : system.inputs) rename_in(input, "input", renames);
  for (Variable& output : system.outputs) rename_in(output, "output", renames);
  return renames;
}

}  // namespace fmpc
