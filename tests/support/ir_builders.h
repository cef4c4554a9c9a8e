#pragma once
// Builders for IR written directly in tests (check, lint): positions are chosen per line of an imaginary file
// "t.fis" so that tests can assert exact diagnostic locations.
#include <string>
#include <utility>
#include <vector>

#include "compiler/ir/fuzzy_system.h"

namespace fmpc::testing {

inline SourceRange at(int line, int column, int end_column) {
  return SourceRange{"t.fis", line, column, line, end_column};
}

// A term on its own line: the definition spans columns 3..40, the name starts at column 3.
inline Term term(const std::string& name, MfKind kind, std::vector<double> params, int line) {
  Term t;
  t.name = name;
  t.mf.kind = kind;
  t.mf.params = std::move(params);
  t.range = at(line, 3, 40);
  t.name_range = at(line, 3, 3 + static_cast<int>(name.size()));
  return t;
}

inline Variable variable(const std::string& name, double min, double max, std::vector<Term> terms, int line) {
  Variable v;
  v.name = name;
  v.unit = "kPa";
  v.min = min;
  v.max = max;
  v.terms = std::move(terms);
  v.range = at(line, 1, 30);
  v.name_range = at(line, 7, 7 + static_cast<int>(name.size()));
  return v;
}

inline Clause clause(int variable_index, int term_index, int line, int column) {
  Clause c;
  c.variable = variable_index;
  c.term = term_index;
  c.range = at(line, column, column + 8);
  return c;
}

inline Rule rule(const std::string& label, std::vector<Clause> antecedent, std::vector<Clause> consequent, int line) {
  Rule r;
  r.label = label;
  r.antecedent = std::move(antecedent);
  r.consequent = std::move(consequent);
  r.range = at(line, 1, 60);
  return r;
}

// Two inputs, one output, four rules: valid under check_system and lint-clean.
inline FuzzySystem two_input_mamdani() {
  FuzzySystem s;
  s.name = "demo";
  s.range = at(1, 1, 12);
  s.inputs.push_back(variable("x", 0, 10,
                              {term("low", MfKind::Triangle, {-10, 0, 10}, 3),
                               term("high", MfKind::Triangle, {0, 10, 20}, 4)},
                              2));
  s.inputs.push_back(variable("y", 0, 10,
                              {term("low", MfKind::Gaussian, {3, 0}, 6), term("high", MfKind::Gaussian, {3, 10}, 7)},
                              5));
  s.outputs.push_back(variable("z", 0, 1,
                               {term("small", MfKind::Triangle, {-0.5, 0, 0.5}, 9),
                                term("medium", MfKind::Triangle, {0, 0.5, 1}, 10),
                                term("big", MfKind::Triangle, {0.5, 1, 1.5}, 11)},
                               8));
  s.rules.push_back(rule("r1", {clause(0, 0, 12, 9), clause(1, 0, 12, 25)}, {clause(0, 0, 12, 40)}, 12));
  s.rules.push_back(rule("r2", {clause(0, 0, 13, 9), clause(1, 1, 13, 25)}, {clause(0, 1, 13, 40)}, 13));
  s.rules.push_back(rule("r3", {clause(0, 1, 14, 9), clause(1, 0, 14, 25)}, {clause(0, 1, 14, 40)}, 14));
  s.rules.push_back(rule("r4", {clause(0, 1, 15, 9), clause(1, 1, 15, 25)}, {clause(0, 2, 15, 40)}, 15));
  return s;
}

}  // namespace fmpc::testing
