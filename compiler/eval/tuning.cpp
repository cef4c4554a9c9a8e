#include "compiler/eval/tuning.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "compiler/eval/interpreter.h"
#include "compiler/frontend/fmpc_ast.h"
#include "compiler/sema/check.h"
#include "compiler/sema/term_shape.h"

namespace fmpc {

namespace {

// `*` any run of characters, `?` one character.
bool glob_matches(const std::string& pattern, const std::string& text) {
  std::size_t p = 0, t = 0, star = std::string::npos, resume = 0;
  while (t < text.size()) {
    if (p < pattern.size() && (pattern[p] == '?' || pattern[p] == text[t])) {
      ++p;
      ++t;
    } else if (p < pattern.size() && pattern[p] == '*') {
      star = p++;
      resume = t;
    } else if (star != std::string::npos) {
      p = star + 1;
      t = ++resume;
    } else {
      return false;
    }
  }
  while (p < pattern.size() && pattern[p] == '*') ++p;
  return p == pattern.size();
}

std::vector<std::string> split_on_dots(const std::string& text) {
  std::vector<std::string> parts{""};
  for (char c : text) {
    if (c == '.') parts.emplace_back();
    else parts.back() += c;
  }
  return parts;
}

// The language's parameter names of a term with their index in the MATLAB-ordered params.
std::vector<std::pair<std::string, std::size_t>> parameter_names(const Term& term, const FuzzySystem& system) {
  std::vector<std::pair<std::string, std::size_t>> names;
  if (term.mf.kind == MfKind::Linear) {
    for (std::size_t i = 0; i < system.inputs.size(); ++i) names.emplace_back(system.inputs[i].name, i);
    names.emplace_back("offset", system.inputs.size());
    return names;
  }
  const ast::FamilySignature& family = ast::family_of(term.mf.kind);
  for (std::size_t i = 0; i < family.parameters.size(); ++i)
    names.emplace_back(family.parameters[i], static_cast<std::size_t>(family.matlab_index[i]));
  return names;
}

// Bounds that keep the parameter what it is (docs/cli.md, `fmpc tune`); the file's own value always lies inside.
void set_bounds(TunableParameter& parameter, const std::string& name, const Term& term, const Variable& variable,
                const FuzzySystem& system) {
  const double v = parameter.value;
  const double lo = variable.min, hi = variable.max, width = hi - lo;
  const auto between = [&](double a, double b, const char* why) {
    parameter.lower = std::min(a, v);
    parameter.upper = std::max(b, v);
    parameter.bound = why;
  };
  const auto magnitude = [&](double small, double large, const char* why) {
    // A sign-carrying size: the sign is kept, the size bounded (the file's value kept inside).
    const double size = std::fabs(v);
    const double a = std::min(small, size > 0 ? size : small), b = std::max(large, size);
    if (v < 0) between(-b, -a, why);
    else between(a, b, why);
  };
  if (term.mf.kind == MfKind::Linear) {
    if (name == "offset") {
      between(lo - 10 * width, hi + 10 * width, "the constant term: within ten ranges of the output's range");
    } else {
      const int input = system.find_input(name);
      const double input_width = input >= 0 ? system.inputs[static_cast<std::size_t>(input)].max -
                                                  system.inputs[static_cast<std::size_t>(input)].min
                                             : 1.0;
      const double limit = 10 * width / (input_width > 0 ? input_width : 1.0);
      between(-limit, limit, "a coefficient: at most ten output ranges across the input's range");
    }
    return;
  }
  if (name == "sd" || name == "sd1" || name == "sd2" || name == "width") {
    magnitude(width * 1e-3, width, "a width: its sign kept, between 1/1000 of the range and the range");
  } else if (term.mf.kind == MfKind::GeneralizedBell && name == "slope") {
    magnitude(0.1, 100, "the bell's steepness: its sign kept, between 0.1 and 100");
  } else if (name == "slope" || name == "slope1" || name == "slope2") {
    // A sigmoid's rise takes about 4 / |slope|: between 1/1000 and ten times the range.
    magnitude(0.4 / width, 4000 / width, "a slope: its sign kept, its rise between 1/1000 and 10 ranges wide");
  } else {
    between(lo, hi, "inside the range");
  }
}

struct TermOrder {
  std::size_t variable = 0;
  bool output = false;
  std::vector<std::pair<std::size_t, std::size_t>> before;  // (a, b): term a lies before term b in the file
};

const Variable& variable_of(const FuzzySystem& system, bool output, std::size_t index) {
  return output ? system.outputs[index] : system.inputs[index];
}

std::vector<std::optional<double>> centres(const Variable& variable) {
  std::vector<std::optional<double>> result;
  for (const Term& term : variable.terms) result.push_back(term_centre(term, variable.min, variable.max));
  return result;
}

// Where the terms of every variable with a tuned parameter lie, in the file: a candidate keeps each pair's order.
std::vector<TermOrder> term_orders(const FuzzySystem& system, const std::vector<TunableParameter>& parameters) {
  std::vector<TermOrder> orders;
  for (const TunableParameter& parameter : parameters) {
    const bool seen = std::any_of(orders.begin(), orders.end(), [&](const TermOrder& order) {
      return order.variable == parameter.variable && order.output == parameter.output;
    });
    if (seen) continue;
    TermOrder order;
    order.variable = parameter.variable;
    order.output = parameter.output;
    const std::vector<std::optional<double>> at = centres(variable_of(system, parameter.output, parameter.variable));
    for (std::size_t a = 0; a < at.size(); ++a)
      for (std::size_t b = 0; b < at.size(); ++b)
        if (at[a] && at[b] && *at[a] < *at[b]) order.before.emplace_back(a, b);
    orders.push_back(std::move(order));
  }
  return orders;
}

bool keeps_order(const FuzzySystem& candidate, const std::vector<TermOrder>& orders) {
  for (const TermOrder& order : orders) {
    const std::vector<std::optional<double>> at = centres(variable_of(candidate, order.output, order.variable));
    for (const auto& [a, b] : order.before)
      if (!at[a] || !at[b] || !(*at[a] < *at[b])) return false;
  }
  return true;
}

double pooled(const std::vector<FoldResult>& folds, bool after) {
  double sum = 0.0;
  std::size_t count = 0;
  for (const FoldResult& fold : folds) {
    const double rmse = after ? fold.rmse_after : fold.rmse_before;
    sum += rmse * rmse * static_cast<double>(fold.patients);
    count += fold.patients;
  }
  return count > 0 ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
}

}  // namespace

std::vector<TunableParameter> select_parameters(const FuzzySystem& system, const std::vector<std::string>& patterns,
                                                const SourceRange& where, DiagnosticList& diagnostics) {
  std::vector<TunableParameter> selected;
  if (system.interval_type2) {
    diagnostics.error(where, "fmpc tune tunes type-1 systems; '" + system.name + "' is interval type-2",
                      {"tune the type-1 system the footprints were drawn around, then widen them"});
    return selected;
  }
  std::vector<bool> taken;
  std::vector<TunableParameter> all;
  std::vector<std::string> all_names;
  std::vector<std::array<std::string, 3>> all_parts;  // variable, term, parameter
  for (const bool output : {false, true}) {
    const std::vector<Variable>& variables = output ? system.outputs : system.inputs;
    for (std::size_t v = 0; v < variables.size(); ++v) {
      for (std::size_t t = 0; t < variables[v].terms.size(); ++t) {
        const Term& term = variables[v].terms[t];
        for (const auto& [name, index] : parameter_names(term, system)) {
          if (index >= term.mf.params.size()) continue;
          TunableParameter parameter;
          parameter.name = variables[v].name + "." + term.name + "." + name;
          parameter.output = output;
          parameter.variable = v;
          parameter.term = t;
          parameter.index = index;
          parameter.value = term.mf.params[index];
          set_bounds(parameter, name, term, variables[v], system);
          all_names.push_back(parameter.name);
          all_parts.push_back({variables[v].name, term.name, name});
          all.push_back(std::move(parameter));
        }
      }
    }
  }
  taken.assign(all.size(), false);
  for (const std::string& pattern : patterns) {
    std::vector<std::string> parts = split_on_dots(pattern);
    if (parts.size() == 2) parts.emplace_back("*");
    if (parts.size() != 3 || std::any_of(parts.begin(), parts.end(), [](const std::string& p) { return p.empty(); })) {
      diagnostics.error(where, "'" + pattern + "' is not a parameter pattern",
                        {"write VARIABLE.TERM.PARAMETER (each part may use * and ?), e.g. HCV.F2.mean or HCV.*.sd"});
      continue;
    }
    bool matched = false;
    for (std::size_t i = 0; i < all.size(); ++i) {
      const std::array<std::string, 3>& name = all_parts[i];
      if (glob_matches(parts[0], name[0]) && glob_matches(parts[1], name[1]) && glob_matches(parts[2], name[2])) {
        matched = true;
        taken[i] = true;
      }
    }
    if (!matched) {
      std::vector<std::string> notes;
      if (auto closest = closest_name(pattern, all_names)) notes.push_back("did you mean '" + *closest + "'?");
      notes.push_back("parameters are named VARIABLE.TERM.PARAMETER with the language's parameter names "
                      "(docs/language.md), e.g. " + (all_names.empty() ? std::string("HCV.F2.mean") : all_names.front()));
      diagnostics.error(where, "'" + pattern + "' matches no parameter of system '" + system.name + "'", notes);
    }
  }
  for (std::size_t i = 0; i < all.size(); ++i)
    if (taken[i]) selected.push_back(all[i]);
  return selected;
}

FuzzySystem with_parameters(const FuzzySystem& system, const std::vector<TunableParameter>& parameters,
                            const std::vector<double>& values) {
  FuzzySystem result = system;
  for (std::size_t i = 0; i < parameters.size() && i < values.size(); ++i) {
    const TunableParameter& parameter = parameters[i];
    std::vector<Variable>& variables = parameter.output ? result.outputs : result.inputs;
    variables[parameter.variable].terms[parameter.term].mf.params[parameter.index] = values[i];
  }
  return result;
}

double prediction_rmse(const FuzzySystem& system, const TuningData& data, const std::vector<std::size_t>& rows) {
  if (rows.empty()) return 0.0;
  Interpreter interpreter(system);
  double sum = 0.0;
  for (std::size_t row : rows) {
    const double predicted = interpreter.evaluate(data.inputs[row]).outputs[data.output];
    if (!std::isfinite(predicted)) return std::numeric_limits<double>::infinity();
    const double error = predicted - data.measured[row];
    sum += error * error;
  }
  return std::sqrt(sum / static_cast<double>(rows.size()));
}

std::vector<std::vector<std::size_t>> fold_assignment(std::size_t patients, int folds, std::uint64_t seed) {
  std::vector<std::size_t> order(patients);
  for (std::size_t i = 0; i < patients; ++i) order[i] = i;
  std::mt19937_64 random(seed);
  for (std::size_t i = patients; i > 1; --i) std::swap(order[i - 1], order[random() % i]);
  const auto k = static_cast<std::size_t>(std::max(folds, 1));
  std::vector<std::vector<std::size_t>> result(k);
  for (std::size_t f = 0; f < k; ++f) {
    for (std::size_t i = f * patients / k; i < (f + 1) * patients / k; ++i) result[f].push_back(order[i]);
    std::sort(result[f].begin(), result[f].end());
  }
  return result;
}

TuningResult tune_system(const FuzzySystem& system, const std::vector<TunableParameter>& parameters,
                         const TuningData& data, const TuningOptions& options) {
  std::vector<double> start, lower, upper;
  for (const TunableParameter& parameter : parameters) {
    start.push_back(parameter.value);
    lower.push_back(parameter.lower);
    upper.push_back(parameter.upper);
  }
  const std::vector<TermOrder> orders = term_orders(system, parameters);
  // Infeasible candidates (invalid parameters, terms out of their order) are infinitely bad.
  const auto search = [&](const std::vector<std::size_t>& rows) {
    const auto objective = [&](const std::vector<double>& values) {
      const FuzzySystem candidate = with_parameters(system, parameters, values);
      DiagnosticList problems;
      check_system(candidate, problems);
      if (problems.has_errors() || !keeps_order(candidate, orders)) return std::numeric_limits<double>::infinity();
      return prediction_rmse(candidate, data, rows);
    };
    return minimise_nelder_mead(objective, start, lower, upper, options.search);
  };
  std::vector<std::size_t> everyone(data.measured.size());
  for (std::size_t i = 0; i < everyone.size(); ++i) everyone[i] = i;
  TuningResult result;
  if (options.folds > 0) {
    const std::vector<std::vector<std::size_t>> folds = fold_assignment(everyone.size(), options.folds, options.seed);
    for (const std::vector<std::size_t>& held_out : folds) {
      std::vector<std::size_t> training;
      std::set_difference(everyone.begin(), everyone.end(), held_out.begin(), held_out.end(),
                          std::back_inserter(training));
      const NelderMeadResult found = search(training);
      FoldResult fold;
      fold.patients = held_out.size();
      fold.rmse_before = prediction_rmse(system, data, held_out);
      fold.rmse_after = prediction_rmse(with_parameters(system, parameters, found.point), data, held_out);
      fold.evaluations = found.evaluations;
      fold.converged = found.converged;
      result.folds.push_back(fold);
    }
    result.held_out_rmse_before = pooled(result.folds, false);
    result.held_out_rmse_after = pooled(result.folds, true);
  }
  result.search = search(everyone);
  result.values = result.search.point;
  result.rmse_before = prediction_rmse(system, data, everyone);
  result.rmse_after = prediction_rmse(with_parameters(system, parameters, result.values), data, everyone);
  return result;
}

}  // namespace fmpc
