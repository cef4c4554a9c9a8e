#include "tools/studio/studio_evaluation.h"

#include "compiler/eval/control_surface.h"
#include "compiler/eval/evaluation_report.h"
#include "compiler/eval/rule_contributions.h"
#include "compiler/eval/system_diff.h"
#include "compiler/sema/lint.h"
#include "diagnostics/number_format.h"

namespace fmpc::studio {

Json evaluation_json(const FuzzySystem& system, const std::vector<double>& inputs) {
  const RuleContributions result = rule_contributions(system, inputs);
  const Evaluation& evaluation = result.explanation.evaluation;
  Json outputs = Json::array();
  for (std::size_t o = 0; o < system.outputs.size(); ++o) {
    const OutputContributions& out = result.outputs[o];
    const OutputExplanation& set = result.explanation.outputs[o];
    Json item;
    item["name"] = system.outputs[o].name;
    item["unit"] = system.outputs[o].unit;
    item["value"] = out.output;
    item["text"] = format_number(out.output);  // as `fmpc eval` prints it
    item["no_rule_fired"] = out.no_rule_fired;
    // The output term that describes the value best (the stage `fmpc diff` compares).
    const int stage = dominant_term(system, o, out.output);
    item["stage"] = stage < 0 ? std::string() : system.outputs[o].terms[static_cast<std::size_t>(stage)].name;
    item["method"] = out.method == ContributionMethod::ExactShare ? "exact" : "leave_one_out";
    if (o < evaluation.intervals.size())
      item["interval"] = {evaluation.intervals[o].lower, evaluation.intervals[o].upper};
    item["set"] = Json{{"x", set.x}, {"membership", set.membership}, {"membership_lower", set.membership_lower}};
    item["contributions"] = out.contribution;
    if (!out.output_without.empty()) {
      item["without"] = out.output_without;
      std::vector<bool> policy(out.policy_without.begin(), out.policy_without.end());
      item["policy_without"] = policy;
    }
    outputs.push_back(item);
  }
  DiagnosticList flags;
  report_evaluation_flags(system, inputs, std::vector<SourceRange>(inputs.size()), SourceRange{}, evaluation, flags);
  Json warnings = Json::array();
  for (const Diagnostic& d : flags.items()) warnings.push_back(d.message);
  Json json;
  json["inputs"] = inputs;
  json["outputs"] = outputs;
  json["firing"] = evaluation.firing_strengths;
  if (!evaluation.firing_lower.empty()) json["firing_lower"] = evaluation.firing_lower;
  json["warnings"] = warnings;
  return json;
}

Json surface_json(const FuzzySystem& system, std::size_t x, std::size_t y, std::size_t output,
                  const std::vector<double>& point, std::size_t resolution) {
  const ControlSurface surface = control_surface(system, x, y, output, point, resolution);
  Json json;
  json["x"] = surface.x;
  json["y"] = surface.y;
  json["z"] = surface.z;
  json["strongest_firing"] = surface.strongest_firing;
  json["threshold"] = LintOptions{}.coverage_threshold;
  json["nan_points"] = surface.nan_points;
  return json;
}

}  // namespace fmpc::studio
