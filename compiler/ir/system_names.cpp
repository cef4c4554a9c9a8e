#include "compiler/ir/system_names.h"

namespace fmpc {

SystemNames::SystemNames(const FuzzySystem& system)
    : inputs_(index_of(system.inputs)), outputs_(index_of(system.outputs)) {}

SystemNames::Role SystemNames::index_of(const std::vector<Variable>& variables) {
  Role role;
  role.names.reserve(variables.size());
  role.term_names.resize(variables.size());
  role.term_index.resize(variables.size());
  for (std::size_t v = 0; v < variables.size(); ++v) {
    role.names.push_back(variables[v].name);
    role.index.emplace(variables[v].name, static_cast<int>(v));  // keeps the first of two equal names
    for (std::size_t t = 0; t < variables[v].terms.size(); ++t) {
      role.term_names[v].push_back(variables[v].terms[t].name);
      role.term_index[v].emplace(variables[v].terms[t].name, static_cast<int>(t));
    }
  }
  return role;
}

int SystemNames::variable(bool output, const std::string& name) const {
  const auto& index = role(output).index;
  const auto found = index.find(name);
  return found == index.end() ? -1 : found->second;
}

int SystemNames::term(bool output, int variable, const std::string& name) const {
  const Role& r = role(output);
  if (variable < 0 || static_cast<std::size_t>(variable) >= r.term_index.size()) return -1;
  const auto& index = r.term_index[static_cast<std::size_t>(variable)];
  const auto found = index.find(name);
  return found == index.end() ? -1 : found->second;
}

const std::vector<std::string>& SystemNames::variable_names(bool output) const { return role(output).names; }

const std::vector<std::string>& SystemNames::term_names(bool output, int variable) const {
  static const std::vector<std::string> none;
  const Role& r = role(output);
  if (variable < 0 || static_cast<std::size_t>(variable) >= r.term_names.size()) return none;
  return r.term_names[static_cast<std::size_t>(variable)];
}

std::string name_list_text(const std::vector<std::string>& names, std::size_t shown) {
  std::string text;
  for (std::size_t i = 0; i < names.size() && i < shown; ++i) text += (i ? ", " : "") + names[i];
  if (names.size() > shown) text += ", ... and " + std::to_string(names.size() - shown) + " more";
  return text;
}

}  // namespace fmpc
