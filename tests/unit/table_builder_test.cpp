// compiler/backend/table: the table builder meets its error target on held-out points, records where the worst
// error is, honours fixed axis counts, uniform spacing, float precision and the grid budget, is the same on any
// number of threads; lookups at and beyond the upper ends; the C++/CUDA arrays header.
#include <catch2/catch.hpp>

#include <cmath>
#include <string>
#include <vector>

#include "compiler/backend/table/table_arrays.h"
#include "compiler/backend/table/table_builder.h"
#include "compiler/eval/interpreter.h"
#include "compiler/frontend/rule_file_loader.h"

namespace {

using namespace fmpc;

const char* const kTipper = R"(system tipper
  type mamdani
  and min  or max  implication min  aggregation max
  defuzzify centroid samples 101
input service in [0, 10] dimensionless
  poor is gauss(mean 0, sd 1.5)
  good is gauss(mean 5, sd 1.5)
  excellent is gauss(mean 10, sd 1.5)
input food in [0, 10] dimensionless
  rancid is trapezoid(start 0, top_start 0, top_end 1, end 3)
  delicious is trapezoid(start 7, top_start 9, top_end 10, end 10)
input mood in [0, 1] dimensionless
  bad is linear_z(start 0, end 1)
output tip in [0, 30] "%"
  cheap is triangle(start 0, peak 5, end 10)
  average is triangle(start 10, peak 15, end 20)
  generous is triangle(start 20, peak 25, end 30)
rule r1: if service is poor or food is rancid then tip is cheap
rule r2: if service is good then tip is average
rule r3: if service is excellent or food is delicious then tip is generous
rule r4: if mood is bad and food is rancid then tip is cheap weight 0.5
)";

FuzzySystem tipper() {
  DiagnosticList diagnostics;
  RuleFile file = load_rule_file("tipper.fis", kTipper, diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  return file.systems.front();
}

CompileResult compile(const FuzzySystem& source, const Bindings& bindings) {
  DiagnosticList diagnostics;
  std::optional<CompileResult> result = run_pipeline(source, bindings, PipelineOptions{}, diagnostics);
  REQUIRE(result);
  return *result;
}

TableBuildOptions fast_options(double max_error) {
  TableBuildOptions options;
  options.max_error = max_error;
  options.held_out_points = 100000;
  options.training_points = 10000;
  options.threads = 2;
  return options;
}

double interpolate(const LookupTable& table, const std::vector<double>& query) {
  std::vector<const double*> pointers;
  std::vector<int> counts;
  const TableView<double> view = view_of(table, pointers, counts);
  double out = 0.0;
  interpolate_table(view, query.data(), &out);
  return out;
}

}  // namespace

TEST_CASE("refined tables meet --max-error on held-out points and record the worst point", "[table-builder]") {
  const FuzzySystem source = tipper();
  const CompileResult compiled = compile(source, Bindings{{{"mood", 0.25, {}}}, {}});
  DiagnosticList diagnostics;
  TableBuildStatistics stats;
  const std::optional<LookupTable> table = build_table(source, compiled, fast_options(0.05), diagnostics, &stats);
  REQUIRE(table);
  CHECK(stats.held_out_points >= 100000);
  CHECK(table->max_error <= 0.05);
  CHECK(table->max_error > 0.0);
  REQUIRE(table->axes.size() == 2);
  CHECK(table->axes[0].input_name == "service");
  CHECK(table->axes[1].input_index == 1);
  REQUIRE(table->fixed_inputs.size() == 1);
  CHECK(table->fixed_inputs[0].first == "mood");
  DiagnosticList valid;
  CHECK(validate_table(*table, "built", valid));
  // The recorded error is what the table and the interpreter give at the recorded point.
  REQUIRE(table->max_error_location.size() == 2);
  const double x = table->max_error_location[0], y = table->max_error_location[1];
  const double reference = evaluate(source, {x, y, 0.25}).outputs[0];
  CHECK(std::fabs(interpolate(*table, {x, y}) - reference) == Approx(table->max_error).epsilon(1e-12));
  // Grid points hold the interpreter's values; at and beyond the upper ends the lookup is the corner value.
  const double corner = evaluate(source, {10.0, 10.0, 0.25}).outputs[0];
  CHECK(interpolate(*table, {10.0, 10.0}) == corner);
  CHECK(interpolate(*table, {12.0, 1e300}) == corner);
  CHECK(interpolate(*table, {-5.0, -1e300}) == evaluate(source, {0.0, 0.0, 0.25}).outputs[0]);
  CHECK(std::isnan(interpolate(*table, {std::nan(""), 1.0})));
  // A .fzt round trip keeps the measurement.
  DiagnosticList parse_diagnostics;
  const std::optional<LookupTable> loaded = parse_fzt("t.fzt", serialize_fzt(*table), parse_diagnostics);
  REQUIRE(loaded);
  CHECK(loaded->max_error == table->max_error);
  CHECK(loaded->values == table->values);
}

TEST_CASE("uniform tables double axes, fixed counts stay, float values are rounded, threads do not matter",
          "[table-builder]") {
  const FuzzySystem source = tipper();
  const CompileResult compiled = compile(source, Bindings{{{"mood", 1.0, {}}}, {{"food", 41, {}}}});
  TableBuildOptions options = fast_options(0.5);
  options.spacing = BreakpointSpacing::Uniform;
  options.value_type = TableValueType::Float32;
  DiagnosticList diagnostics;
  const std::optional<LookupTable> table = build_table(source, compiled, options, diagnostics);
  INFO(render_all(diagnostics, SourceFiles{}));
  REQUIRE(table);
  CHECK(table->max_error <= 0.5);
  REQUIRE(table->axes[1].breakpoints.size() == 41);
  CHECK(table->axes[1].breakpoints[4] == 1.0);
  CHECK(table->axes[1].breakpoints[40] == 10.0);
  const std::size_t n = table->axes[0].breakpoints.size();
  CHECK(((n - 1) & (n - 2)) == 0);  // 2^k + 1 breakpoints
  for (std::size_t k = 0; k < n; ++k)
    CHECK(table->axes[0].breakpoints[k] == Approx(10.0 * static_cast<double>(k) / static_cast<double>(n - 1)));
  for (double v : table->values) CHECK(v == static_cast<double>(static_cast<float>(v)));

  options.threads = 1;
  const std::optional<LookupTable> single = build_table(source, compiled, options, diagnostics);
  REQUIRE(single);
  CHECK(single->values == table->values);
  CHECK(single->max_error == table->max_error);
  CHECK(single->max_error_location == table->max_error_location);
}

TEST_CASE("a target far beyond the budget is refused after two rounds, with the estimate", "[table-builder]") {
  const FuzzySystem source = tipper();
  const CompileResult compiled = compile(source, Bindings{});
  TableBuildOptions options = fast_options(1e-9);
  options.max_grid_points = 2000;
  std::vector<TableBuildProgress> rounds;
  options.progress = [&](const TableBuildProgress& p) { rounds.push_back(p); };
  DiagnosticList diagnostics;
  TableBuildStatistics stats;
  CHECK_FALSE(build_table(source, compiled, options, diagnostics, &stats));
  REQUIRE(diagnostics.error_count() == 1);
  CHECK(stats.rounds == kEarlyRefusalRounds);
  REQUIRE(rounds.size() == static_cast<std::size_t>(kEarlyRefusalRounds));
  CHECK(rounds.back().estimated_grid_points > 16 * 2000.0);
  CHECK(rounds.back().budget == 2000);
  CHECK(rounds.front().round == 1);
  const std::string& message = diagnostics.items()[0].message;
  CHECK(message.find("after 2 rounds") != std::string::npos);
  CHECK(message.find("an estimate") != std::string::npos);

  // Off, the build refines up to the budget and fails there (the test below).
  options.early_refusal_factor = 0;
  rounds.clear();
  DiagnosticList late;
  CHECK_FALSE(build_table(source, compiled, options, late, &stats));
  CHECK(stats.rounds > kEarlyRefusalRounds);
  CHECK(late.items()[0].message.find("an estimate") == std::string::npos);
}

TEST_CASE("an unreachable --max-error stops at the grid budget with what was reached", "[table-builder]") {
  const FuzzySystem source = tipper();
  const CompileResult compiled = compile(source, Bindings{});
  TableBuildOptions options = fast_options(1e-6);
  options.max_grid_points = 2000;
  options.early_refusal_factor = 0;
  DiagnosticList diagnostics;
  CHECK_FALSE(build_table(source, compiled, options, diagnostics));
  REQUIRE(diagnostics.error_count() == 1);
  const std::string& message = diagnostics.items()[0].message;
  CHECK(message.find("cannot reach --max-error 1e-06 within 2000 grid points") != std::string::npos);
  CHECK(message.find("maximum error of") != std::string::npos);

  // When the error lies along an axis whose count is fixed, refining the others does not help: say so at once.
  const CompileResult coarse = compile(source, Bindings{{{"mood", 1.0, {}}}, {{"food", 3, {}}}});
  DiagnosticList fixed_axis;
  CHECK_FALSE(build_table(source, coarse, fast_options(0.05), fixed_axis));
  REQUIRE(fixed_axis.error_count() == 1);
  CHECK(fixed_axis.items()[0].message.find("cannot refine the grid to reach") != std::string::npos);
  CHECK(fixed_axis.items()[0].notes[0].find("--vary NAME:points") != std::string::npos);

  options.max_error = -1.0;
  DiagnosticList negative;
  CHECK_FALSE(build_table(source, compiled, options, negative));
  CHECK(negative.items()[0].message.find("positive") != std::string::npos);
}

TEST_CASE("table arrays header holds the axes, counts and values", "[table-builder]") {
  LookupTable table;
  table.system_name = "s";
  table.source_path = "s.fis";
  table.axes.push_back({"x", 0, {0.0, 0.5, 1.0}});
  table.output_names = {"y"};
  table.values = {1.0, 2.5, 3.0};
  table.max_error = 0.01;
  table.max_error_location = {0.25};
  TableArraysOptions options;
  options.namespace_name = "scene::liver";
  const std::string header = write_table_arrays(table, options);
  CHECK(header.find("namespace scene::liver {") != std::string::npos);
  CHECK(header.find("inline const double axis0[3] = {\n    0.0, 0.5, 1.0\n};") != std::string::npos);
  CHECK(header.find("inline const double values[3] = {\n    1.0, 2.5, 3.0\n};") != std::string::npos);
  CHECK(header.find("__device__ const int counts[1] = {3};") != std::string::npos);
  CHECK(header.find("measured maximum error against the interpreter: 0.01 at x = 0.25") != std::string::npos);
  table.value_type = TableValueType::Float32;
  table.values = {0.1, 2.0, 3.0};
  CHECK(write_table_arrays(table, options).find("const float values[3] = {\n    0.10000000149011612f, 2.0f, 3.0f") !=
        std::string::npos);
}
