#include "runtime/scene/parameter_binding.h"

#include <algorithm>
#include <cmath>

#include "diagnostics/number_format.h"

namespace fmpc::sim {

namespace {

std::string listed(const std::vector<std::string>& names) {
  std::string out;
  for (const std::string& name : names) out += (out.empty() ? "" : ", ") + name;
  return out;
}

std::vector<std::string> parameter_keywords(const ElementLawRow& law) {
  std::vector<std::string> out;
  for (const MaterialParameterRow& parameter : law.parameters) out.emplace_back(parameter.keyword);
  return out;
}

std::string bind_field(const ParameterBinding& bound) { return "material.bind." + bound.parameter; }

// A Prony term's weight (kernels/prony_viscoelasticity.h): a fraction of the law's instantaneous stress, in [0, 1)
// at each element (0: the term does not relax there). Not a law's parameter: the series acts on any law; its time
// constants are the scene's, its weights one per element where a rule output gives them.
const MaterialParameterRow kPronyWeight = {"viscoelastic.prony[I].weight", "Prony weight",
                                           MaterialParameterRow::Quantity::Dimensionless, 0.0, 1.0, true, false,
                                           nullptr};

// The term index of "viscoelastic.prony[I].weight", or -1 for any other parameter.
int prony_weight_term(const std::string& parameter) {
  const std::string head = "viscoelastic.prony[", tail = "].weight";
  if (parameter.size() <= head.size() + tail.size() || parameter.compare(0, head.size(), head) != 0 ||
      parameter.compare(parameter.size() - tail.size(), tail.size(), tail) != 0)
    return -1;
  const std::string digits = parameter.substr(head.size(), parameter.size() - head.size() - tail.size());
  if (digits.size() != 1 || digits[0] < '0' || digits[0] > '9') return -1;
  return digits[0] - '0';
}

// The row checking `parameter` of `law`: the law's own, or a Prony weight's; null when neither.
const MaterialParameterRow* checked_parameter(const ElementLawRow& law, const std::string& parameter) {
  if (prony_weight_term(parameter) >= 0) return &kPronyWeight;
  return material_parameter(law, parameter);
}

// The unit, the declared range and each element's value of `output` against `parameter`: the values in SI, or
// nullopt after an error at the bind's field naming the output.
std::optional<std::vector<double>> checked_values(const Scene& scene, const ParameterBinding& bound,
                                                  const MaterialParameterRow& parameter, const MaterialBinding& binding,
                                                  const BoundOutput& output, const std::vector<Point3>& centroids,
                                                  DiagnosticList& diagnostics) {
  const std::string field = bind_field(bound), name = bound_output_name(binding, output);
  const SourceRange where = scene.range_of(field + ".output");
  const auto scale = si_per_unit(parameter, output.unit);
  if (!scale) {
    diagnostics.error(where, field + ": " + name + " is in '" + output.unit + "', which is not a unit of " +
                                 parameter.description,
                      {parameter.quantity == MaterialParameterRow::Quantity::Pressure
                           ? "give the output kPa, Pa or MPa in the rule file (and recompile a table)"
                           : "a ratio has no unit: give the output none, 'dimensionless' or '%' in the rule file"});
    return std::nullopt;
  }
  if (output.unit.empty() && parameter.quantity == MaterialParameterRow::Quantity::Pressure)
    diagnostics.warning(where, "assumed-unit", field + ": " + name + " has no unit; it is read in kPa");
  // The declared range may touch an end the parameter excludes (a centroid reaches its output's end only with all of
  // the aggregate there; every element's value is checked below), but not pass it.
  const double low = output.range_min * *scale, high = output.range_max * *scale;
  if (output.has_range && (low < parameter.lowest || high > parameter.highest)) {
    diagnostics.error(where, field + ": " + name + " ranges over [" + format_number(low) + ", " + format_number(high) +
                                 "], which leaves the " + parameter.description + "'s valid range " +
                                 valid_range_text(parameter),
                      {std::string("narrow the output's range (and its terms) in the rule file so that no rule can "
                                   "give an invalid ") +
                       parameter.description});
    return std::nullopt;
  }
  std::vector<double> values(output.values.size());
  for (std::size_t e = 0; e < values.size(); ++e) {
    values[e] = output.values[e] * *scale;
    if (in_valid_range(parameter, values[e]) && std::isfinite(values[e])) continue;
    const Point3& c = centroids[e];
    diagnostics.error(where, field + ": " + name + " gives " + format_number(values[e]) + " at element " +
                                 std::to_string(e) + " (centroid " + format_number(c[0]) + ", " + format_number(c[1]) +
                                 ", " + format_number(c[2]) + "), outside the " + parameter.description +
                                 "'s valid range " + valid_range_text(parameter));
    return std::nullopt;
  }
  return values;
}

}  // namespace

std::optional<int> output_index(const Scene& scene, const std::vector<std::string>& outputs, const std::string& name,
                                const std::string& field, const std::string& what, DiagnosticList& diagnostics) {
  const auto found = std::find(outputs.begin(), outputs.end(), name);
  if (found != outputs.end()) return static_cast<int>(found - outputs.begin());
  std::vector<std::string> notes;
  if (auto suggestion = closest_name(name, outputs)) notes.push_back("did you mean '" + *suggestion + "'?");
  if (field != "material.output") notes.push_back("the outputs of " + what + " are: " + listed(outputs));
  const std::string label = field == "material.output" ? field : field.substr(0, field.size() - 7);  // less ".output"
  diagnostics.error(scene.range_of(field), label + ": " + what + " has no output '" + name + "'", notes);
  return std::nullopt;
}

std::optional<std::vector<int>> bound_output_indices(const Scene& scene, const std::vector<std::string>& outputs,
                                                     const std::string& what, DiagnosticList& diagnostics) {
  std::vector<int> out;
  const SceneMaterial& material = scene.material;
  if (material.bind.empty()) return out;
  if (scene.model != ForceModel::Elements) {
    diagnostics.error(scene.range_of("material.bind"),
                      "material.bind: binds the parameters of a finite-element law (model: fem); a spring network "
                      "takes Young's modulus alone: name its output with 'output'");
    return std::nullopt;
  }
  const ElementLawRow& law = element_law_row(scene.element_law);
  const bool strain = std::any_of(material.bindings.begin(), material.bindings.end(),
                                  [](const InputBinding& b) { return b.kind == InputBinding::Kind::Strain; });
  const std::size_t errors = diagnostics.error_count();
  for (const ParameterBinding& bound : material.bind) {
    const std::string field = bind_field(bound);
    const int term = prony_weight_term(bound.parameter);
    if (term >= static_cast<int>(material.prony.size())) {
      diagnostics.error(scene.range_of(field),
                        field + ": material.viscoelastic has " + std::to_string(material.prony.size()) +
                            " Prony terms; a bound weight needs its term there, with its time: prony: [{time: TAU}]");
      continue;
    }
    if (checked_parameter(law, bound.parameter) == nullptr) {
      const std::vector<std::string> names = parameter_keywords(law);
      std::vector<std::string> notes;
      if (auto suggestion = closest_name(bound.parameter, names)) notes.push_back("did you mean '" + *suggestion + "'?");
      notes.push_back("the parameters of law '" + std::string(law.keyword) + "' are: " + listed(names));
      notes.push_back("and the weight of each term of material.viscoelastic: viscoelastic.prony[0].weight, ...");
      diagnostics.error(scene.range_of(field), field + ": '" + bound.parameter + "' is not a parameter of law '" +
                                                   law.keyword + "'", notes);
      continue;
    }
    if (bound.parameter == "youngs_modulus") continue;  // select_output's (it is the rules' main output)
    const auto index = output_index(scene, outputs, bound.output, field + ".output", what, diagnostics);
    if (!index) continue;
    if (strain) {
      diagnostics.error(scene.range_of(field),
                        field + ": with an input bound to 'strain' only youngs_modulus can be bound (the strain "
                                "table holds Young's modulus alone); give material." + bound.parameter + " instead");
      continue;
    }
    out.push_back(*index);
  }
  if (diagnostics.error_count() != errors) return std::nullopt;
  return out;
}

std::string bound_output_name(const MaterialBinding& binding, const BoundOutput& output) {
  return "output '" + output.name + "' of " + (output.has_range ? "system '" : "table '") + binding.system + "'";
}

bool apply_bound_parameters(const Scene& scene, const ElementLawRow& law, const MaterialBinding& binding,
                            const std::vector<Point3>& centroids, ElementMaterial& material,
                            std::vector<PronyTerm>& prony, DiagnosticList& diagnostics) {
  std::size_t next = 0;
  // The weights' sum with each bound weight at its output's declared largest value (a table's: its largest here).
  double largest_sum = 0.0;
  std::string bound_weights;
  for (const PronyTerm& term : prony) largest_sum += term.weight;
  for (const ParameterBinding& bound : scene.material.bind) {
    if (bound.parameter == "youngs_modulus") continue;
    const MaterialParameterRow& parameter = *checked_parameter(law, bound.parameter);
    const BoundOutput& output = binding.bound.at(next++);
    auto values = checked_values(scene, bound, parameter, binding, output, centroids, diagnostics);
    if (!values) return false;
    const int term = prony_weight_term(bound.parameter);
    if (term < 0) {
      material.*(parameter.values) = std::move(*values);
      continue;
    }
    // The same positive weight at every element is the scene's; otherwise one per element (largest in `weight`).
    PronyTerm& weighted = prony[static_cast<std::size_t>(term)];
    weighted.element_weight.clear();
    if (!values->empty()) {
      const auto [low, high] = std::minmax_element(values->begin(), values->end());
      weighted.weight = *high;
      if (*low != *high || !(*low > 0.0)) weighted.element_weight = std::move(*values);
    }
    const auto scale = si_per_unit(parameter, output.unit);
    largest_sum += output.has_range ? output.range_max * *scale : weighted.weight;
    bound_weights += (bound_weights.empty() ? "" : ", ") + bound_output_name(binding, output);
  }
  // The largest sum over the elements (each term's weight at the element).
  double sum = 0.0;
  for (std::size_t e = 0; e < centroids.size(); ++e) {
    double at = 0.0;
    for (const PronyTerm& term : prony) at += prony_weight_at(term, e);
    sum = std::max(sum, at);
  }
  if (!bound_weights.empty() && !(largest_sum < 1.0 && sum < 1.0)) {
    diagnostics.error(scene.range_of("material.bind"),
                      "material.bind: the Prony weights can sum to " + format_number(std::max(largest_sum, sum)) +
                          " (" + bound_weights + " at their largest, with the weights material.viscoelastic gives); "
                          "they must sum below 1 (the long-term modulus is 1 - sum g_i times the law's instantaneous "
                          "one)",
                      {"narrow the outputs' ranges in the rule file"});
    return false;
  }
  return true;
}

}  // namespace fmpc::sim
