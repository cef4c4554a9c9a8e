// compiler/passes: each pass against its stated error bound on seeded random systems and random points, exact
// results on hand-made systems, the pipeline's binding errors, and the IR dump.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "compiler/eval/interpreter.h"
#include "compiler/frontend/rule_file_loader.h"
#include "compiler/frontend/ir_printer.h"
#include "compiler/passes/drop_dead_terms.h"
#include "compiler/passes/fuse_consequents.h"
#include "compiler/passes/pipeline.h"
#include "compiler/passes/prune_rules.h"
#include "compiler/passes/specialize.h"
#include "tests/support/random_system.h"

namespace {

using namespace fmpc;

FuzzySystem load(const std::string& text) {
  DiagnosticList diagnostics;
  RuleFile file = load_rule_file("test.fis", text, diagnostics);
  INFO(render_all(diagnostics, SourceFiles{}));
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(file.systems.size() == 1);
  return file.systems.front();
}

const char* const kTwoInputs = R"(system two
  type mamdani
  and min  or max  implication min  aggregation max
  defuzzify centroid samples 101
input a in [0, 10] m
  low is triangle(start -10, peak 0, end 10)
  high is triangle(start 0, peak 10, end 20)
  far is triangle(start 20, peak 25, end 30)
input b in [0, 10] m
  low is gauss(mean 0, sd 3)
  high is gauss(mean 10, sd 3)
output y in [0, 1] m
  small is triangle(start 0, peak 0.2, end 0.5)
  big is triangle(start 0.5, peak 0.8, end 1)
  unused is triangle(start 0, peak 0.5, end 1)
rule r1: if a is low and b is low then y is small
rule r2: if a is high and b is low then y is small
rule r3: if a is high and b is high then y is big
rule r4: if a is far and b is high then y is big
)";

double rounding_tolerance(const FuzzySystem& system) {
  double range = 1.0;
  for (const Variable& output : system.outputs) range = std::max(range, output.max - output.min);
  return 1e-9 * range;
}

// Compares `transformed` (inputs = the source's inputs at `kept`) with `source` at `count` random points where the
// inputs not kept take `fixed`; returns the largest output difference.
double largest_difference(const FuzzySystem& source, const FuzzySystem& transformed, const std::vector<int>& kept,
                          const std::vector<double>& fixed_values, std::uint64_t seed, std::size_t count) {
  Interpreter reference(source), candidate(transformed);
  std::mt19937_64 generator(seed);
  double largest = 0.0;
  for (std::size_t n = 0; n < count; ++n) {
    std::vector<double> full = fixed_values, reduced;
    for (int i : kept) {
      const Variable& input = source.inputs[static_cast<std::size_t>(i)];
      const double unit = static_cast<double>(generator() >> 11) * 0x1.0p-53;
      full[static_cast<std::size_t>(i)] = input.min + unit * (input.max - input.min);
      reduced.push_back(full[static_cast<std::size_t>(i)]);
    }
    const Evaluation expected = reference.evaluate(full), actual = candidate.evaluate(reduced);
    for (std::size_t o = 0; o < expected.outputs.size(); ++o) {
      const double a = expected.outputs[o], b = actual.outputs[o];
      if (std::isnan(a) && std::isnan(b)) continue;
      largest = std::max(largest, std::isnan(a - b) ? std::numeric_limits<double>::infinity() : std::fabs(a - b));
    }
  }
  return largest;
}

std::vector<int> all_inputs(const FuzzySystem& system) {
  std::vector<int> kept;
  for (std::size_t i = 0; i < system.inputs.size(); ++i) kept.push_back(static_cast<int>(i));
  return kept;
}

}  // namespace

TEST_CASE("specialize folds fixed inputs exactly into folded grades and linear outputs", "[passes]") {
  const FuzzySystem source = load(kTwoInputs);
  FuzzySystem system = source;
  const PassReport report = specialize(system, {{0, 2.5}});
  CHECK(report.error_bound == 0.0);
  CHECK(report.summary == "folded 1 input, 4 clauses");
  REQUIRE(system.inputs.size() == 1);
  CHECK(system.inputs[0].name == "b");
  REQUIRE(system.rules.size() == 4);
  CHECK(*system.rules[0].folded_grade == 0.75);  // low at 2.5: (10 - 2.5) / 10
  CHECK(*system.rules[1].folded_grade == 0.25);
  CHECK(*system.rules[3].folded_grade == 0.0);
  CHECK(system.rules[0].antecedent.size() == 1);
  CHECK(system.rules[0].antecedent[0].variable == 0);
  CHECK(largest_difference(source, system, {1}, {2.5, 0.0}, 11, 500) == 0.0);  // min/max: bitwise

  FuzzySystem sugeno = load(R"(system s
  type sugeno
  and prod  or probor
  defuzzify wtaver
input a in [0, 10] m
  low is gauss(mean 0, sd 4)
input b in [0, 10] m
  low is gauss(mean 0, sd 4)
output y in [0, 100] m
  plane is linear(a 2, b 3, offset 1)
rule r1: if a is low and b is low then y is plane
rule r2: if a is not low or b is low then y is plane
)");
  FuzzySystem folded = sugeno;
  specialize(folded, {{1, 4.0}});
  CHECK(folded.outputs[0].terms[0].mf.params == std::vector<double>{2.0, 13.0});  // 2 a + (3 * 4 + 1)
  CHECK(largest_difference(sugeno, folded, {0}, {0.0, 4.0}, 12, 500) <= rounding_tolerance(sugeno));
}

TEST_CASE("specialize then every pass keeps the output within its bound on random systems", "[passes]") {
  std::mt19937_64 generator(20240611);
  int fused_somewhere = 0, pruned_somewhere = 0;
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    testing::RandomSystemOptions options = testing::RandomSystemOptions::matlab();
    options.min_inputs = 2;
    options.max_rules = 16;
    if (seed % 2 == 0) options.aggregation_methods = {SNorm::Maximum};
    const FuzzySystem source = testing::random_system(seed, options);
    INFO("seed " << seed);
    std::vector<InputValue> fixed;
    std::vector<double> fixed_values(source.inputs.size(), 0.0);
    std::vector<int> kept;
    for (std::size_t i = 0; i < source.inputs.size(); ++i) {
      const Variable& input = source.inputs[i];
      const double unit = static_cast<double>(generator() >> 11) * 0x1.0p-53;
      if (i + 1 < source.inputs.size() && generator() % 2 == 0) {
        fixed_values[i] = input.min + unit * (input.max - input.min);
        fixed.push_back({static_cast<int>(i), fixed_values[i]});
      } else {
        kept.push_back(static_cast<int>(i));
      }
    }
    const double tolerance = rounding_tolerance(source);
    FuzzySystem stage = source;
    const PassReport specialized = specialize(stage, fixed);
    CHECK(largest_difference(source, stage, kept, fixed_values, seed, 200) <= specialized.error_bound + tolerance);

    // Each later pass is compared with the stage before it, on the varying inputs only.
    FuzzySystem before = stage;
    const std::vector<int> stage_inputs = all_inputs(stage);
    const std::vector<double> no_fixed(stage.inputs.size(), 0.0);
    const double epsilon = seed % 3 == 0 ? 0.05 : 0.0;
    const PassReport pruned = prune_rules(stage, epsilon);
    CHECK(largest_difference(before, stage, stage_inputs, no_fixed, seed + 1, 200) <= pruned.error_bound + tolerance);
    pruned_somewhere += stage.rules.size() < before.rules.size() ? 1 : 0;
    before = stage;
    const PassReport fused = fuse_consequents(stage);
    CHECK(fused.error_bound == 0.0);
    CHECK(largest_difference(before, stage, stage_inputs, no_fixed, seed + 2, 200) <= tolerance);
    fused_somewhere += stage.rules.size() < before.rules.size() ? 1 : 0;
    before = stage;
    const PassReport dropped = drop_dead_terms(stage);
    CHECK(dropped.error_bound == 0.0);
    CHECK(largest_difference(before, stage, stage_inputs, no_fixed, seed + 3, 200) <= tolerance);
  }
  // The property is only worth something if the passes changed systems.
  CHECK(fused_somewhere > 0);
  CHECK(pruned_somewhere > 0);
}

TEST_CASE("membership bounds over intervals are exact at peaks and ends, unknown for NaN", "[passes]") {
  const MembershipFunction gauss{MfKind::Gaussian, {1.0, 5.0}};
  const auto around = membership_bounds(gauss, 4.0, 6.0);
  REQUIRE(around);
  CHECK(around->high == 1.0);
  CHECK(around->low == Approx(std::exp(-0.5)).epsilon(1e-15));
  const auto right = membership_bounds(gauss, 6.0, 7.0);
  REQUIRE(right);
  CHECK(right->high == Approx(std::exp(-0.5)).epsilon(1e-15));
  CHECK(right->low == Approx(std::exp(-2.0)).epsilon(1e-15));
  const auto far = membership_bounds(MembershipFunction{MfKind::Triangle, {20, 25, 30}}, 0.0, 10.0);
  REQUIRE(far);
  CHECK(far->high == 0.0);
  const auto sigmoid = membership_bounds(MembershipFunction{MfKind::Sigmoid, {-2.0, 5.0}}, 0.0, 10.0);
  REQUIRE(sigmoid);
  CHECK(sigmoid->low < 1e-4);
  CHECK(sigmoid->high > 0.9999);
  CHECK_FALSE(membership_bounds(MembershipFunction{MfKind::Gaussian, {std::nan(""), 5.0}}, 0.0, 1.0));
  CHECK_FALSE(membership_bounds(MembershipFunction{MfKind::GeneralizedBell, {1.0, -2.0, 5.0}}, 0.0, 1.0));
  // A degenerate interval gives the value there.
  const auto point = membership_bounds(gauss, 6.0, 6.0);
  REQUIRE(point);
  CHECK(point->low == point->high);
}

TEST_CASE("prune_rules removes rules that cannot fire, exactly, and names them", "[passes]") {
  FuzzySystem system = load(kTwoInputs);
  const FuzzySystem source = system;
  const PassReport report = prune_rules(system, 0.0);
  CHECK(system.rules.size() == 3);  // r4: a is far, 0 on [0, 10]
  CHECK(report.error_bound == 0.0);
  REQUIRE(report.details.size() == 1);
  CHECK(report.details[0] == "r4: cannot fire on the inputs' ranges");
  CHECK(largest_difference(source, system, all_inputs(source), {0, 0}, 5, 300) == 0.0);

  // Fixing a at 10 makes "a is low" 0: r1 cannot fire either.
  FuzzySystem fixed = source;
  specialize(fixed, {{0, 10.0}});
  prune_rules(fixed, 0.0);
  CHECK(fixed.rules.size() == 2);
}

TEST_CASE("prune_rules with epsilon states a centroid bound that holds, and the whole range when none is proven",
          "[passes]") {
  const FuzzySystem source = load(R"(system eps
  type mamdani
  and min  or max  implication min  aggregation max
  defuzzify centroid samples 101
input x in [0, 1] m
  all is trapezoid(start -1, top_start -0.5, top_end 1.5, end 2)
  faint is gauss(mean 3, sd 0.5)
output y in [0, 10] m
  mid is triangle(start 2, peak 5, end 8)
  high is triangle(start 6, peak 9, end 10)
rule r1: if x is all then y is mid
rule r2: if x is faint then y is high
)");
  FuzzySystem system = source;
  const PassReport report = prune_rules(system, 1e-3);
  REQUIRE(system.rules.size() == 1);
  // S_min = sum of the mid triangle's samples (r1 fires at 1 everywhere) = 30, so R n eps / S_min = 10 * 101e-3 / 30.
  CHECK(report.error_bound == Approx(10.0 * 101 * 1e-3 / 30.0).epsilon(1e-9));
  CHECK(report.error_bound < 10.0);
  CHECK(largest_difference(source, system, {0}, {0.0}, 9, 2000) <= report.error_bound);
  CHECK(largest_difference(source, system, {0}, {0.0}, 9, 2000) > 0.0);  // the bound is about something real

  // Without a rule that always fires, the pruned set may be empty somewhere: the bound is the whole range.
  FuzzySystem weak = load(R"(system weak
  type mamdani
  defuzzify centroid samples 101
input x in [0, 1] m
  left is triangle(start -1, peak 0, end 1)
  faint is gauss(mean 3, sd 0.5)
output y in [0, 10] m
  mid is triangle(start 2, peak 5, end 8)
  high is triangle(start 6, peak 9, end 10)
rule r1: if x is left then y is mid
rule r2: if x is faint then y is high
)");
  const PassReport weak_report = prune_rules(weak, 1e-3);
  CHECK(weak_report.error_bound == 10.0);

  // Sugeno systems ignore epsilon and say so.
  FuzzySystem sugeno = load(R"(system s
  type sugeno
  defuzzify wtaver
input x in [0, 1] m
  faint is gauss(mean 3, sd 0.5)
output y in [0, 10] m
  c is constant(value 4)
rule r1: if x is faint then y is c
)");
  const PassReport sugeno_report = prune_rules(sugeno, 1e-3);
  CHECK(sugeno.rules.size() == 1);
  CHECK(sugeno_report.details.front().find("ignored") != std::string::npos);
}

TEST_CASE("fuse_consequents fuses identical antecedents and disjunctions, and nothing it cannot express",
          "[passes]") {
  const FuzzySystem source = load(kTwoInputs);
  FuzzySystem system = source;
  specialize(system, {{0, 2.5}});
  const FuzzySystem specialised = system;
  const PassReport report = fuse_consequents(system);
  // r1 (0.75 and b low -> small) and r2 (0.25 and b low -> small) become one with grade 0.75; r3, r4 likewise.
  REQUIRE(system.rules.size() == 2);
  CHECK(*system.rules[0].folded_grade == 0.75);
  CHECK(*system.rules[1].folded_grade == 0.25);
  CHECK(report.details[0] == "r2 -> r1 (identical antecedents)");
  CHECK(largest_difference(specialised, system, {0}, {0.0}, 3, 500) == 0.0);

  FuzzySystem disjunctive = load(R"(system d
  type mamdani
  and min  or max  implication prod  aggregation max
  defuzzify centroid
input a in [0, 10] m
  low is gauss(mean 0, sd 3)
input b in [0, 10] m
  low is gauss(mean 0, sd 3)
  high is gauss(mean 10, sd 3)
output y in [0, 1] m
  small is triangle(start 0, peak 0.2, end 0.5)
rule r1: if a is low then y is small
rule r2: if b is low then y is small
rule r3: if a is low and b is high then y is small
rule r4: if b is high then y is small weight 0.5
)");
  const FuzzySystem before = disjunctive;
  fuse_consequents(disjunctive);
  REQUIRE(disjunctive.rules.size() == 3);  // r1 or r2; r3 is a conjunction; r4 has another weight
  CHECK(disjunctive.rules[0].connective == Connective::Or);
  CHECK(disjunctive.rules[0].antecedent.size() == 2);
  CHECK(largest_difference(before, disjunctive, {0, 1}, {0, 0}, 4, 500) == 0.0);

  FuzzySystem summed = before;
  summed.aggregation = SNorm::Sum;
  const PassReport not_applicable = fuse_consequents(summed);
  CHECK(summed.rules.size() == 4);
  CHECK(not_applicable.details.front().find("not applicable") != std::string::npos);
}

TEST_CASE("drop_dead_terms removes unnamed terms and renumbers clauses", "[passes]") {
  FuzzySystem system = load(kTwoInputs);
  prune_rules(system, 0.0);
  const FuzzySystem before = system;
  const PassReport report = drop_dead_terms(system);
  CHECK(report.summary == "removed 2 terms");  // a.far (r4 pruned), y.unused
  CHECK(system.inputs[0].terms.size() == 2);
  CHECK(system.outputs[0].terms.size() == 2);
  CHECK(largest_difference(before, system, {0, 1}, {0, 0}, 6, 300) == 0.0);
}

TEST_CASE("run_pipeline resolves bindings, reports every pass and dumps the IR", "[passes]") {
  const FuzzySystem source = load(kTwoInputs);
  DiagnosticList diagnostics;
  Bindings bindings;
  bindings.fixed.push_back({"a", 2.5, {}});
  PipelineOptions options;
  options.dump_after = {"specialize", "drop_dead_terms"};
  const std::optional<CompileResult> result = run_pipeline(source, bindings, options, diagnostics);
  REQUIRE(result);
  CHECK_FALSE(diagnostics.has_errors());
  CHECK(result->source_inputs == std::vector<int>{1});
  REQUIRE(result->reports.size() == 4);
  CHECK(result->reports[0].pass == "specialize");
  CHECK(result->reports[3].pass == "drop_dead_terms");
  CHECK(result->error_bound() == 0.0);
  REQUIRE(result->dumps.size() == 2);
  CHECK(result->dumps[0].text.find("rule r1: if <fixed 0.75> and b is low then y is small") != std::string::npos);
  CHECK(result->system.rules.size() == 2);
  CHECK(largest_difference(source, result->system, {1}, {2.5, 0.0}, 8, 300) == 0.0);
}

TEST_CASE("run_pipeline rejects bad bindings with located messages", "[passes]") {
  const FuzzySystem source = load(kTwoInputs);
  const SourceRange here{"argument", 0, 0, 0, 0};
  const auto errors_of = [&](const Bindings& bindings, const PipelineOptions& options = {}) {
    DiagnosticList diagnostics;
    CHECK_FALSE(run_pipeline(source, bindings, options, diagnostics));
    std::string text;
    for (const Diagnostic& d : diagnostics.items()) {
      text += d.message + "\n";
      for (const std::string& note : d.notes) text += "  " + note + "\n";
    }
    return text;
  };
  CHECK(errors_of(Bindings{{{"aa", 1.0, here}}, {}}).find("did you mean 'a'?") != std::string::npos);
  CHECK(errors_of(Bindings{{{"a", 1.0, here}, {"a", 2.0, here}}, {}}).find("bound twice") != std::string::npos);
  CHECK(errors_of(Bindings{{{"a", 1.0, here}}, {{"a", 0, here}}}).find("both fixed and varied") !=
        std::string::npos);
  CHECK(errors_of(Bindings{{{"a", std::nan(""), here}}, {}}).find("NaN") != std::string::npos);
  CHECK(errors_of(Bindings{{}, {{"b", 1, here}}}).find("an axis takes 2 to 1000000 points, not 1") !=
        std::string::npos);
  CHECK(errors_of(Bindings{{{"a", 1.0, here}, {"b", 1.0, here}}, {}}).find("every input") != std::string::npos);
  PipelineOptions dump;
  dump.dump_after = {"prune_rule"};
  CHECK(errors_of(Bindings{}, dump).find("did you mean 'prune_rules'?") != std::string::npos);
  FuzzySystem type2 = source;
  type2.interval_type2 = true;
  DiagnosticList diagnostics;
  CHECK_FALSE(run_pipeline(type2, Bindings{}, PipelineOptions{}, diagnostics));
  REQUIRE(diagnostics.error_count() == 1);
  CHECK(diagnostics.items()[0].message.find("interval type-2") != std::string::npos);
  // Out of range is a warning, evaluated as given.
  DiagnosticList warnings;
  CHECK(run_pipeline(source, Bindings{{{"a", 11.0, here}}, {}}, PipelineOptions{}, warnings));
  CHECK(warnings.warning_count() == 1);
}

TEST_CASE("the liver ruleset specialised for three fixed inputs matches the interpreter exactly", "[passes]") {
  const std::string path = std::string(FMPC_SOURCE_DIR) + "/rulesets/liver_fibrosis/mamdani.fis";
  std::FILE* file = std::fopen(path.c_str(), "rb");
  REQUIRE(file);
  std::string text;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, file)) > 0;) text.append(buffer, n);
  std::fclose(file);
  DiagnosticList diagnostics;
  const RuleFile rules = load_rule_file(path, text, diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  const FuzzySystem& source = rules.systems.front();
  Bindings bindings;
  bindings.fixed = {{"HCV", 10.0, {}}, {"HBV", 7.0, {}}, {"ALD", 12.0, {}}};
  const std::optional<CompileResult> result = run_pipeline(source, bindings, PipelineOptions{}, diagnostics);
  REQUIRE(result);
  CHECK(result->system.rules.size() < source.rules.size() / 2);
  CHECK(largest_difference(source, result->system, {3, 4}, {10.0, 7.0, 12.0, 0.0, 0.0}, 21, 300) == 0.0);
}
