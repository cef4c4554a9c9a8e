#pragma once
// A system's variable and term names, hashed once, for the readers that resolve names in rules (the fmpc language,
// FLL, FCL). A linear search per clause made name resolution quadratic: a valid 7 MiB FLL file of 120,000 terms and
// 100,000 rules took 207 s to check. Lookups here are constant time, and the name lists that errors quote ("did you
// mean", "terms of X: ...") are built once per variable, not once per error.
#include <string>
#include <unordered_map>
#include <vector>

#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

class SystemNames {
 public:
  // The names of `system` as they are now: build it again after adding variables or terms.
  explicit SystemNames(const FuzzySystem& system);

  // Index of the input or output called `name`, or -1; the first of two equal names, as FuzzySystem::find_input.
  int variable(bool output, const std::string& name) const;
  // Index of the term called `name` of that variable, or -1; the first of two equal names, as Variable::find_term.
  int term(bool output, int variable, const std::string& name) const;

  // Every input's (output's) name in order, and every term's of one variable, for "did you mean" and lists.
  const std::vector<std::string>& variable_names(bool output) const;
  const std::vector<std::string>& term_names(bool output, int variable) const;

 private:
  struct Role {
    std::vector<std::string> names;
    std::unordered_map<std::string, int> index;
    std::vector<std::vector<std::string>> term_names;
    std::vector<std::unordered_map<std::string, int>> term_index;
  };
  const Role& role(bool output) const { return output ? outputs_ : inputs_; }
  static Role index_of(const std::vector<Variable>& variables);

  Role inputs_, outputs_;
};

// "a, b, c" for at most `shown` names, then "... and N more": a list in a message stays short whatever the file
// holds (a variable of 120,000 terms).
std::string name_list_text(const std::vector<std::string>& names, std::size_t shown = 20);

}  // namespace fmpc
