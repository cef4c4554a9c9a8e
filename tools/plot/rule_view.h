#pragma once
// MATLAB's ruleview for one input point: one row per rule, one column per input and output. An input cell shows
// the clause's membership function, the input value (a red line) and the clause's grade (the shaded part and the
// number); an output cell shows the consequent clipped by the rule's firing strength (Mamdani) or a stem at the
// rule's output value as tall as its weight (Sugeno). The last row shows each output's aggregate and the crisp
// value (the centroid for a centroid defuzzifier).
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "tools/plot/canvas.h"

namespace fmpc::plot {

struct RulePanel {
  bool present = false;            // the rule has a clause on this variable
  std::vector<double> x;           // samples over the variable's range
  std::vector<double> membership;  // the clause's curve (hedge and `not` applied)
  std::vector<double> filled;      // the shaded part: inputs min(curve, grade); outputs the clipped consequent
  double grade = std::nan("");     // inputs: the clause's grade; Sugeno outputs: the stem's height
  double marker = std::nan("");    // inputs: the input value; outputs: the crisp value or the stem's position
  std::vector<std::pair<double, double>> stems;  // Sugeno aggregate: (rule output, height in [0, 1]) per rule
};

struct RuleView {
  std::vector<std::string> title;
  std::vector<std::string> input_titles;   // "HCV = 7.6 kPa"
  std::vector<std::string> output_titles;  // "stiffness = 9.83 kPa"
  std::vector<std::string> rule_titles;    // "r3: 0.41"
  std::vector<std::vector<RulePanel>> inputs;   // [rule][input]
  std::vector<std::vector<RulePanel>> outputs;  // [rule][output]
  std::vector<RulePanel> aggregate;             // [output]: membership = the aggregate, marker = the crisp output
  std::vector<std::pair<double, double>> input_ranges;
  std::vector<std::pair<double, double>> output_ranges;
  std::string aggregate_title = "aggregate";
};

// The figure (its height grows with the rules), as PNG or SVG bytes.
std::string render_rule_view(const RuleView& view, ImageFormat format);

}  // namespace fmpc::plot
