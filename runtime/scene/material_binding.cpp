#include "runtime/scene/material_binding.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "compiler/eval/interpreter.h"
#include "diagnostics/number_format.h"
#include "kernels/table_math.h"

namespace fmpc::sim {

std::optional<double> pascals_per_unit(const std::string& unit) {
  if (unit == "kPa") return 1000.0;
  if (unit == "Pa") return 1.0;
  if (unit == "MPa") return 1e6;
  return std::nullopt;
}

namespace {

// Pa per unit of the output `name` of `what` ("rules 'liver.fis'", "table 'liver.fzt'") at the scene's `field`
// (material.rules or material.table): the unit converted, no unit read as kPa with a warning (MATLAB files carry
// none; the liver rules' unit), any other unit an error.
std::optional<double> output_unit_scale(const std::string& unit, const std::string& name, const std::string& what,
                                        const std::string& field, const Scene& scene, DiagnosticList& diagnostics) {
  if (unit.empty()) {
    diagnostics.warning(scene.range_of(field), "assumed-unit",
                        field + ": output '" + name + "' of " + what +
                            " has no unit (MATLAB .fis files carry none); it is read as Young's modulus in kPa",
                        {"if it is in Pa or MPa, use a rule file in the fmpc language that says so (fmpc convert "
                         "--to fmpc, then give the output its unit)"});
    return 1000.0;
  }
  if (const auto scale = pascals_per_unit(unit)) return scale;
  diagnostics.error(scene.range_of(field), field + ": output '" + name + "' of " + what + " is in '" + unit +
                                               "'; Young's modulus must be in kPa, Pa or MPa",
                    {"give the output one of those units in the rule file (and recompile a table)"});
  return std::nullopt;
}

bool inside(const SceneBox& box, const Point3& p) {
  for (std::size_t i = 0; i < 3; ++i)
    if (p[i] < box.min[i] || p[i] > box.max[i]) return false;
  return true;
}

// The inputs every binding and the evaluator agree on: per evaluator input, which binding sets it.
struct ResolvedBindings {
  std::vector<const InputBinding*> by_input;  // one per evaluator input
  int strain_input = -1;
  bool per_region = false;
};

std::optional<ResolvedBindings> resolve_bindings(const std::vector<std::string>& input_names,
                                                 const std::string& evaluator, const Scene& scene,
                                                 DiagnosticList& diagnostics) {
  ResolvedBindings resolved;
  resolved.by_input.assign(input_names.size(), nullptr);
  const std::size_t errors = diagnostics.error_count();
  std::string all_inputs;
  for (const auto& name : input_names) all_inputs += (all_inputs.empty() ? "" : ", ") + name;
  for (const InputBinding& binding : scene.material.bindings) {
    const std::string field = "material.inputs." + binding.input;
    const auto found = std::find(input_names.begin(), input_names.end(), binding.input);
    if (found == input_names.end()) {
      std::vector<std::string> notes;
      if (auto suggestion = closest_name(binding.input, input_names)) notes.push_back("did you mean '" + *suggestion + "'?");
      notes.push_back("the inputs of " + evaluator + " are: " + all_inputs);
      diagnostics.error(scene.range_of(field), field + ": '" + binding.input + "' is not an input of " + evaluator, notes);
      continue;
    }
    const auto index = static_cast<std::size_t>(found - input_names.begin());
    resolved.by_input[index] = &binding;
    if (binding.kind == InputBinding::Kind::Strain) resolved.strain_input = static_cast<int>(index);
    if (binding.kind == InputBinding::Kind::PerRegion) resolved.per_region = true;
  }
  for (std::size_t i = 0; i < input_names.size(); ++i) {
    if (resolved.by_input[i]) continue;
    diagnostics.error(scene.range_of("material.inputs"),
                      "material.inputs: input '" + input_names[i] + "' of " + evaluator +
                          " is not bound; give it a number, 'strain' or {regions: [...], default: NUMBER}");
  }
  if (resolved.strain_input >= 0 && resolved.per_region) {
    diagnostics.error(scene.range_of("material.inputs"),
                      "material.inputs: a 'strain' binding cannot be combined with per-region bindings; bind the "
                      "other inputs to constants");
  }
  if (diagnostics.error_count() != errors) return std::nullopt;
  return resolved;
}

// "spring 12" or "element 12".
std::string point_name(MaterialPoint kind, std::size_t index) {
  return (kind == MaterialPoint::SpringMidpoint ? "spring " : "element ") + std::to_string(index);
}

// The value of every non-strain input at one material point, or nullopt (with an error) when a per-region input
// has no region and no default there.
std::optional<double> bound_value(const InputBinding& binding, const Point3& position, std::size_t index,
                                  MaterialPoint kind, const Scene& scene, DiagnosticList& diagnostics) {
  if (binding.kind == InputBinding::Kind::Constant) return binding.value;
  for (const RegionValue& region : binding.regions)
    if (inside(region.box, position)) return region.value;
  if (binding.has_default) return binding.value;
  const std::string field = "material.inputs." + binding.input;
  diagnostics.error(scene.range_of(field),
                    field + ": " + point_name(kind, index) +
                        (kind == MaterialPoint::SpringMidpoint ? " (midpoint " : " (centroid ") +
                        format_number(position[0]) + ", " + format_number(position[1]) + ", " +
                        format_number(position[2]) + ") lies in no region; add a region that contains it or a 'default'");
  return std::nullopt;
}

// Checks and converts the evaluator's outputs (output units) to Pa, and fills the range.
bool finish(MaterialBinding& binding, MaterialPoint kind, const Scene& scene, DiagnosticList& diagnostics) {
  std::vector<double>& values = binding.strain.empty() ? binding.modulus_per_spring : binding.strain_modulus;
  const std::string field = scene.material.source == SceneMaterial::Source::Table ? "material.table" : "material.rules";
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!(values[i] > 0.0) || !std::isfinite(values[i])) {
      const std::string where = binding.strain.empty() ? point_name(kind, i)
                                                       : "strain " + format_number(binding.strain[i]);
      diagnostics.error(scene.range_of(field), field + ": output '" + binding.output + "' is " +
                                                   format_number(values[i]) + " at " + where +
                                                   "; Young's modulus must be a positive number");
      return false;
    }
    values[i] *= binding.pascals_per_output_unit;
  }
  if (!values.empty()) {
    binding.modulus_min = *std::min_element(values.begin(), values.end());
    binding.modulus_max = *std::max_element(values.begin(), values.end());
  }
  return true;
}

void report_flags(const EvaluationFlags& flags, const FuzzySystem& system, const std::vector<double>& inputs,
                  const Scene& scene, std::vector<bool>& warned_range, bool& warned_no_fire,
                  DiagnosticList& diagnostics) {
  for (const int i : flags.inputs_out_of_range) {
    const auto index = static_cast<std::size_t>(i);
    if (warned_range[index]) continue;
    warned_range[index] = true;
    const Variable& input = system.inputs[index];
    const std::string field = "material.inputs." + input.name;
    diagnostics.warning(scene.range_of(field), "input-out-of-range",
                        field + ": " + format_number(inputs[index]) + " is outside the input's range [" +
                            format_number(input.min) + ", " + format_number(input.max) + "]; evaluated as given");
  }
  if (!flags.outputs_no_rule_fired.empty() && !warned_no_fire) {
    warned_no_fire = true;
    diagnostics.warning(scene.range_of("material.inputs"), "no-rule-fired",
                        "material.inputs: no rule of '" + system.name +
                            "' fires for some bound values; the no-fire policy gives the output");
  }
}

}  // namespace

std::optional<MaterialBinding> bind_rules(const FuzzySystem& system, int output_index, const Scene& scene,
                                          const std::vector<Point3>& points, MaterialPoint kind,
                                          DiagnosticList& diagnostics, const std::vector<int>& bound_outputs) {
  std::vector<std::string> names;
  for (const Variable& v : system.inputs) names.push_back(v.name);
  const auto resolved = resolve_bindings(names, "system '" + system.name + "'", scene, diagnostics);
  if (!resolved) return std::nullopt;
  MaterialBinding binding;
  binding.system = system.name;
  const Variable& output = system.outputs[static_cast<std::size_t>(output_index)];
  binding.output = output.name;
  const auto scale = output_unit_scale(output.unit, output.name, "system '" + system.name + "'", "material.rules",
                                       scene, diagnostics);
  if (!scale) return std::nullopt;
  binding.pascals_per_output_unit = *scale;
  Interpreter interpreter(system);
  std::vector<bool> warned_range(system.inputs.size(), false);
  bool warned_no_fire = false;
  for (const int index : bound_outputs) {
    const Variable& variable = system.outputs[static_cast<std::size_t>(index)];
    binding.bound.push_back({index, variable.name, variable.unit, true, variable.min, variable.max, {}});
  }
  // Young's modulus, then each bound output.
  std::vector<double> all_outputs;
  const auto evaluate = [&](const std::vector<double>& inputs) -> std::optional<double> {
    const Evaluation evaluation = interpreter.evaluate(inputs);
    all_outputs.clear();
    for (const BoundOutput& bound : binding.bound)
      all_outputs.push_back(evaluation.outputs[static_cast<std::size_t>(bound.index)]);
    ++binding.evaluations;
    report_flags(evaluation.flags, system, inputs, scene, warned_range, warned_no_fire, diagnostics);
    if (evaluation.flags.no_fire_error) {
      diagnostics.error(scene.range_of("material.inputs"),
                        "material.inputs: no rule of '" + system.name +
                            "' fires and its no-fire policy is 'error'; change the bound values");
      return std::nullopt;
    }
    return evaluation.outputs[static_cast<std::size_t>(output_index)];
  };

  std::vector<double> inputs(system.inputs.size(), 0.0);
  if (resolved->strain_input >= 0) {
    const auto strain_index = static_cast<std::size_t>(resolved->strain_input);
    const Variable& strain_input = system.inputs[strain_index];
    StrainAxis axis{strain_input.min, strain_input.max, 101};
    if (scene.material.strain_axis) axis = *scene.material.strain_axis;
    for (std::size_t i = 0; i < inputs.size(); ++i)
      if (i != strain_index) inputs[i] = resolved->by_input[i]->value;
    for (int p = 0; p < axis.points; ++p) {
      const double strain =
          p + 1 == axis.points ? axis.max : axis.min + (axis.max - axis.min) * p / (axis.points - 1);
      inputs[strain_index] = strain;
      const auto value = evaluate(inputs);
      if (!value) return std::nullopt;
      binding.strain.push_back(strain);
      binding.strain_modulus.push_back(*value);
    }
  } else {
    // Per distinct input values: Young's modulus, then each bound output.
    std::map<std::vector<double>, std::vector<double>> cache;
    binding.modulus_per_spring.resize(points.size());
    for (BoundOutput& bound : binding.bound) bound.values.resize(points.size());
    for (std::size_t s = 0; s < points.size(); ++s) {
      for (std::size_t i = 0; i < inputs.size(); ++i) {
        const auto value = bound_value(*resolved->by_input[i], points[s], s, kind, scene, diagnostics);
        if (!value) return std::nullopt;
        inputs[i] = *value;
      }
      auto cached = cache.find(inputs);
      if (cached == cache.end()) {
        const auto value = evaluate(inputs);
        if (!value) return std::nullopt;
        std::vector<double> values = {*value};
        values.insert(values.end(), all_outputs.begin(), all_outputs.end());
        cached = cache.emplace(inputs, std::move(values)).first;
      }
      binding.modulus_per_spring[s] = cached->second[0];
      for (std::size_t b = 0; b < binding.bound.size(); ++b) binding.bound[b].values[s] = cached->second[b + 1];
    }
  }
  if (!finish(binding, kind, scene, diagnostics)) return std::nullopt;
  return binding;
}

std::optional<MaterialBinding> bind_table(const LookupTable& table, int output_index, const Scene& scene,
                                          const std::vector<Point3>& points, MaterialPoint kind,
                                          DiagnosticList& diagnostics, const std::vector<int>& bound_outputs) {
  std::vector<std::string> names;
  for (const TableAxis& axis : table.axes) names.push_back(axis.input_name);
  const auto resolved = resolve_bindings(names, "table '" + table.system_name + "'", scene, diagnostics);
  if (!resolved) return std::nullopt;
  MaterialBinding binding;
  binding.system = table.system_name;
  binding.output = table.output_names[static_cast<std::size_t>(output_index)];
  const auto unit = static_cast<std::size_t>(output_index);
  const auto scale = output_unit_scale(unit < table.output_units.size() ? table.output_units[unit] : std::string(),
                                       binding.output, "table '" + table.system_name + "'", "material.table", scene,
                                       diagnostics);
  if (!scale) return std::nullopt;
  binding.pascals_per_output_unit = *scale;
  std::vector<const double*> breakpoints;
  std::vector<int> counts;
  const TableView<double> view = view_of(table, breakpoints, counts);
  std::vector<double> all_outputs(table.output_names.size());
  const auto evaluate = [&](const std::vector<double>& query) {
    interpolate_table(view, query.data(), all_outputs.data());
    ++binding.evaluations;
    return all_outputs[static_cast<std::size_t>(output_index)];
  };
  std::vector<double> query(table.axes.size(), 0.0);
  if (resolved->strain_input >= 0) {
    const auto strain_index = static_cast<std::size_t>(resolved->strain_input);
    for (std::size_t i = 0; i < query.size(); ++i)
      if (i != strain_index) query[i] = resolved->by_input[i]->value;
    for (const double strain : table.axes[strain_index].breakpoints) {
      query[strain_index] = strain;
      binding.strain.push_back(strain);
      binding.strain_modulus.push_back(evaluate(query));
    }
  } else {
    binding.modulus_per_spring.resize(points.size());
    for (const int index : bound_outputs) {
      const auto i = static_cast<std::size_t>(index);
      binding.bound.push_back({index, table.output_names[i],
                               i < table.output_units.size() ? table.output_units[i] : std::string(), false, 0.0, 0.0,
                               std::vector<double>(points.size())});
    }
    for (std::size_t s = 0; s < points.size(); ++s) {
      for (std::size_t i = 0; i < query.size(); ++i) {
        const auto value = bound_value(*resolved->by_input[i], points[s], s, kind, scene, diagnostics);
        if (!value) return std::nullopt;
        query[i] = *value;
      }
      binding.modulus_per_spring[s] = evaluate(query);
      for (BoundOutput& bound : binding.bound) bound.values[s] = all_outputs[static_cast<std::size_t>(bound.index)];
    }
  }
  if (!finish(binding, kind, scene, diagnostics)) return std::nullopt;
  return binding;
}

}  // namespace fmpc::sim
