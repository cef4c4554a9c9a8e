#pragma once
// Edits the studio's rule table and membership editor make to the rule file's text: each replaces only the text of
// the item it changes (a parameter's number, a rule), so that comments, layout and everything else stay as the
// user wrote them. The text must read without errors first (the items are found through the reader). Each returns
// the new text, or nullopt with `error` saying why not.
#include <optional>
#include <string>
#include <vector>

namespace fmpc::studio {

// Sets parameter `parameter` (the language's name: "mean", "peak", ...) of term `term` of variable `variable` to
// `value` in the variable's unit. A unit written on that parameter is dropped when it is not the variable's.
std::optional<std::string> set_term_parameter(const std::string& path, const std::string& text,
                                              const std::string& system, const std::string& variable,
                                              const std::string& term, const std::string& parameter, double value,
                                              std::string& error);

struct ClauseSpec {
  std::string variable;
  std::string term;
  bool negated = false;
  std::string hedge;  // "", "somewhat", "very", "extremely", "very very"
};

struct RuleSpec {
  std::vector<ClauseSpec> antecedent;
  std::vector<ClauseSpec> consequent;
  bool conjunction = true;  // and; false: or
  double weight = 1.0;
};

// Rewrites rule `rule` (0-based, of `system`) from `spec`, keeping its label.
std::optional<std::string> set_rule(const std::string& path, const std::string& text, const std::string& system,
                                    std::size_t rule, const RuleSpec& spec, std::string& error);

// Appends a rule labelled "rN" (the first free N) after the system's last rule: `spec`, or when it has no clauses,
// "if FIRST-INPUT is ITS-FIRST-TERM then FIRST-OUTPUT is ITS-FIRST-TERM" for the user to change.
std::optional<std::string> add_rule(const std::string& path, const std::string& text, const std::string& system,
                                    const RuleSpec& spec, std::string& error);

// Removes rule `rule` with its line when it has the line to itself.
std::optional<std::string> delete_rule(const std::string& path, const std::string& text, const std::string& system,
                                       std::size_t rule, std::string& error);

// The byte offset of a 1-based (line, column) in `text`; nullopt when the text has no such place.
std::optional<std::size_t> offset_of(const std::string& text, int line, int column);

}  // namespace fmpc::studio
