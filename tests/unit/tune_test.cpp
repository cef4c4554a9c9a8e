// Tuning (compiler/eval/tuning.h, nelder_mead.h) and writing tuned numbers into fmpc text: the search finds known
// minima inside its box and stops at its cap saying so; folds partition the patients the same way for a seed;
// patterns select parameters with their bounds; tuning recovers the parameters measured data were made with, keeps
// terms in their order when the data pull them across, and never touches rules.
#include <catch2/catch.hpp>
#include <cmath>

#include "compiler/eval/interpreter.h"
#include "compiler/eval/tuning.h"
#include "compiler/frontend/fmpc_language.h"

namespace fmpc {
namespace {

FuzzySystem read_system(const std::string& text) {
  DiagnosticList diagnostics;
  RuleFile file = read_fmpc("t.fis", text, diagnostics);
  INFO(render_all(diagnostics, SourceFiles{}));
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(file.systems.size() == 1);
  return file.systems.front();
}

const char* const kTissue = R"(system tissue
input HCV in [0, 30] kPa
  low is gauss(mean 5, sd 3)
  high is gauss(mean 20, sd 4)
output stiffness in [0, 75] kPa
  soft is gauss(mean 10, sd 5)
  hard is gauss(mean 50, sd 8)
rule r1: if HCV is low then stiffness is soft
rule r2: if HCV is high then stiffness is hard
)";

// Patients at HCV = 1, 2.2, ..., measured as `truth` predicts them.
TuningData data_from(const FuzzySystem& truth, std::size_t patients) {
  TuningData data;
  Interpreter interpreter(truth);
  for (std::size_t i = 0; i < patients; ++i) {
    data.inputs.push_back({1.0 + 1.2 * static_cast<double>(i)});
    data.measured.push_back(interpreter.evaluate(data.inputs.back()).outputs[0]);
  }
  return data;
}

}  // namespace

TEST_CASE("Nelder-Mead: minima inside the box, on its bound, deterministic, and a cap that says so", "[tune]") {
  const auto rosenbrock = [](const std::vector<double>& x) {
    return 100 * (x[1] - x[0] * x[0]) * (x[1] - x[0] * x[0]) + (1 - x[0]) * (1 - x[0]);
  };
  NelderMeadOptions options;
  options.max_evaluations = 2000;
  const NelderMeadResult inside = minimise_nelder_mead(rosenbrock, {-1.2, 1}, {-2, -2}, {2, 2}, options);
  CHECK(inside.converged);
  CHECK(inside.point[0] == Approx(1).margin(1e-4));
  CHECK(inside.point[1] == Approx(1).margin(1e-4));
  // The same run twice: the same points and counts.
  const NelderMeadResult again = minimise_nelder_mead(rosenbrock, {-1.2, 1}, {-2, -2}, {2, 2}, options);
  CHECK(again.point == inside.point);
  CHECK(again.evaluations == inside.evaluations);
  // The minimum outside the box: the search ends on the bound, never past it.
  const auto bowl = [](const std::vector<double>& x) { return (x[0] - 5) * (x[0] - 5) + (x[1] + 1) * (x[1] + 1); };
  const NelderMeadResult bounded = minimise_nelder_mead(bowl, {0, 0}, {-1, -1}, {1, 1}, options);
  CHECK(bounded.point[0] == Approx(1).margin(1e-6));
  CHECK(bounded.point[1] == Approx(-1).margin(1e-6));
  // Infeasible points (an infinite objective) are avoided; a tiny cap stops the search and says so.
  const auto walled = [](const std::vector<double>& x) {
    return x[0] < 0.25 ? HUGE_VAL : (x[0] - 0.5) * (x[0] - 0.5);
  };
  const NelderMeadResult feasible = minimise_nelder_mead(walled, {0.9}, {0}, {1}, options);
  CHECK(feasible.point[0] == Approx(0.5).margin(1e-5));
  options.max_evaluations = 5;
  const NelderMeadResult capped = minimise_nelder_mead(rosenbrock, {-1.2, 1}, {-2, -2}, {2, 2}, options);
  CHECK_FALSE(capped.converged);
  CHECK(capped.evaluations <= 7);  // the cap is checked between iterations: one iteration may add two
  CHECK(capped.value_spread > 0);
  // No parameters: nothing to search.
  const NelderMeadResult empty =
      minimise_nelder_mead([](const std::vector<double>& x) { return static_cast<double>(x.size()); }, {}, {}, {},
                           options);
  CHECK(empty.converged);
  CHECK(empty.evaluations == 1);
}

TEST_CASE("tune: folds partition the patients, sizes within one, fixed by the seed", "[tune]") {
  const auto folds = fold_assignment(23, 5, 7);
  REQUIRE(folds.size() == 5);
  std::vector<int> seen(23, 0);
  for (const auto& fold : folds) {
    CHECK((fold.size() == 4 || fold.size() == 5));
    for (std::size_t i : fold) ++seen[i];
  }
  CHECK(std::all_of(seen.begin(), seen.end(), [](int n) { return n == 1; }));
  CHECK(fold_assignment(23, 5, 7) == folds);
  CHECK(fold_assignment(23, 5, 8) != folds);
  // std::mt19937_64's output is fixed by the C++ standard: so is this assignment, on every platform.
  CHECK(fold_assignment(6, 3, 1) == fold_assignment(6, 3, 1));
  CHECK(fold_assignment(2, 2, 1)[0].size() == 1);
}

TEST_CASE("tune: patterns select parameters with bounds that keep each one what it is", "[tune]") {
  const FuzzySystem system = read_system(std::string(kTissue) + "input x in [0, 1]\n  far is triangle(start -2, peak 0.5, end 3)\n");
  DiagnosticList diagnostics;
  const SourceRange where{"argument --parameters", 0, 0, 0, 0};
  std::vector<TunableParameter> selected = select_parameters(system, {"HCV.*.mean", "HCV.high"}, where, diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  std::vector<std::string> names;
  for (const TunableParameter& p : selected) names.push_back(p.name);
  CHECK(names == std::vector<std::string>{"HCV.low.mean", "HCV.high.mean", "HCV.high.sd"});
  CHECK(selected[0].lower == 0);
  CHECK(selected[0].upper == 30);
  CHECK(selected[2].lower == Approx(0.03));  // a width: from 1/1000 of the range ...
  CHECK(selected[2].upper == 30);            // ... to the range
  // A parameter the file puts outside the range keeps its value feasible.
  selected = select_parameters(system, {"x.far.start"}, where, diagnostics);
  REQUIRE(selected.size() == 1);
  CHECK(selected[0].lower == -2);
  CHECK(selected[0].upper == 1);
  // Globs with ?, and every parameter of the system.
  CHECK(select_parameters(system, {"*.?o*.*"}, where, diagnostics).size() == 4);  // low and soft
  CHECK(select_parameters(system, {"*.*.*"}, where, diagnostics).size() == 11);
  REQUIRE_FALSE(diagnostics.has_errors());
  // Patterns that match nothing, or are not patterns.
  select_parameters(system, {"HCV.high.men", "HCV"}, where, diagnostics);
  REQUIRE(diagnostics.items().size() == 2);
  CHECK(diagnostics.items()[0].message == "'HCV.high.men' matches no parameter of system 'tissue'");
  CHECK(diagnostics.items()[0].notes[0] == "did you mean 'HCV.high.mean'?");
  CHECK(diagnostics.items()[1].message == "'HCV' is not a parameter pattern");
}

TEST_CASE("tune: recovers the parameters the measurements were made with; rules never change", "[tune]") {
  const FuzzySystem file = read_system(kTissue);
  FuzzySystem truth = file;
  truth.inputs[0].terms[1].mf.params = {3, 15};  // high: sd 3, mean 15
  const TuningData data = data_from(truth, 24);
  DiagnosticList diagnostics;
  const std::vector<TunableParameter> parameters =
      select_parameters(file, {"HCV.high.*"}, SourceRange{}, diagnostics);
  const TuningResult result = tune_system(file, parameters, data, TuningOptions{});
  CHECK(result.search.converged);
  REQUIRE(result.values.size() == 2);
  CHECK(result.values[0] == Approx(15).margin(1e-6));  // mean (the language's order: mean, sd)
  CHECK(result.values[1] == Approx(3).margin(1e-6));
  CHECK(result.rmse_before > 1);
  CHECK(result.rmse_after < 1e-6);
  REQUIRE(result.folds.size() == 5);
  CHECK(result.held_out_rmse_before > 1);
  CHECK(result.held_out_rmse_after < 1e-5);
  const FuzzySystem tuned = with_parameters(file, parameters, result.values);
  REQUIRE(tuned.rules.size() == file.rules.size());
  for (std::size_t r = 0; r < tuned.rules.size(); ++r) {
    CHECK(tuned.rules[r].weight == file.rules[r].weight);
    CHECK(tuned.rules[r].antecedent.size() == file.rules[r].antecedent.size());
  }
  CHECK(tuned.outputs[0].terms[1].mf.params == file.outputs[0].terms[1].mf.params);  // not named: not changed
}

TEST_CASE("tune: terms keep their order even where the data pull one across another", "[tune]") {
  const FuzzySystem file = read_system(kTissue);
  // Data made with `high` centred at 2, below `low` (mean 5): the fit may not cross it.
  FuzzySystem truth = file;
  truth.inputs[0].terms[1].mf.params = {4, 2};
  const TuningData data = data_from(truth, 24);
  DiagnosticList diagnostics;
  const std::vector<TunableParameter> parameters =
      select_parameters(file, {"HCV.high.mean"}, SourceRange{}, diagnostics);
  TuningOptions options;
  options.folds = 0;
  const TuningResult result = tune_system(file, parameters, data, options);
  CHECK(result.folds.empty());
  REQUIRE(result.values.size() == 1);
  CHECK(result.values[0] > 5);  // still after low
  CHECK(result.rmse_after <= result.rmse_before);
}

TEST_CASE("edit_fmpc_parameters writes numbers in place: comments, layout and units kept", "[tune]") {
  const std::string text = R"(system s  # the system
input x in [0, 10] kPa
  a is gauss(sd 1,   mean 5300 Pa)   # written in Pa
output y in [0, 1]
  k is linear(offset 1)
rule: if x is a then y is k
)";
  DiagnosticList diagnostics;
  const std::optional<std::string> edited = edit_fmpc_parameters(
      "t.fis", text,
      {ParameterEdit{"s", "x", "a", "mean", 6.25}, ParameterEdit{"s", "x", "a", "sd", 0.5},
       ParameterEdit{"s", "y", "k", "x", -0.125}, ParameterEdit{"s", "y", "k", "offset", 2}},
      diagnostics);
  REQUIRE(edited);
  CHECK(*edited == R"(system s  # the system
input x in [0, 10] kPa
  a is gauss(sd 0.5,   mean 6.25 kPa)   # written in Pa
output y in [0, 1]
  k is linear(offset 2, x -0.125)
rule: if x is a then y is k
)");
  CHECK_FALSE(edit_fmpc_parameters("t.fis", text, {ParameterEdit{"s", "x", "b", "mean", 1}}, diagnostics));
  CHECK(diagnostics.items().back().message == "no term 'b' of 'x' in system 's' to write into");
}

}  // namespace fmpc
