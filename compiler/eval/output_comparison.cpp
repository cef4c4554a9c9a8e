#include "compiler/eval/output_comparison.h"

#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

std::string policy_text(const FuzzySystem& system) {
  switch (system.no_fire) {
    case NoFirePolicy::Midrange: return "midrange";
    case NoFirePolicy::Value: return "value " + format_number(system.no_fire_value);
    case NoFirePolicy::Error: return "error";
  }
  return "midrange";
}

std::string samples_text(int samples) { return samples == 0 ? "exact" : std::to_string(samples); }

}  // namespace

std::vector<std::string> setting_changes(const FuzzySystem& a, const FuzzySystem& b) {
  std::vector<std::string> changes;
  const auto differ = [&](const std::string& what, const std::string& x, const std::string& y) {
    if (x != y) changes.push_back(what + " changes from " + x + " to " + y);
  };
  differ("the system type", to_string(a.type), to_string(b.type));
  differ("the system", a.interval_type2 ? "interval type-2" : "type-1", b.interval_type2 ? "interval type-2" : "type-1");
  if (a.interval_type2 && b.interval_type2)
    differ("the type reduction", to_string(a.type_reduction), to_string(b.type_reduction));
  differ("the defuzzifier", to_string(a.defuzzifier), to_string(b.defuzzifier));
  differ("the and method", to_string(a.and_method), to_string(b.and_method));
  differ("the or method", to_string(a.or_method), to_string(b.or_method));
  if (a.type == SystemType::Mamdani) {
    differ("the implication", to_string(a.implication), to_string(b.implication));
    differ("the aggregation", to_string(a.aggregation), to_string(b.aggregation));
    differ("the output sampling", samples_text(a.samples), samples_text(b.samples));
  }
  differ("the no-fire policy", policy_text(a), policy_text(b));
  return changes;
}

namespace {

// The settings that decide outputs, each as "what: intended -> written" where they differ, and the variables' ranges
// (by position).
void compare_settings(const FuzzySystem& a, const FuzzySystem& b, std::vector<std::string>& changes) {
  for (std::string& change : setting_changes(a, b)) changes.push_back(std::move(change));
  const auto differ = [&](const std::string& what, const std::string& x, const std::string& y) {
    if (x != y) changes.push_back(what + " changes from " + x + " to " + y);
  };
  for (const auto* variables : {&a.inputs, &a.outputs}) {
    const auto* others = variables == &a.inputs ? &b.inputs : &b.outputs;
    const char* role = variables == &a.inputs ? "input" : "output";
    for (std::size_t i = 0; i < variables->size() && i < others->size(); ++i) {
      const Variable& x = (*variables)[i];
      const Variable& y = (*others)[i];
      differ(std::string("the range of ") + role + " '" + x.name + "'",
             "[" + format_number(x.min) + ", " + format_number(x.max) + "]",
             "[" + format_number(y.min) + ", " + format_number(y.max) + "]");
    }
  }
}

std::string point_text(const FuzzySystem& system, const std::vector<double>& x) {
  std::string text;
  for (std::size_t i = 0; i < x.size(); ++i)
    text += (i ? ", " : "") + system.inputs[i].name + " = " + format_number(x[i]);
  return text;
}

std::vector<std::vector<double>> probe_points(const FuzzySystem& system, std::size_t random_points) {
  const std::size_t d = system.inputs.size();
  std::vector<std::vector<double>> points;
  std::vector<double> middle;
  for (const Variable& input : system.inputs) middle.push_back((input.min + input.max) / 2.0);
  points.push_back(middle);
  if (d <= 8)
    for (std::size_t corner = 0; corner < (std::size_t{1} << d); ++corner) {
      std::vector<double> x(d);
      for (std::size_t i = 0; i < d; ++i) x[i] = corner >> i & 1 ? system.inputs[i].max : system.inputs[i].min;
      points.push_back(x);
    }
  for (std::size_t i = 0; i < d; ++i)
    for (int k = 0; k <= 100; ++k) {
      std::vector<double> x = middle;
      x[i] = system.inputs[i].min + (system.inputs[i].max - system.inputs[i].min) * k / 100.0;
      points.push_back(x);
    }
  std::mt19937_64 random(20261124);
  for (std::size_t p = 0; p < random_points; ++p) {
    std::vector<double> x(d);
    for (std::size_t i = 0; i < d; ++i)
      x[i] = system.inputs[i].min +
             (system.inputs[i].max - system.inputs[i].min) * (static_cast<double>(random() >> 11) * 0x1.0p-53);
    points.push_back(x);
  }
  return points;
}

bool same(double a, double b, double tolerance) {
  return (std::isnan(a) && std::isnan(b)) || a == b || std::fabs(a - b) <= tolerance;
}

}  // namespace

std::vector<std::string> output_changes(const FuzzySystem& intended, const FuzzySystem& written,
                                        const OutputComparison& comparison) {
  std::vector<std::string> changes;
  if (comparison.settings) compare_settings(intended, written, changes);
  if (intended.inputs.size() != written.inputs.size() || intended.outputs.size() != written.outputs.size()) {
    changes.push_back("the numbers of inputs and outputs change from " + std::to_string(intended.inputs.size()) +
                      " and " + std::to_string(intended.outputs.size()) + " to " +
                      std::to_string(written.inputs.size()) + " and " + std::to_string(written.outputs.size()));
    return changes;
  }
  Interpreter a(intended, comparison.evaluation), b(written, comparison.evaluation);
  // Per output: the crisp value, then the type-2 interval's lower and upper ends.
  struct Largest {
    double difference = 0.0;
    std::vector<double> at;
    double from = 0.0, to = 0.0;
  };
  std::vector<std::array<Largest, 3>> largest(intended.outputs.size());
  const std::vector<std::vector<double>> points = probe_points(intended, comparison.random_points);
  for (std::size_t k = 0; k < points.size(); ++k) {
    const std::vector<double>& x = points[k];
    if (comparison.progress) comparison.progress(k, points.size());
    const Evaluation p = a.evaluate(x), q = b.evaluate(x);
    for (std::size_t o = 0; o < intended.outputs.size(); ++o) {
      const double range = intended.outputs[o].max - intended.outputs[o].min;
      const double tolerance = 1e-12 * std::max(range, 1e-300);
      const auto consider = [&](std::size_t which, double from, double to) {
        if (same(from, to, tolerance)) return;
        const double difference = std::isnan(from) || std::isnan(to) ? std::numeric_limits<double>::infinity()
                                                                      : std::fabs(from - to);
        if (difference > largest[o][which].difference) largest[o][which] = Largest{difference, x, from, to};
      };
      consider(0, p.outputs[o], q.outputs[o]);
      if (o < p.intervals.size() && o < q.intervals.size()) {
        consider(1, p.intervals[o].lower, q.intervals[o].lower);
        consider(2, p.intervals[o].upper, q.intervals[o].upper);
      }
    }
  }
  static const char* const kWhich[] = {"", " (lower end of its interval)", " (upper end of its interval)"};
  for (std::size_t o = 0; o < intended.outputs.size(); ++o)
    for (std::size_t which = 0; which < 3; ++which) {
      const Largest& l = largest[o][which];
      if (l.at.empty()) continue;
      const Variable& output = intended.outputs[o];
      changes.push_back("output '" + output.name + "'" + kWhich[which] + " changes by up to " +
                        format_number(l.difference) + (output.unit.empty() ? "" : " " + output.unit) + " (from " +
                        format_number(l.from) + " to " + format_number(l.to) + " at " + point_text(intended, l.at) +
                        ")");
    }
  return changes;
}

std::vector<std::string> name_changes(const FuzzySystem& intended, const FuzzySystem& written) {
  std::vector<std::string> changes;
  // "input 'a\"b' is written as 'a'b'", "term 'x' of output 'z' is written as ..."
  const auto compare = [&](const std::string& what, const std::string& from, const std::string& to,
                           const std::string& of = "") {
    if (from != to) changes.push_back(what + " '" + from + "'" + of + " is written as '" + to + "'");
  };
  compare("system", intended.name, written.name);
  const auto variables = [&](const std::vector<Variable>& from, const std::vector<Variable>& to, const char* role) {
    for (std::size_t v = 0; v < from.size() && v < to.size(); ++v) {
      compare(role, from[v].name, to[v].name);
      for (std::size_t t = 0; t < from[v].terms.size() && t < to[v].terms.size(); ++t)
        compare("term", from[v].terms[t].name, to[v].terms[t].name,
                " of " + std::string(role) + " '" + from[v].name + "'");
    }
  };
  variables(intended.inputs, written.inputs, "input");
  variables(intended.outputs, written.outputs, "output");
  return changes;
}

}  // namespace fmpc
