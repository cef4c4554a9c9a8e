#include "compiler/passes/pipeline.h"

#include <cmath>

#include "compiler/frontend/ir_printer.h"
#include "diagnostics/number_format.h"
#include "compiler/passes/drop_dead_terms.h"
#include "compiler/passes/fuse_consequents.h"
#include "compiler/passes/prune_rules.h"
#include "compiler/passes/specialize.h"

namespace fmpc {

namespace {

std::vector<std::string> input_names(const FuzzySystem& system) {
  std::vector<std::string> names;
  for (const Variable& v : system.inputs) names.push_back(v.name);
  return names;
}

// The input named `name`, or -1 after reporting it.
int resolve_input(const FuzzySystem& system, const std::string& name, const SourceRange& origin,
                  DiagnosticList& diagnostics) {
  const int index = system.find_input(name);
  if (index >= 0) return index;
  std::vector<std::string> notes;
  if (auto suggestion = closest_name(name, input_names(system))) notes.push_back("did you mean '" + *suggestion + "'?");
  std::string all;
  for (const std::string& n : input_names(system)) all += (all.empty() ? "" : ", ") + n;
  notes.push_back("the inputs of '" + system.name + "' are: " + all);
  diagnostics.error(origin, "'" + name + "' is not an input of system '" + system.name + "'", notes);
  return -1;
}

bool wants_dump(const PipelineOptions& options, const std::string& pass) {
  for (const std::string& name : options.dump_after)
    if (name == pass || name == "all") return true;
  return false;
}

}  // namespace

double CompileResult::error_bound() const {
  double total = 0.0;
  for (const PassReport& report : reports) total += report.error_bound;
  return total;
}

const std::vector<std::string>& pipeline_pass_names() {
  static const std::vector<std::string> names = {"specialize", "prune_rules", "fuse_consequents", "drop_dead_terms"};
  return names;
}

std::optional<CompileResult> run_pipeline(const FuzzySystem& source, const Bindings& bindings,
                                          const PipelineOptions& options, DiagnosticList& diagnostics) {
  const std::size_t errors_before = diagnostics.error_count();
  if (source.interval_type2 && !options.interval_type2) {
    diagnostics.error(source.range,
                      "system '" + source.name + "' is interval type-2, which this back end does not take",
                      {"evaluate it with fmpc eval, or compile it with fmpc compile --target cpp|cuda|table"});
    return std::nullopt;
  }
  for (const std::string& pass : options.dump_after) {
    if (pass == "all") continue;
    bool known = false;
    for (const std::string& name : pipeline_pass_names()) known = known || name == pass;
    if (known) continue;
    std::vector<std::string> notes;
    if (auto suggestion = closest_name(pass, pipeline_pass_names())) notes.push_back("did you mean '" + *suggestion + "'?");
    notes.push_back("the passes are: specialize, prune_rules, fuse_consequents, drop_dead_terms (or all)");
    diagnostics.error(SourceRange{"command line", 0, 0, 0, 0}, "no pass named '" + pass + "'", notes);
  }

  const std::size_t input_count = source.inputs.size();
  std::vector<bool> bound(input_count, false);
  std::vector<std::optional<double>> fixed_value(input_count);
  std::vector<int> points(input_count, 0);
  for (const FixedInput& binding : bindings.fixed) {
    const int index = resolve_input(source, binding.name, binding.origin, diagnostics);
    if (index < 0) continue;
    const Variable& input = source.inputs[static_cast<std::size_t>(index)];
    if (bound[static_cast<std::size_t>(index)]) {
      diagnostics.error(binding.origin, "input '" + binding.name + "' is bound twice");
      continue;
    }
    bound[static_cast<std::size_t>(index)] = true;
    if (std::isnan(binding.value)) {
      diagnostics.error(binding.origin, "input '" + binding.name + "' is fixed at NaN",
                        {"give a number within [" + format_number(input.min) + ", " + format_number(input.max) + "]"});
      continue;
    }
    if (binding.value < input.min || binding.value > input.max)
      diagnostics.warning(binding.origin, "input-out-of-range",
                          "input '" + input.name + "' = " + format_number(binding.value) + " is outside its range [" +
                              format_number(input.min) + ", " + format_number(input.max) + "]; evaluated as given");
    fixed_value[static_cast<std::size_t>(index)] = binding.value;
  }
  for (const VariedInput& binding : bindings.varied) {
    const int index = resolve_input(source, binding.name, binding.origin, diagnostics);
    if (index < 0) continue;
    if (bound[static_cast<std::size_t>(index)]) {
      diagnostics.error(binding.origin, fixed_value[static_cast<std::size_t>(index)]
                                            ? "input '" + binding.name + "' is both fixed and varied"
                                            : "input '" + binding.name + "' is bound twice");
      continue;
    }
    bound[static_cast<std::size_t>(index)] = true;
    if (binding.points != 0 && (binding.points < 2 || binding.points > kMaxAxisPoints)) {
      diagnostics.error(binding.origin,
                        "an axis takes 2 to " + std::to_string(kMaxAxisPoints) + " points, not " +
                            std::to_string(binding.points),
                        {"give " + binding.name + " 2 or more points, or leave the count out to have it chosen"});
      continue;
    }
    points[static_cast<std::size_t>(index)] = binding.points;
  }
  // prune_rules bounds the centroid's change for type-1 sets only (prune_rules.h).
  if (source.interval_type2 && options.prune_epsilon > 0.0)
    diagnostics.error(SourceRange{"command line", 0, 0, 0, 0},
                      "--prune-epsilon " + format_number(options.prune_epsilon) + " needs an error bound, and none "
                      "is known for interval type-2 system '" + source.name + "'",
                      {"leave it out: the rules that cannot fire are removed exactly without it"});
  std::size_t varying = 0;
  for (std::size_t i = 0; i < input_count; ++i) varying += fixed_value[i] ? 0 : 1;
  if (varying == 0 && diagnostics.error_count() == errors_before)
    diagnostics.error(SourceRange{"command line", 0, 0, 0, 0}, "every input of '" + source.name + "' is fixed",
                      {"leave at least one input varying (--vary NAME), or evaluate the point with fmpc eval"});
  if (diagnostics.error_count() > errors_before) return std::nullopt;

  CompileResult result;
  result.system = source;
  for (std::size_t r = 0; r < result.system.rules.size(); ++r)
    if (result.system.rules[r].label.empty()) result.system.rules[r].label = "r" + std::to_string(r + 1);
  std::vector<InputValue> fixed;
  for (std::size_t i = 0; i < input_count; ++i) {
    if (fixed_value[i]) {
      fixed.push_back({static_cast<int>(i), *fixed_value[i]});
      result.fixed.emplace_back(static_cast<int>(i), *fixed_value[i]);
    } else {
      result.source_inputs.push_back(static_cast<int>(i));
      result.axis_points.push_back(points[i]);
    }
  }

  const auto record = [&](PassReport report) {
    if (wants_dump(options, report.pass)) result.dumps.push_back({report.pass, print_ir(result.system)});
    result.reports.push_back(std::move(report));
  };
  record(specialize(result.system, fixed));
  record(prune_rules(result.system, options.prune_epsilon));
  record(fuse_consequents(result.system));
  record(drop_dead_terms(result.system));
  return result;
}

}  // namespace fmpc
