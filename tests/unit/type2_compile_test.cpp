// fmpc compile on interval type-2 systems: specialize folds fixed inputs into both ends of each rule's firing
// interval (Rule::folded_grade, folded_grade_lower), prune_rules removes the rules whose upper firing is provably 0,
// fuse_consequents works end by end, drop_dead_terms as in type-1; the specialised system, interpreted and as
// generated C++ (compiler/backend/cpp/emit_type2.h), equals the source with the fixed inputs bound: bitwise where
// every fold is min / max, else within 1e-12 of the output range. Tables (--target table) and fmpc trade take
// type-2 systems too.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "compiler/backend/cpp/emit_cpp.h"
#include "compiler/backend/table/table_builder.h"
#include "compiler/eval/interpreter.h"
#include "compiler/frontend/rule_file_loader.h"
#include "compiler/frontend/ir_printer.h"
#include "diagnostics/number_format.h"
#include "compiler/passes/drop_dead_terms.h"
#include "compiler/passes/fuse_consequents.h"
#include "compiler/passes/pipeline.h"
#include "compiler/passes/prune_rules.h"
#include "compiler/passes/specialize.h"
#include "kernels/table_math.h"
#include "tests/support/generated_program.h"
#include "tests/support/random_system.h"

namespace {

namespace fs = std::filesystem;
using fmpc::Bindings;
using fmpc::CompileResult;
using fmpc::DiagnosticList;
using fmpc::Evaluation;
using fmpc::FuzzySystem;
using fmpc::PipelineOptions;

FuzzySystem load_text(const std::string& path, const std::string& text) {
  DiagnosticList diagnostics;
  fmpc::RuleFile file = fmpc::load_rule_file(path, text, diagnostics);
  INFO(path);
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(file.systems.size() == 1);
  return file.systems.front();
}

FuzzySystem load_file(const fs::path& path) { return load_text(path.string(), fmpc::testing::read_text_file(path)); }

FuzzySystem liver_it2() { return load_file(fs::path(FMPC_SOURCE_DIR) / "rulesets" / "liver_fibrosis" / "it2.fis"); }
FuzzySystem valve_it2() {
  return load_file(fs::path(FMPC_SOURCE_DIR) / "tests" / "golden" / "compile_type2_cpp" / "valve_it2.fis");
}

// A Mamdani type-2 system built so that every pass has work: with `a` fixed, r1/r2 and r4/r5 differ only in the
// folded grade (fused), r3 names a term that is 0 on a's range (pruned), `unused` is named by no rule (dropped).
const char* const kSmallMamdani = R"(system small_it2m
  type interval_type2 mamdani
  type_reduction enhanced_karnik_mendel
input a in [0, 10] dimensionless
  low is triangle(start 0, peak 2, end 5) lower scale 0.8 lag 0.1
  high is gauss(mean [6, 8], sd 1.5)
  far is triangle(start 20, peak 25, end 30)
input b in [0, 1] dimensionless
  mid is gauss(mean 0.5, sd [0.1, 0.2])
  up is upper linear_s(start 0, end 1) lower linear_s(start 0.3, end 1)
  unused is triangle(start 0, peak 0.5, end 1)
output z in [0, 1] dimensionless
  s is triangle(start 0, peak 0.25, end 0.5) lower scale 0.7 lag 0
  m is gauss(mean [0.45, 0.55], sd 0.1)
  l is gauss(mean 0.8, sd [0.05, 0.1])
rule r1: if a is low and b is mid then z is s
rule r2: if a is high and b is mid then z is s
rule r3: if a is far and b is up then z is l
rule r4: if a is high or b is up then z is m
rule r5: if a is not low or b is up then z is m
rule r6: if a is very high and b is not mid then z is l weight 0.5
)";

bool same_bits(double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); }

bool within(double a, double b, double tolerance) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return std::fabs(a - b) <= tolerance;
}

// The source's inputs for a point of the compiled system: the fixed values plus the point on the varying inputs.
std::vector<double> source_point(const FuzzySystem& source, const CompileResult& compiled, const std::vector<double>& point) {
  std::vector<double> inputs(source.inputs.size(), 0.0);
  for (const auto& [index, value] : compiled.fixed) inputs[static_cast<std::size_t>(index)] = value;
  for (std::size_t a = 0; a < compiled.source_inputs.size(); ++a)
    inputs[static_cast<std::size_t>(compiled.source_inputs[a])] = point[a];
  return inputs;
}

// Every fold min or max and no linear output: the specialised evaluation is the same arithmetic, bit for bit.
bool bitwise_expected(const FuzzySystem& system) {
  if (system.and_method != fmpc::TNorm::Minimum || system.or_method != fmpc::SNorm::Maximum) return false;
  for (const fmpc::Variable& output : system.outputs)
    for (const fmpc::Term& term : output.terms)
      if (term.mf.kind == fmpc::MfKind::Linear) return false;
  return true;
}

struct Comparison {
  std::size_t points = 0, bitwise = 0, wide = 0;
  double worst = 0.0;  // largest difference as a fraction of the output range
};

// Compares the source evaluated at the bound point with `specialised` at the point: crisp output and both ends of
// the type-reduced interval, per output.
void compare_point(const FuzzySystem& source, const CompileResult& compiled, const FuzzySystem& specialised,
                   const std::vector<double>& point, bool bitwise, Comparison& tally) {
  const Evaluation want = fmpc::evaluate(source, source_point(source, compiled, point));
  const Evaluation got = fmpc::evaluate(specialised, point);
  REQUIRE(got.outputs.size() == want.outputs.size());
  REQUIRE(got.intervals.size() == want.intervals.size());
  ++tally.points;
  bool all_same = true;
  for (std::size_t o = 0; o < want.outputs.size(); ++o) {
    const double range = source.outputs[o].max - source.outputs[o].min;
    const double values[3][2] = {{want.outputs[o], got.outputs[o]},
                                 {want.intervals[o].lower, got.intervals[o].lower},
                                 {want.intervals[o].upper, got.intervals[o].upper}};
    for (const auto& pair : values) {
      INFO("output " << o << ": " << pair[0] << " vs " << pair[1]);
      all_same = all_same && same_bits(pair[0], pair[1]);
      if (bitwise) CHECK(same_bits(pair[0], pair[1]));
      CHECK(within(pair[0], pair[1], 1e-12 * range));
      if (std::isfinite(pair[0]) && std::isfinite(pair[1]))
        tally.worst = std::max(tally.worst, std::fabs(pair[0] - pair[1]) / range);
    }
    if (want.intervals[o].upper - want.intervals[o].lower > 1e-6 * range) ++tally.wide;
  }
  tally.bitwise += all_same ? 1 : 0;
}

// Points inside the varying inputs' ranges (where prune_rules' bounds hold), the range ends, and a NaN.
std::vector<std::vector<double>> in_range_points(const FuzzySystem& system, std::uint64_t seed, std::size_t count) {
  std::vector<std::vector<double>> points = fmpc::testing::random_inputs(system, seed, count);
  std::vector<double> low, high, nan;
  for (const fmpc::Variable& v : system.inputs) {
    low.push_back(v.min);
    high.push_back(v.max);
    nan.push_back(nan.empty() ? std::numeric_limits<double>::quiet_NaN() : v.min);
  }
  points.push_back(low);
  points.push_back(high);
  points.push_back(nan);
  return points;
}

// Fixes a seeded, non-empty proper subset of the inputs at seeded values in range (one at an end of its range).
Bindings random_bindings(const FuzzySystem& system, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  const auto uniform = [&random] { return static_cast<double>(random() >> 11) * 0x1.0p-53; };
  Bindings bindings;
  const std::size_t n = system.inputs.size();
  std::size_t fixed = 0;
  for (std::size_t i = 0; i < n && fixed + 1 < n; ++i) {
    if (uniform() < 0.5) continue;
    const fmpc::Variable& v = system.inputs[i];
    const double value = fixed == 0 && seed % 5 == 0 ? v.max : v.min + uniform() * (v.max - v.min);
    bindings.fixed.push_back({v.name, value, {}});
    ++fixed;
  }
  if (fixed == 0 && n >= 2) bindings.fixed.push_back({system.inputs[n - 1].name, system.inputs[n - 1].min, {}});
  return bindings;
}

fmpc::testing::RandomSystemOptions random_type2_options() {
  fmpc::testing::RandomSystemOptions options;
  options.interval_type2 = true;
  options.exact_samples = false;
  options.consequent_negation = true;
  options.consequent_hedges = true;
  options.min_inputs = 2;
  options.max_inputs = 4;
  options.max_rules = 10;
  return options;
}

CompileResult compile(const FuzzySystem& source, const Bindings& bindings) {
  PipelineOptions options;
  options.interval_type2 = true;
  DiagnosticList diagnostics;
  std::optional<CompileResult> result = fmpc::run_pipeline(source, bindings, options, diagnostics);
  INFO(source.name);
  REQUIRE(result);
  REQUIRE_FALSE(diagnostics.has_errors());
  return *result;
}

// The specialise pass alone (no pruning or fusing), as run_pipeline's bindings resolve it.
CompileResult specialise_only(const FuzzySystem& source, const Bindings& bindings) {
  CompileResult result = compile(source, bindings);
  result.system = source;
  std::vector<fmpc::InputValue> fixed;
  for (const auto& [index, value] : result.fixed) fixed.push_back({index, value});
  fmpc::specialize(result.system, fixed);
  return result;
}

}  // namespace

TEST_CASE("specialize folds fixed inputs into both ends of type-2 firing intervals", "[type2-compile]") {
  const FuzzySystem source = load_text("small.fis", kSmallMamdani);
  const CompileResult compiled = specialise_only(source, Bindings{{{"a", 3.0, {}}}, {}});
  const FuzzySystem& system = compiled.system;
  REQUIRE(system.inputs.size() == 1);
  CHECK(system.inputs[0].name == "b");
  // r1 = low(3) and mid(b): low is a triangle 0-2-5, lower scale 0.8 lag 0.1: upper (5 - 3) / 3, lower
  // 0.8 (2/3 - 0.1) / 0.9. The fold starts at the and-identity 1, and min(1, g) = g.
  const fmpc::Rule& r1 = system.rules[0];
  REQUIRE(r1.folded_grade);
  REQUIRE(r1.folded_grade_lower);
  CHECK(*r1.folded_grade == (5.0 - 3.0) / 3.0);
  CHECK(*r1.folded_grade_lower == 0.8 * (((5.0 - 3.0) / 3.0 - 0.1) / (1.0 - 0.1)));
  CHECK(r1.antecedent.size() == 1);
  // r5 = not low(3) or up(b): not [l, u] = [1 - u, 1 - l], folded into the or-identity 0.
  const fmpc::Rule& r5 = system.rules[4];
  CHECK(*r5.folded_grade == 1.0 - *r1.folded_grade_lower);
  CHECK(*r5.folded_grade_lower == 1.0 - *r1.folded_grade);
  // The dump shows the interval.
  const std::string dump = fmpc::print_ir(system);
  const std::string fixed = "<fixed [" + fmpc::format_number(*r1.folded_grade_lower) + ", " +
                            fmpc::format_number(*r1.folded_grade) + "]>";
  CHECK(dump.find("rule r1: if " + fixed + " and b is mid then z is s") != std::string::npos);
  // Type-1 systems keep folded_grade_lower empty.
  FuzzySystem type1 = source;
  type1.interval_type2 = false;
  for (auto* variables : {&type1.inputs, &type1.outputs})
    for (fmpc::Variable& v : *variables)
      for (fmpc::Term& t : v.terms) t.footprint.reset();
  fmpc::specialize(type1, {{0, 3.0}});
  for (const fmpc::Rule& rule : type1.rules) CHECK_FALSE(rule.folded_grade_lower);
  // And the specialised system is the source at a = 3, bitwise (min / max folds).
  Comparison tally;
  for (const auto& point : in_range_points(system, 5, 200)) compare_point(source, compiled, system, point, true, tally);
  CHECK(tally.bitwise == tally.points);
  CHECK(tally.wide > tally.points / 2);
}

TEST_CASE("specialised type-2 rule files equal the source with the fixed inputs bound", "[type2-compile]") {
  struct FileCase {
    FuzzySystem system;
    std::vector<Bindings> bindings;
  };
  std::vector<FileCase> cases;
  cases.push_back({liver_it2(), {Bindings{{{"HCV", 10.0, {}}, {"ALD", 30.0, {}}}, {}},
                                 Bindings{{{"HBV", 0.0, {}}, {"CLD", 75.0, {}}, {"NAFLD", 8.0, {}}}, {}}}});
  cases.push_back({valve_it2(), {Bindings{{{"level", 5.0, {}}}, {}}, Bindings{{{"rate", -0.25, {}}}, {}}}});
  cases.push_back({load_text("small.fis", kSmallMamdani), {Bindings{{{"a", 7.0, {}}}, {}}, Bindings{{{"b", 0.9, {}}}, {}}}});
  std::uint64_t seed = 11;
  for (const FileCase& c : cases)
    for (const Bindings& bindings : c.bindings) {
      INFO(c.system.name << " with " << bindings.fixed.front().name << " fixed");
      const bool bitwise = bitwise_expected(c.system);
      Comparison only, full;
      const CompileResult specialised = specialise_only(c.system, bindings);
      const CompileResult compiled = compile(c.system, bindings);
      for (const auto& point : fmpc::testing::evaluator_test_points(specialised.system, seed++, 150))
        compare_point(c.system, specialised, specialised.system, point, bitwise, only);
      for (const auto& point : in_range_points(compiled.system, seed++, 150))
        compare_point(c.system, compiled, compiled.system, point, false, full);
      CHECK(only.wide > only.points / 4);
      WARN(c.system.name << ": specialised " << only.bitwise << "/" << only.points << " bitwise; whole pipeline "
                         << full.bitwise << "/" << full.points << " bitwise, worst " << full.worst
                         << " of the range; rules " << c.system.rules.size() << " -> " << compiled.system.rules.size());
    }
}

TEST_CASE("specialised random type-2 systems equal the source with the fixed inputs bound", "[type2-compile]") {
  const fmpc::testing::RandomSystemOptions options = random_type2_options();
  // Every other system: Mamdani with max aggregation and few terms, where specialising leaves rules to fuse; every
  // fourth of those with min / max folds (the bitwise case).
  fmpc::testing::RandomSystemOptions fusable = options;
  fusable.sugeno = false;
  fusable.aggregation_methods = {fmpc::SNorm::Maximum};
  fusable.max_terms = 2;
  fmpc::testing::RandomSystemOptions min_max = fusable;
  min_max.and_methods = {fmpc::TNorm::Minimum};
  min_max.or_methods = {fmpc::SNorm::Maximum};
  Comparison only, full;
  std::size_t systems = 0, bitwise_systems = 0, pruned = 0, fused = 0, dropped = 0;
  for (std::uint64_t seed = 500; seed < 580; ++seed) {
    const FuzzySystem source =
        fmpc::testing::random_system(seed, seed % 2 == 0 ? options : seed % 4 == 1 ? min_max : fusable);
    INFO("seed " << seed);
    const Bindings bindings = random_bindings(source, seed);
    REQUIRE_FALSE(bindings.fixed.empty());
    const bool bitwise = bitwise_expected(source);
    bitwise_systems += bitwise ? 1 : 0;
    ++systems;
    const CompileResult specialised = specialise_only(source, bindings);
    for (const auto& point : fmpc::testing::evaluator_test_points(specialised.system, seed * 3, 25))
      compare_point(source, specialised, specialised.system, point, bitwise, only);
    const CompileResult compiled = compile(source, bindings);
    // Pruning a Sugeno rule removes zero-weight points from type reduction, which EKM and EIASC round differently.
    const bool incremental = source.type_reduction == fmpc::TypeReduction::EnhancedKarnikMendel ||
                             source.type_reduction == fmpc::TypeReduction::Eiasc;
    const bool pipeline_bitwise = bitwise && (source.type == fmpc::SystemType::Mamdani || !incremental);
    for (const auto& point : in_range_points(compiled.system, seed * 5, 25))
      compare_point(source, compiled, compiled.system, point, pipeline_bitwise, full);
    for (const fmpc::PassReport& report : compiled.reports) {
      CHECK(report.error_bound == 0.0);
      if (report.pass == "prune_rules" && report.summary.rfind("removed 0 ", 0) != 0) ++pruned;
      if (report.pass == "fuse_consequents" && !report.details.empty() &&
          report.details.front().find("not applicable") == std::string::npos)
        ++fused;
      if (report.pass == "drop_dead_terms" && report.summary != "removed 0 terms") ++dropped;
    }
  }
  // The draw exercises the bitwise case, the regrouped case and every pass.
  CHECK(bitwise_systems > 0);
  CHECK(bitwise_systems < systems);
  CHECK(only.wide > only.points / 4);
  CHECK(fused > 0);
  CHECK(dropped > 0);
  WARN("random type-2: " << systems << " systems (" << bitwise_systems << " min/max), specialised "
                         << only.bitwise << "/" << only.points << " points bitwise, worst " << only.worst
                         << " of the range; whole pipeline " << full.bitwise << "/" << full.points
                         << " bitwise, worst " << full.worst << "; systems pruned " << pruned << ", fused " << fused
                         << ", terms dropped " << dropped);
}

TEST_CASE("type-2 firing-interval bounds hold at every point of the inputs' ranges", "[type2-compile]") {
  const fmpc::testing::RandomSystemOptions options = random_type2_options();
  std::size_t checked = 0, known = 0;
  for (std::uint64_t seed = 700; seed < 740; ++seed) {
    FuzzySystem system = fmpc::testing::random_system(seed, options);
    // Fold a fixed input in first, so the bounds start from folded grades too.
    if (seed % 2 == 0) system = specialise_only(system, random_bindings(system, seed)).system;
    fmpc::Interpreter interpreter(system);
    for (std::size_t r = 0; r < system.rules.size(); ++r) {
      const auto bounds = fmpc::firing_interval_bounds(system, r);
      if (!bounds) continue;
      ++known;
      CHECK(bounds->lower.low <= bounds->lower.high);
      CHECK(bounds->upper.low <= bounds->upper.high);
    }
    for (const auto& point : fmpc::testing::random_inputs(system, seed, 60)) {
      const Evaluation e = interpreter.evaluate(point);
      for (std::size_t r = 0; r < system.rules.size(); ++r) {
        const auto bounds = fmpc::firing_interval_bounds(system, r);
        if (!bounds) continue;
        INFO("seed " << seed << " rule " << r);
        const double slack = 1e-12;
        CHECK(e.firing_lower[r] >= bounds->lower.low - slack);
        CHECK(e.firing_lower[r] <= bounds->lower.high + slack);
        CHECK(e.firing_strengths[r] >= bounds->upper.low - slack);
        CHECK(e.firing_strengths[r] <= bounds->upper.high + slack);
        ++checked;
      }
    }
  }
  CHECK(known > 100);
  CHECK(checked > 10000);
}

TEST_CASE("prune, fuse and drop on a type-2 system: what each removed, exactly", "[type2-compile]") {
  const FuzzySystem source = load_text("small.fis", kSmallMamdani);
  const CompileResult compiled = compile(source, Bindings{{{"a", 3.0, {}}}, {}});
  REQUIRE(compiled.reports.size() == 4);
  for (const fmpc::PassReport& report : compiled.reports) {
    INFO(report.pass << ": " << report.summary);
    CHECK(report.summary.find("not run") == std::string::npos);
    CHECK(report.error_bound == 0.0);
  }
  // r3: far(3) is 0 on both ends; r6: very high(3) and not mid: nonzero, kept.
  CHECK(compiled.reports[1].summary == "removed 1 rules (1 cannot fire, 0 below epsilon)");
  CHECK(compiled.reports[1].details == std::vector<std::string>{"r3: cannot fire on the inputs' ranges"});
  // r2 -> r1 (same clause "b is mid", folded grades max-ed on each end); r5 -> r4.
  CHECK(compiled.reports[2].summary == "fused 5 rules into 3");
  CHECK(compiled.reports[2].details ==
        std::vector<std::string>{"r2 -> r1 (identical antecedents)", "r5 -> r4 (identical antecedents)"});
  CHECK(compiled.reports[3].details == std::vector<std::string>{"input 'b': term 'unused' (no rule names it)"});
  const fmpc::Rule& r1 = compiled.system.rules[0];
  const FuzzySystem unfused = specialise_only(source, Bindings{{{"a", 3.0, {}}}, {}}).system;
  CHECK(*r1.folded_grade == std::max(*unfused.rules[0].folded_grade, *unfused.rules[1].folded_grade));
  CHECK(*r1.folded_grade_lower == std::max(*unfused.rules[0].folded_grade_lower, *unfused.rules[1].folded_grade_lower));
  Comparison tally;
  for (const auto& point : in_range_points(compiled.system, 9, 300))
    compare_point(source, compiled, compiled.system, point, true, tally);
  CHECK(tally.bitwise == tally.points);

  // Without a binding, r3 cannot fire on a's range either.
  const CompileResult unbound = compile(source, Bindings{});
  CHECK(unbound.system.rules.size() == 5);
  // A rule named by no clause after pruning: its terms go (r3 was the only user of a's `far`).
  CHECK(unbound.system.inputs[0].terms.size() == 2);
}

TEST_CASE("run_pipeline on type-2 systems: fixed inputs taken, --prune-epsilon refused", "[type2-compile]") {
  const FuzzySystem source = valve_it2();
  PipelineOptions options;
  options.interval_type2 = true;
  options.prune_epsilon = 0.05;
  DiagnosticList diagnostics;
  CHECK_FALSE(fmpc::run_pipeline(source, Bindings{{{"level", 5.0, {}}}, {}}, options, diagnostics));
  REQUIRE(diagnostics.error_count() == 1);
  CHECK(diagnostics.items()[0].message ==
        "--prune-epsilon 0.05 needs an error bound, and none is known for interval type-2 system 'valve_it2'");
  // Called directly, the pass ignores epsilon on type-2 systems and says so.
  FuzzySystem direct = source;
  const fmpc::PassReport report = fmpc::prune_rules(direct, 0.5);
  CHECK(report.details.front().find("ignored: no error bound is known for interval type-2") != std::string::npos);
  CHECK(direct.rules.size() == source.rules.size());
  // Unless the caller's back end takes type-2, the system is refused.
  DiagnosticList refused;
  CHECK_FALSE(fmpc::run_pipeline(source, Bindings{}, PipelineOptions{}, refused));
  REQUIRE(refused.error_count() == 1);
  CHECK(refused.items()[0].message.find("is interval type-2") != std::string::npos);
}

TEST_CASE("generated C++ of specialised type-2 systems equals the source with the fixed inputs bound",
          "[type2-compile][emit]") {
  struct Case {
    std::string label;
    FuzzySystem source;
    CompileResult compiled;
    std::vector<std::vector<double>> points;
  };
  std::vector<Case> cases;
  const auto add = [&cases](const std::string& label, const FuzzySystem& source, const Bindings& bindings,
                            std::uint64_t seed) {
    Case c{label, source, compile(source, bindings), {}};
    c.points = in_range_points(c.compiled.system, seed, 40);
    cases.push_back(std::move(c));
  };
  add("liver_it2", liver_it2(), Bindings{{{"HCV", 10.0, {}}, {"ALD", 30.0, {}}}, {}}, 1);
  add("valve_it2 level", valve_it2(), Bindings{{{"level", 5.0, {}}}, {}}, 2);
  add("valve_it2 rate", valve_it2(), Bindings{{{"rate", -0.25, {}}}, {}}, 3);
  add("small_it2m", load_text("small.fis", kSmallMamdani), Bindings{{{"a", 3.0, {}}}, {}}, 4);
  const fmpc::testing::RandomSystemOptions options = random_type2_options();
  for (std::uint64_t seed = 600; seed < 624; ++seed) {
    const FuzzySystem source = fmpc::testing::random_system(seed, options);
    add("random type-2 seed " + std::to_string(seed), source, random_bindings(source, seed), seed);
  }

  fmpc::testing::ScratchFolder folder("type2_compile");
  std::string driver = "#include <cstdio>\n#include <cstdlib>\n#include <vector>\n";
  std::string entries;
  for (std::size_t c = 0; c < cases.size(); ++c) {
    fmpc::EmitOptions emit;
    emit.source_path = cases[c].label;
    emit.namespace_name = "case" + std::to_string(c);
    emit.header_path = "case" + std::to_string(c) + ".h";
    DiagnosticList diagnostics;
    const auto header = fmpc::emit_evaluator(cases[c].compiled.system, emit, diagnostics);
    INFO(cases[c].label);
    REQUIRE(header);
    fmpc::testing::write_text_file(folder.path() / emit.header_path, *header);
    driver += "#include \"" + emit.header_path + "\"\n";
    entries += "  {" + emit.namespace_name + "::kInputCount, " + emit.namespace_name + "::kOutputCount, &" +
               emit.namespace_name + "::evaluate_interval<double>},\n";
  }
  driver += R"(
struct Entry {
  std::size_t inputs, outputs;
  unsigned (*interval)(const double*, double*, double*, double*);
};
static const Entry kEntries[] = {
)" + entries + R"(};
int main(int argc, char** argv) {
  if (argc != 3) return 2;
  std::FILE* in = std::fopen(argv[1], "r");
  std::FILE* out = std::fopen(argv[2], "w");
  if (!in || !out) return 3;
  unsigned long index = 0;
  while (std::fscanf(in, "%lu", &index) == 1) {
    const Entry& e = kEntries[index];
    std::vector<double> x(e.inputs + 1), y(e.outputs), l(e.outputs), h(e.outputs);
    for (std::size_t i = 0; i < e.inputs; ++i) {
      char word[64];
      if (std::fscanf(in, "%63s", word) != 1) return 4;
      x[i] = std::strtod(word, nullptr);
    }
    e.interval(x.data(), y.data(), l.data(), h.data());
    for (std::size_t o = 0; o < e.outputs; ++o) std::fprintf(out, " %a %a %a", y[o], l[o], h[o]);
    std::fprintf(out, "\n");
  }
  return 0;
}
)";
  fmpc::testing::write_text_file(folder.path() / "driver.cpp", driver);
  std::string inputs;
  for (std::size_t c = 0; c < cases.size(); ++c)
    for (const auto& point : cases[c].points) {
      inputs += std::to_string(c);
      for (double x : point) {
        char text[64];
        std::snprintf(text, sizeof text, "%a", x);
        inputs += std::string(" ") + text;
      }
      inputs += "\n";
    }
  fmpc::testing::write_text_file(folder.path() / "inputs.txt", inputs);
  std::string log;
  const bool built = fmpc::testing::compile_generated_program(folder.path() / "driver.cpp", folder.path() / "driver", log);
  INFO("compiler output:\n" << log.substr(0, 4000));
  REQUIRE(built);
  const std::string run = (folder.path() / "driver").string() + " " + (folder.path() / "inputs.txt").string() + " " +
                          (folder.path() / "outputs.txt").string();
  REQUIRE(std::system(run.c_str()) == 0);

  std::istringstream lines(fmpc::testing::read_text_file(folder.path() / "outputs.txt"));
  const auto next = [&lines] {
    std::string word;
    lines >> word;
    return std::strtod(word.c_str(), nullptr);
  };
  std::size_t points = 0, wide = 0, folded_rules = 0;
  double worst = 0.0;
  for (const Case& c : cases) {
    for (const fmpc::Rule& rule : c.compiled.system.rules) folded_rules += rule.folded_grade_lower ? 1 : 0;
    for (const auto& point : c.points) {
      const Evaluation want = fmpc::evaluate(c.source, source_point(c.source, c.compiled, point));
      ++points;
      for (std::size_t o = 0; o < want.outputs.size(); ++o) {
        const double range = c.source.outputs[o].max - c.source.outputs[o].min;
        const double got[3] = {next(), next(), next()};
        const double expected[3] = {want.outputs[o], want.intervals[o].lower, want.intervals[o].upper};
        for (int k = 0; k < 3; ++k) {
          INFO(c.label << " output " << o << " value " << k << ": " << got[k] << " vs " << expected[k]);
          CHECK(within(got[k], expected[k], 1e-12 * range));
          if (std::isfinite(got[k]) && std::isfinite(expected[k]))
            worst = std::max(worst, std::fabs(got[k] - expected[k]) / range);
        }
        if (expected[2] - expected[1] > 1e-6 * range) ++wide;
      }
    }
  }
  CHECK(folded_rules > 20);
  CHECK(wide > points / 4);
  WARN("generated C++ of specialised type-2 systems: " << cases.size() << " systems, " << points
                                                       << " points, worst double difference " << worst
                                                       << " of the range");
}

TEST_CASE("tables of specialised type-2 systems sample the crisp output and meet --max-error", "[type2-compile][table]") {
  const FuzzySystem source = valve_it2();
  const CompileResult compiled = compile(source, Bindings{{{"level", 5.0, {}}}, {}});
  fmpc::TableBuildOptions options;
  options.max_error = 0.05;  // m/s on a [0, 20] output
  options.held_out_points = 100000;
  options.training_points = 10000;
  options.threads = 2;
  DiagnosticList diagnostics;
  fmpc::TableBuildStatistics stats;
  const std::optional<fmpc::LookupTable> table = fmpc::build_table(source, compiled, options, diagnostics, &stats);
  REQUIRE(table);
  CHECK(table->max_error <= options.max_error);
  REQUIRE(table->axes.size() == 1);
  CHECK(table->axes[0].input_name == "rate");
  // Grid values are the specialised interpreter's crisp outputs; between them, an independent seeded sample.
  std::vector<const double*> pointers;
  std::vector<int> counts;
  const fmpc::TableView<double> view = fmpc::view_of(*table, pointers, counts);
  const std::vector<double>& breakpoints = table->axes[0].breakpoints;
  for (std::size_t k = 0; k < breakpoints.size(); ++k) {
    double out = 0.0;
    fmpc::interpolate_table(view, &breakpoints[k], &out);
    CHECK(same_bits(out, fmpc::evaluate(compiled.system, {breakpoints[k]}).outputs[0]));
  }
  double worst = 0.0;
  for (const auto& point : fmpc::testing::random_inputs(compiled.system, 77, 2000)) {
    double out = 0.0;
    fmpc::interpolate_table(view, point.data(), &out);
    worst = std::max(worst, std::fabs(out - fmpc::evaluate(source, {5.0, point[0]}).outputs[0]));
  }
  CHECK(worst <= options.max_error);
  WARN("valve_it2 table over rate (level = 5): " << breakpoints.size() << " breakpoints, held-out max error "
                                                 << table->max_error << ", 2000 fresh points " << worst);
}

TEST_CASE("fmpc trade measures type-2 systems: interpreter, compiled C++ and tables", "[type2-compile][trade]") {
  const fs::path valve = fs::path(FMPC_SOURCE_DIR) / "tests" / "golden" / "compile_type2_cpp" / "valve_it2.fis";
  fmpc::testing::ScratchFolder folder("type2_trade");
  const std::string command = std::string(FMPC_BINARY) + " trade " + valve.string() +
                              " --fix level=5 --points 60 --min-seconds 0.01 --resolutions 3,9 --csv " +
                              (folder.path() / "t.csv").string() + " > " + (folder.path() / "out.md").string() +
                              " 2> " + (folder.path() / "err.txt").string();
  const int status = std::system(command.c_str());
  INFO(fmpc::testing::read_text_file(folder.path() / "err.txt"));
  REQUIRE(status == 0);
  const std::string markdown = fmpc::testing::read_text_file(folder.path() / "out.md");
  INFO(markdown);
  CHECK(markdown.find("| interpreter | interval type-2, eiasc (reference) | 0 | 0 |") != std::string::npos);
  CHECK(markdown.find("samples exact") == std::string::npos);
  CHECK(markdown.find("| table | 9 uniform, double |") != std::string::npos);
  // The compiled double row agrees with the interpreter to rounding.
  const std::string csv = fmpc::testing::read_text_file(folder.path() / "t.csv");
  const std::size_t row = csv.find("compiled C++,\"double");
  REQUIRE(row != std::string::npos);
  const std::size_t error_at = csv.find("\",", row) + 2;
  CHECK(std::strtod(csv.c_str() + error_at, nullptr) < 1e-12);
}
