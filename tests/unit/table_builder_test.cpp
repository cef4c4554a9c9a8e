// compiler/backend/table: the table builder states a bound (or, outside the bound's class, an estimate) below its
// error target, which 1e6 held-out points plus local searches never exceed (the issue-11 table among them);
// honours fixed axis counts, uniform spacing, float precision and the grid budget, is the same on any number of
// threads; lookups at and beyond the upper ends; the C++/CUDA arrays header.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "compiler/backend/table/table_arrays.h"
#include "compiler/backend/table/table_builder.h"
#include "compiler/eval/interpreter.h"
#include "compiler/frontend/rule_file_loader.h"
#include "diagnostics/number_format.h"

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
  PipelineOptions pipeline;
  pipeline.interval_type2 = true;  // the table builder takes type-2 systems
  std::optional<CompileResult> result = run_pipeline(source, bindings, pipeline, diagnostics);
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

// The largest |table - interpreter on `source`| found at `count` uniform points of the table's box (seeded) and by
// a compass search from each of the 16 worst: each axis in turn, +- a step that starts at a quarter of the local
// cell and halves when no move improves, 40 rounds. Two threads. Independent of the builder's own estimate code.
double largest_error_found(const LookupTable& table, const FuzzySystem& source, std::size_t count,
                           std::uint64_t seed) {
  const std::size_t d = table.axes.size(), m = table.output_names.size();
  std::vector<double> base(source.inputs.size(), 0.0);
  for (const TableFixedInput& fixed : table.fixed_inputs) base[static_cast<std::size_t>(source.find_input(fixed.name))] = fixed.value;
  std::vector<const double*> pointers;
  std::vector<int> counts;
  const TableView<double> view = view_of(table, pointers, counts);
  const auto error_at = [&](Interpreter& interpreter, const std::vector<double>& x) {
    std::vector<double> inputs = base, out(m);
    for (std::size_t a = 0; a < d; ++a) inputs[table.axes[a].input_index] = x[a];
    interpolate_table(view, x.data(), out.data());
    const std::vector<double> reference = interpreter.evaluate(inputs).outputs;
    double error = 0.0;
    for (std::size_t o = 0; o < m; ++o) error = std::max(error, std::fabs(out[o] - reference[o]));
    return error;
  };
  std::vector<double> points(count * d);
  std::mt19937_64 random(seed);
  for (std::size_t i = 0; i < count; ++i)
    for (std::size_t a = 0; a < d; ++a) {
      const std::vector<double>& b = table.axes[a].breakpoints;
      points[i * d + a] = b.front() + (b.back() - b.front()) * (static_cast<double>(random() >> 11) * 0x1.0p-53);
    }
  std::vector<double> errors(count);
  const auto sweep = [&](std::size_t begin, std::size_t end) {
    Interpreter interpreter(source);
    for (std::size_t i = begin; i < end; ++i)
      errors[i] = error_at(interpreter, std::vector<double>(points.begin() + static_cast<std::ptrdiff_t>(i * d),
                                                            points.begin() + static_cast<std::ptrdiff_t>((i + 1) * d)));
  };
  std::thread other(sweep, count / 2, count);
  sweep(0, count / 2);
  other.join();
  std::vector<std::size_t> order(count);
  for (std::size_t i = 0; i < count; ++i) order[i] = i;
  std::partial_sort(order.begin(), order.begin() + 16, order.end(),
                    [&](std::size_t a, std::size_t b) { return errors[a] > errors[b]; });
  double worst = errors[order[0]];
  Interpreter interpreter(source);
  for (std::size_t k = 0; k < 16; ++k) {
    std::vector<double> x(points.begin() + static_cast<std::ptrdiff_t>(order[k] * d),
                          points.begin() + static_cast<std::ptrdiff_t>((order[k] + 1) * d));
    double best = errors[order[k]];
    std::vector<double> step(d);
    for (std::size_t a = 0; a < d; ++a) {
      const std::vector<double>& b = table.axes[a].breakpoints;
      const auto at = std::upper_bound(b.begin(), b.end(), x[a]);
      const std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(at - b.begin()), b.size() - 1);
      step[a] = 0.25 * (b[i] - b[i - 1]);
    }
    for (int round = 0; round < 40; ++round) {
      bool moved = false;
      for (std::size_t a = 0; a < d; ++a)
        for (const double sign : {1.0, -1.0}) {
          std::vector<double> y = x;
          y[a] = std::clamp(x[a] + sign * step[a], table.axes[a].breakpoints.front(), table.axes[a].breakpoints.back());
          const double e = error_at(interpreter, y);
          if (e > best) {
            best = e;
            x = y;
            moved = true;
          }
        }
      if (!moved)
        for (double& s : step) s /= 2.0;
    }
    worst = std::max(worst, best);
  }
  return worst;
}

std::string source_text(const std::string& relative) {
  std::ifstream in(std::string(FMPC_SOURCE_DIR) + "/" + relative);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST_CASE("the issue's liver table: the stated bound holds at its point and on 1e6 held-out points", "[table-builder][heavy]") {
  // fmpc compile rulesets/liver_fibrosis/mamdani.fis --target table --fix ALD=12 --fix CLD=9 --fix NAFLD=8
  //   --max-error 0.1 --spacing uniform: on main at 6bad843 it stated 0.0699 kPa from held-out points, and the
  // table was 0.1203 kPa from the interpreter at HCV = 10.019762901974728, HBV = 7.810095226429762.
  DiagnosticList diagnostics;
  RuleFile file = load_rule_file("mamdani.fis", source_text("rulesets/liver_fibrosis/mamdani.fis"), diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  const FuzzySystem& source = file.systems.front();
  const CompileResult compiled =
      compile(source, Bindings{{{"ALD", 12.0, {}}, {"CLD", 9.0, {}}, {"NAFLD", 8.0, {}}}, {}});
  TableBuildOptions options;
  options.max_error = 0.1;
  options.spacing = BreakpointSpacing::Uniform;
  TableBuildStatistics stats;
  const std::optional<LookupTable> table = build_table(source, compiled, options, diagnostics, &stats);
  INFO(render_all(diagnostics, SourceFiles{}));
  REQUIRE(table);
  CHECK(table->error_kind == TableErrorKind::Bound);
  CHECK(table->max_error <= 0.1);
  CHECK(stats.bound_limitation.empty());
  const double at_issue_point =
      std::fabs(interpolate(*table, {10.019762901974728, 7.810095226429762}) -
                evaluate(source, {10.019762901974728, 7.810095226429762, 12.0, 9.0, 8.0}).outputs[0]);
  CHECK(at_issue_point <= table->max_error);
  const double found = largest_error_found(*table, source, 1000000, 20261124);
  CHECK(found <= table->max_error);
  WARN("issue-11 liver table: " << table->axes[0].breakpoints.size() << " x " << table->axes[1].breakpoints.size()
                                 << ", bound " << table->max_error << " kPa; at the issue's point " << at_issue_point
                                 << ", largest found over 1e6 points and local searches " << found);
}

TEST_CASE("bounds and estimates hold on 1e6 held-out points plus local searches", "[heavy][table-builder]") {
  const FuzzySystem source = tipper();
  struct Variant {
    const char* label;
    bool type2;
    BreakpointSpacing spacing;
    TableValueType type;
    double max_error;
    TableErrorKind kind;
  };
  for (const Variant& v : {Variant{"refined, float32", false, BreakpointSpacing::Refined, TableValueType::Float32,
                                   0.05, TableErrorKind::Bound},
                           Variant{"uniform", false, BreakpointSpacing::Uniform, TableValueType::Float64, 0.2,
                                   TableErrorKind::Bound},
                           Variant{"interval type-2 (an estimate)", true, BreakpointSpacing::Refined,
                                   TableValueType::Float64, 0.1, TableErrorKind::Estimate}}) {
    FuzzySystem variant = source;
    if (v.type2) {  // MATLAB's lower scale 0.8 and lag 0.1 on every input term
      variant.interval_type2 = true;
      for (Variable& input : variant.inputs)
        for (Term& term : input.terms) term.footprint = Footprint{FootprintKind::ScaleLag, 0.8, 0.1, {}, {}};
    }
    const CompileResult compiled = compile(variant, Bindings{{{"mood", 0.25, {}}}, {}});
    TableBuildOptions options = fast_options(v.max_error);
    options.spacing = v.spacing;
    options.value_type = v.type;
    DiagnosticList diagnostics;
    TableBuildStatistics stats;
    const std::optional<LookupTable> table = build_table(variant, compiled, options, diagnostics, &stats);
    INFO(v.label << ": " << render_all(diagnostics, SourceFiles{}));
    REQUIRE(table);
    CHECK(table->error_kind == v.kind);
    CHECK(table->max_error <= v.max_error);
    CHECK(stats.bound_limitation.empty() == (v.kind == TableErrorKind::Bound));
    const double found = largest_error_found(*table, variant, 1000000, 99);
    INFO("stated " << table->max_error << ", found " << found);
    CHECK(found <= table->max_error);
  }
}

TEST_CASE("refined tables state a bound below --max-error and where it is largest", "[table-builder]") {
  const FuzzySystem source = tipper();
  const CompileResult compiled = compile(source, Bindings{{{"mood", 0.25, {}}}, {}});
  DiagnosticList diagnostics;
  TableBuildStatistics stats;
  const std::optional<LookupTable> table = build_table(source, compiled, fast_options(0.05), diagnostics, &stats);
  REQUIRE(table);
  CHECK(table->error_kind == TableErrorKind::Bound);
  CHECK(stats.cells > 0);
  CHECK(stats.cells_bounded > 0);
  CHECK(table->max_error <= 0.05);
  CHECK(table->max_error > 0.0);
  REQUIRE(table->axes.size() == 2);
  CHECK(table->axes[0].input_name == "service");
  CHECK(table->axes[1].input_index == 1);
  REQUIRE(table->fixed_inputs.size() == 1);
  CHECK(table->fixed_inputs[0].name == "mood");
  DiagnosticList valid;
  CHECK(validate_table(*table, "built", valid));
  // The bound is largest in the cell whose centre is recorded; the table is within it there.
  REQUIRE(table->max_error_location.size() == 2);
  const double x = table->max_error_location[0], y = table->max_error_location[1];
  const double reference = evaluate(source, {x, y, 0.25}).outputs[0];
  CHECK(std::fabs(interpolate(*table, {x, y}) - reference) <= table->max_error);
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
  // The training points' measured error already exceeds the target at the budget: said before any bounding.
  const std::string& message = diagnostics.items()[0].message;
  CHECK(message.find("cannot reach --max-error 1e-06 within 2000 grid points") != std::string::npos);
  CHECK(message.find("with a maximum error of") != std::string::npos);

  // Where the few training points are met but no grid within the budget bounds every cell below the target.
  options.max_error = 1e-3;
  options.training_points = 5;
  DiagnosticList bound_budget;
  CHECK_FALSE(build_table(source, compiled, options, bound_budget));
  REQUIRE(bound_budget.error_count() == 1);
  CHECK(bound_budget.items()[0].message.find(
            "cannot bound the table's error below --max-error 0.001 within 2000 grid points") != std::string::npos);
  CHECK(bound_budget.items()[0].message.find("its error bound is") != std::string::npos);

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

TEST_CASE("a --max-error below what rounding lets a table reach is refused at once, naming the floor",
          "[table-builder]") {
  // Before this check, --max-error 1e-300 refined for more than a minute before the budget stopped it.
  const FuzzySystem source = tipper();
  const CompileResult compiled = compile(source, Bindings{});
  for (const TableValueType type : {TableValueType::Float64, TableValueType::Float32}) {
    const double floor = reachable_error_floor(compiled, type);
    // tipper's output is [0, 30]: the interpreter's 1e-12 of the range, plus half an ulp of 30 in the value type.
    CHECK(floor == 30.0 * (type == TableValueType::Float32 ? 0x1.0p-24 : 0x1.0p-53) + 30e-12);
    for (const double target : {1e-300, 4.9e-324, floor}) {
      TableBuildOptions options = fast_options(target);
      options.value_type = type;
      TableBuildStatistics stats;
      DiagnosticList diagnostics;
      CHECK_FALSE(build_table(source, compiled, options, diagnostics, &stats));
      REQUIRE(diagnostics.error_count() == 1);
      CHECK(diagnostics.items()[0].range.file == "command line");
      CHECK(diagnostics.items()[0].message.find("its floor is " + format_number(floor)) != std::string::npos);
      CHECK(stats.rounds == 0);  // nothing evaluated
    }
  }
}

TEST_CASE("table arrays header holds the axes, counts and values", "[table-builder]") {
  LookupTable table;
  table.system_name = "s";
  table.source_path = "s.fis";
  table.axes.push_back({"x", "kPa", 0, {0.0, 0.5, 1.0}});
  table.output_names = {"y"};
  table.output_units = {"Pa"};
  table.values = {1.0, 2.5, 3.0};
  table.max_error = 0.01;
  table.max_error_location = {0.25};
  TableArraysOptions options;
  options.namespace_name = "scene::liver";
  DiagnosticList diagnostics;
  const std::string header = write_table_arrays(table, options, diagnostics).value();
  CHECK(header.find("namespace scene::liver {") != std::string::npos);
  CHECK(header.find("inline const double axis0[3] = {\n    0.0, 0.5, 1.0\n};") != std::string::npos);
  CHECK(header.find("inline const double values[3] = {\n    1.0, 2.5, 3.0\n};") != std::string::npos);
  CHECK(header.find("__device__ const int counts[1] = {3};") != std::string::npos);
  CHECK(header.find("maximum error against the interpreter (estimate, measured): 0.01, largest at x = 0.25") !=
        std::string::npos);
  CHECK(header.find("inline constexpr const char* kAxisUnits[] = {\"kPa\"};") != std::string::npos);
  CHECK(header.find("inline constexpr const char* kOutputUnits[] = {\"Pa\"};") != std::string::npos);
  CHECK(header.find("inline constexpr bool kMaxErrorIsBound = false;") != std::string::npos);
  table.value_type = TableValueType::Float32;
  table.values = {0.1, 2.0, 3.0};
  CHECK(write_table_arrays(table, options, diagnostics).value().find("const float values[3] = {\n    0.10000000149011612f, 2.0f, 3.0f") !=
        std::string::npos);
}
