#pragma once
// What the fmpc language's tests share (tests/unit/fmpc_language_test.cpp, fmpc_writer_test.cpp): reading text that
// must load cleanly, fmt's output, the first field in which two systems differ, and the liver example.
#include <catch2/catch.hpp>
#include <algorithm>
#include <sstream>
#include <string>
#include <vector>

#include "compiler/frontend/fmpc_language.h"

namespace fmpc::testing {

inline RuleFile read_ok(const std::string& text) {
  DiagnosticList diagnostics;
  RuleFile file = read_fmpc("t.fis", text, diagnostics);
  SourceFiles sources;
  sources.add("t.fis", text);
  INFO(render_all(diagnostics, sources));
  REQUIRE(diagnostics.empty());
  return file;
}

inline FuzzySystem read_one(const std::string& text) {
  RuleFile file = read_ok(text);
  REQUIRE(file.systems.size() == 1);
  return file.systems.front();
}

inline std::string format_ok(const std::string& text) {
  DiagnosticList diagnostics;
  std::optional<std::string> formatted = format_fmpc("t.fis", text, diagnostics);
  INFO(render_all(diagnostics, SourceFiles{}));
  REQUIRE(formatted.has_value());
  return *formatted;
}

// The first field in which two systems differ (source ranges ignored), or "" when they are the same.
inline std::string difference(const FuzzySystem& a, const FuzzySystem& b) {
  std::ostringstream out;
  const auto diff = [&](bool differs, const std::string& what) {
    if (differs && out.str().empty()) out << what;
  };
  diff(a.name != b.name, "name");
  diff(a.description != b.description, "description");
  diff(a.type != b.type, "type");
  diff(a.and_method != b.and_method, "and");
  diff(a.or_method != b.or_method, "or");
  diff(a.implication != b.implication, "implication");
  diff(a.aggregation != b.aggregation, "aggregation");
  diff(a.defuzzifier != b.defuzzifier, "defuzzifier");
  diff(a.samples != b.samples, "samples");
  diff(a.no_fire != b.no_fire, "no_fire");
  diff(a.no_fire_value != b.no_fire_value, "no_fire_value");
  const auto variables = [&](const std::vector<Variable>& x, const std::vector<Variable>& y, const std::string& kind) {
    diff(x.size() != y.size(), kind + " count");
    for (std::size_t i = 0; i < std::min(x.size(), y.size()); ++i) {
      const std::string where = kind + " " + x[i].name;
      diff(x[i].name != y[i].name, where + " name");
      diff(x[i].description != y[i].description, where + " description");
      diff(x[i].unit != y[i].unit, where + " unit");
      diff(x[i].min != y[i].min || x[i].max != y[i].max, where + " range");
      diff(x[i].terms.size() != y[i].terms.size(), where + " term count");
      for (std::size_t t = 0; t < std::min(x[i].terms.size(), y[i].terms.size()); ++t) {
        diff(x[i].terms[t].name != y[i].terms[t].name, where + " term name " + x[i].terms[t].name);
        diff(x[i].terms[t].mf.kind != y[i].terms[t].mf.kind, where + " kind of " + x[i].terms[t].name);
        diff(x[i].terms[t].mf.params != y[i].terms[t].mf.params, where + " params of " + x[i].terms[t].name);
      }
    }
  };
  variables(a.inputs, b.inputs, "input");
  variables(a.outputs, b.outputs, "output");
  diff(a.rules.size() != b.rules.size(), "rule count");
  for (std::size_t r = 0; r < std::min(a.rules.size(), b.rules.size()); ++r) {
    const Rule& x = a.rules[r];
    const Rule& y = b.rules[r];
    const std::string where = "rule " + std::to_string(r + 1);
    diff(x.label != y.label, where + " label");
    diff(x.weight != y.weight, where + " weight");
    diff(x.antecedent.size() > 1 && x.connective != y.connective, where + " connective");
    const auto clauses = [&](const std::vector<Clause>& p, const std::vector<Clause>& q, const std::string& part) {
      diff(p.size() != q.size(), where + " " + part + " size");
      for (std::size_t c = 0; c < std::min(p.size(), q.size()); ++c)
        diff(p[c].variable != q[c].variable || p[c].term != q[c].term || p[c].negated != q[c].negated ||
                 p[c].hedge != q[c].hedge,
             where + " " + part + " clause " + std::to_string(c + 1));
    };
    clauses(x.antecedent, y.antecedent, "antecedent");
    clauses(x.consequent, y.consequent, "consequent");
  }
  return out.str();
}

inline const char* const kLiver = R"(# Liver stiffness from FibroScan readings
system liver "Fuzzy MSM parameter controller"
  type mamdani
  and min
  or max
  implication min
  aggregation max
  defuzzify centroid samples 101
  when no rule fires: midrange

input HCV "FibroScan stiffness, hepatitis C" in [0, 75] kPa
  F2 is gauss(mean 7.64, sd 0.91)
  F3 is gauss(sd 0.38, mean 9.72)
  F4 is gauss(mean 13.81, sd 2.38)

input HBV in [0, 75] kPa
  "F0-F1" is triangle(start -20, peak 0, end 20)
  F2 is trapezoid(start 5, top_start 6, top_end 8, end 9)

output stiffness "Liver stiffness" in [0, 75] kPa
  "F0-F1" is gauss(mean 5300 Pa, sd 1.45 kPa)
  F2 is gauss(mean 7.64, sd 0.91)
  F3 is gauss(mean 9.72, sd 0.38)

output damping in [0, 1] dimensionless
  low is linear_z(start 0.1, end 0.5)

rule r1: if HCV is F2 and HBV is "F0-F1" then stiffness is "F0-F1"
rule r7: if HCV is not F4 or HBV is very F2 then stiffness is F2 weight 0.5
rule: if HCV is somewhat F3 then stiffness is F3 and damping is low
rule r9: if HBV is extremely F2 and HCV is not very very F4 then stiffness is not somewhat F2
)";

}  // namespace fmpc::testing
