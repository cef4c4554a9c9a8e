// The C++/CUDA emitter on interval type-2 systems (compiler/backend/cpp/emit_type2.h). The generated headers are
// compiled with the system compiler at test time (several systems per translation unit) and run against the
// reference interpreter on every type-2 rule file and on seeded random type-2 systems: the crisp output and both
// ends of the type-reduced interval agree to 1e-12 of the output range in double, 1e-5 in float.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "compiler/backend/cpp/embedded_kernels.h"
#include "compiler/backend/cpp/embedded_math.h"
#include "compiler/backend/cpp/emit_cpp.h"
#include "compiler/backend/cpp/emit_type2.h"
#include "compiler/eval/interpreter.h"
#include "compiler/frontend/rule_file_loader.h"
#include "compiler/passes/pipeline.h"
#include "kernels/fuzzy_math.h"
#include "tests/support/generated_program.h"
#include "tests/support/random_system.h"
#include "tests/support/type_reduction_reference.h"

namespace {

namespace fs = std::filesystem;
using fmpc::EmitOptions;
using fmpc::FuzzySystem;
using fmpc::testing::read_text_file;
using fmpc::testing::write_text_file;

constexpr double kInf = std::numeric_limits<double>::infinity();

struct Case {
  std::string label;
  FuzzySystem system;
  std::vector<std::vector<double>> points;
  EmitOptions::Target target = EmitOptions::Target::Cpp;
};

// One point's results: the crisp output and the interval [yl, yr] per output, in double and in float.
struct Result {
  unsigned flags_double = 0, flags_float = 0;
  std::vector<double> y_double, low_double, high_double, y_float, low_float, high_float;
};

EmitOptions case_options(const Case& c, std::size_t index) {
  EmitOptions options;
  options.target = c.target;
  options.source_path = c.label;
  options.source_hash = 0x0123456789abcdefULL;
  options.namespace_name = "case" + std::to_string(index);
  options.header_path = "case" + std::to_string(index) + ".h";
  return options;
}

// The driver reads "case x1 .. xd" lines (hex floats) and prints "flags_d flags_f" then y yl yr per output in
// double, then in float. It checks itself that evaluate<double> and evaluate_batch<double> give
// evaluate_interval<double>'s crisp outputs and flags (exit status 5 otherwise).
std::string driver_source(const std::vector<Case>& cases) {
  std::string text = "#include <cstdio>\n#include <cstdlib>\n#include <vector>\n";
  for (std::size_t c = 0; c < cases.size(); ++c) text += "#include \"case" + std::to_string(c) + ".h\"\n";
  text += R"(
struct Entry {
  std::size_t inputs, outputs;
  unsigned (*interval_double)(const double*, double*, double*, double*);
  unsigned (*interval_float)(const float*, float*, float*, float*);
  unsigned (*crisp_double)(const double*, double*);
  void (*batch_double)(const double*, double*, std::size_t, unsigned*);
};
static const Entry kEntries[] = {
)";
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const std::string ns = "case" + std::to_string(c);
    text += "  {" + ns + "::kInputCount, " + ns + "::kOutputCount, &" + ns + "::evaluate_interval<double>, &" + ns +
            "::evaluate_interval<float>, &" + ns + "::evaluate<double>, &" + ns + "::evaluate_batch<double>},\n";
  }
  text += R"(};
static bool same(double a, double b) { return a == b || (a != a && b != b); }
int main(int argc, char** argv) {
  if (argc != 3) return 2;
  std::FILE* in = std::fopen(argv[1], "r");
  std::FILE* out = std::fopen(argv[2], "w");
  if (!in || !out) return 3;
  unsigned long index = 0;
  while (std::fscanf(in, "%lu", &index) == 1) {
    const Entry& e = kEntries[index];
    std::vector<double> xd(e.inputs + 1), yd(e.outputs), ld(e.outputs), hd(e.outputs), yc(e.outputs), yb(e.outputs);
    std::vector<float> xf(e.inputs + 1), yf(e.outputs), lf(e.outputs), hf(e.outputs);
    for (std::size_t i = 0; i < e.inputs; ++i) {
      char word[64];
      if (std::fscanf(in, "%63s", word) != 1) return 4;
      xd[i] = std::strtod(word, nullptr);
      xf[i] = static_cast<float>(xd[i]);
    }
    const unsigned fd = e.interval_double(xd.data(), yd.data(), ld.data(), hd.data());
    const unsigned ff = e.interval_float(xf.data(), yf.data(), lf.data(), hf.data());
    const unsigned fc = e.crisp_double(xd.data(), yc.data());
    unsigned fb = 0;
    e.batch_double(xd.data(), yb.data(), 1, &fb);
    if (fc != fd || fb != fd) return 5;
    for (std::size_t o = 0; o < e.outputs; ++o)
      if (!same(yc[o], yd[o]) || !same(yb[o], yd[o])) return 5;
    std::fprintf(out, "%u %u", fd, ff);
    for (std::size_t o = 0; o < e.outputs; ++o) std::fprintf(out, " %a %a %a", yd[o], ld[o], hd[o]);
    for (std::size_t o = 0; o < e.outputs; ++o)
      std::fprintf(out, " %a %a %a", static_cast<double>(yf[o]), static_cast<double>(lf[o]),
                   static_cast<double>(hf[o]));
    std::fprintf(out, "\n");
  }
  return 0;
}
)";
  return text;
}

std::string hex_float(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%a", value);
  return text;
}

// Emits every case into one translation unit, compiles it with fmpc's warnings as errors, and runs it.
std::vector<std::vector<Result>> compile_and_run(const std::vector<Case>& cases, const std::string& tag) {
  fmpc::testing::ScratchFolder folder("type2_" + tag);
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const EmitOptions options = case_options(cases[c], c);
    fmpc::DiagnosticList diagnostics;
    const auto header = fmpc::emit_evaluator(cases[c].system, options, diagnostics);
    INFO(cases[c].label);
    REQUIRE(header);
    REQUIRE(diagnostics.empty());
    write_text_file(folder.path() / options.header_path, *header);
  }
  write_text_file(folder.path() / "driver.cpp", driver_source(cases));
  std::string inputs;
  for (std::size_t c = 0; c < cases.size(); ++c)
    for (const auto& point : cases[c].points) {
      inputs += std::to_string(c);
      for (double x : point) inputs += " " + hex_float(x);
      inputs += "\n";
    }
  write_text_file(folder.path() / "inputs.txt", inputs);

  std::string log;
  const bool compiled =
      fmpc::testing::compile_generated_program(folder.path() / "driver.cpp", folder.path() / "driver", log);
  INFO("compiler output:\n" << log.substr(0, 4000));
  REQUIRE(compiled);
  const std::string run = (folder.path() / "driver").string() + " " + (folder.path() / "inputs.txt").string() +
                          " " + (folder.path() / "outputs.txt").string();
  REQUIRE(std::system(run.c_str()) == 0);

  std::vector<std::vector<Result>> results(cases.size());
  std::istringstream lines(read_text_file(folder.path() / "outputs.txt"));
  const auto next = [&lines] {
    std::string word;
    lines >> word;
    return std::strtod(word.c_str(), nullptr);
  };
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const std::size_t m = cases[c].system.outputs.size();
    for (std::size_t p = 0; p < cases[c].points.size(); ++p) {
      Result r;
      lines >> r.flags_double >> r.flags_float;
      for (std::size_t o = 0; o < m; ++o) {
        r.y_double.push_back(next());
        r.low_double.push_back(next());
        r.high_double.push_back(next());
      }
      for (std::size_t o = 0; o < m; ++o) {
        r.y_float.push_back(next());
        r.low_float.push_back(next());
        r.high_float.push_back(next());
      }
      results[c].push_back(r);
    }
  }
  REQUIRE(lines.good());
  return results;
}

bool same_or_both_nan(double a, double b, double tolerance) {
  if (std::isnan(a) || std::isnan(b)) return std::isnan(a) && std::isnan(b);
  if (std::isinf(a) || std::isinf(b)) return a == b;
  return std::fabs(a - b) <= tolerance;
}

unsigned expected_flags(const fmpc::Evaluation& evaluation) {
  unsigned flags = 0;
  if (!evaluation.flags.inputs_nan.empty()) return 1u;
  if (!evaluation.flags.inputs_out_of_range.empty()) flags |= 2u;
  if (!evaluation.flags.outputs_no_rule_fired.empty()) flags |= 4u;
  if (evaluation.flags.no_fire_error) flags |= 8u;
  return flags;
}

// Where float cannot carry a type-2 computation, so that comparing it with double would test float, not the
// generated code. Lower ends are small differences more often than type-1 grades, and KM weighs them against the
// upper ends:
// - cancellation: a difference keeping less than 1% of its operands turns float's rounding of them (6e-8
//   relative) into more than 6e-6 relative error: `not` of a grade above 0.99 (random seed 304: not of a bell at
//   0.99991 moved yl by 5e-5 of the range), and a MATLAB lower scale/lag footprint just above its lag
//   (scale (upper - lag) / (1 - lag));
// - a Mamdani interval end whose centroid denominator (sum_{i<k} U_i + sum_{i>=k} L_i for yl, the mirror for yr,
//   at the interpreter's switch point k) is below 1e-6 of the total upper weight: the end then rests on weights
//   that float cannot weigh against the others, and KM in float settles on another switch point (the golden
//   it2 system at HCV = 19.8: D / sum U = 3e-10, yl = 1.5e-13 in double, 13 in float).
bool float_cannot_carry(const FuzzySystem& system, const std::vector<double>& x, const fmpc::Explanation& explained) {
  const auto cancels = [](double kept, double operand) { return kept > 0.0 && kept < 0.01 * operand; };
  for (std::size_t i = 0; i < system.inputs.size(); ++i)
    for (const fmpc::Term& term : system.inputs[i].terms) {
      if (!term.footprint || term.footprint->kind != fmpc::FootprintKind::ScaleLag) continue;
      const double upper = fmpc::membership(term.mf.kind, term.mf.params.data(), x[i]);
      if (cancels(upper - term.footprint->second, upper)) return true;
    }
  for (const fmpc::Rule& rule : system.rules)
    for (const fmpc::Clause& clause : rule.antecedent) {
      if (!clause.negated) continue;
      const auto v = static_cast<std::size_t>(clause.variable);
      const fmpc::Term& term = system.inputs[v].terms[static_cast<std::size_t>(clause.term)];
      const auto mu = fmpc::interval_hedge(fmpc::term_membership(term, x[v]), fmpc::hedge_exponent(clause.hedge));
      if (cancels(1.0 - mu.lower, 1.0) || cancels(1.0 - mu.upper, 1.0)) return true;
    }
  if (system.type == fmpc::SystemType::Sugeno)  // negated consequents: 1 - w^(1/hedge)
    for (std::size_t r = 0; r < system.rules.size(); ++r)
      for (const fmpc::Clause& clause : system.rules[r].consequent)
        for (const double w : {explained.evaluation.firing_lower[r], explained.evaluation.firing_strengths[r]})
          if (clause.negated && cancels(1.0 - std::pow(w, 1.0 / fmpc::hedge_exponent(clause.hedge)), 1.0))
            return true;
  if (system.type != fmpc::SystemType::Mamdani || system.type_reduction == fmpc::TypeReduction::NieTan) return false;
  for (std::size_t o = 0; o < system.outputs.size(); ++o) {
    const fmpc::TypeReducedOutput& interval = explained.evaluation.intervals[o];
    const fmpc::OutputExplanation& sets = explained.outputs[o];
    if (interval.left_switch < 0 || sets.membership.empty()) continue;  // no reduction ran
    double total = 0.0, left = 0.0, right = 0.0;
    for (std::size_t k = 0; k < sets.membership.size(); ++k) {
      const auto index = static_cast<int>(k);
      total += sets.membership[k];
      left += index < interval.left_switch ? sets.membership[k] : sets.membership_lower[k];
      right += index < interval.right_switch ? sets.membership_lower[k] : sets.membership[k];
    }
    if (left < 1e-6 * total || right < 1e-6 * total) return true;
  }
  return false;
}

struct Tally {
  std::size_t points = 0, float_checked = 0, float_skipped = 0;
  std::size_t wide_intervals = 0;  // outputs with yl < yr: the type reduction ran and found a proper interval
  std::size_t no_fire = 0;
  double worst_double = 0.0;  // largest |double - interpreter| / range over the outputs and interval ends
};

// Double: the crisp output and both interval ends within 1e-12 of the output range of the interpreter, and the
// same flags. Float: within 1e-5 of the range (or of the value, for Sugeno outputs outside their declared range)
// where float can carry the computation: every firing end that is above 0 must be above 1e-30 (a firing of 1e-40
// is a normal double but 0 in float, which turns "fired weakly" into "no rule fired").
void compare_with_interpreter(const Case& c, const std::vector<Result>& results, Tally& tally) {
  fmpc::Interpreter interpreter(c.system);
  for (std::size_t p = 0; p < c.points.size(); ++p) {
    const fmpc::Evaluation expected = interpreter.evaluate(c.points[p]);
    REQUIRE(expected.intervals.size() == c.system.outputs.size());
    const Result& got = results[p];
    ++tally.points;
    INFO(c.label << " point " << p);
    CHECK(got.flags_double == expected_flags(expected));
    if (!expected.flags.outputs_no_rule_fired.empty()) ++tally.no_fire;
    double weakest_firing = kInf;
    for (const auto* ends : {&expected.firing_strengths, &expected.firing_lower})
      for (double w : *ends)
        if (w > 0.0) weakest_firing = std::min(weakest_firing, w);
    // Float is compared with the interpreter at the inputs float holds: a Gaussian's tail turns the rounding of x
    // (6e-8 relative) into a much larger relative change of a grade, which is the input's doing, not float's.
    std::vector<double> rounded = c.points[p];
    for (double& x : rounded) x = static_cast<double>(static_cast<float>(x));
    const fmpc::Explanation explained_float = interpreter.explain(rounded);
    const fmpc::Evaluation& expected_float = explained_float.evaluation;
    const bool float_comparable = weakest_firing > 1e-30 && got.flags_float == got.flags_double &&
                                  !float_cannot_carry(c.system, rounded, explained_float);
    if (float_comparable) ++tally.float_checked;
    else ++tally.float_skipped;
    for (std::size_t o = 0; o < c.system.outputs.size(); ++o) {
      const double range = c.system.outputs[o].max - c.system.outputs[o].min;
      const fmpc::TypeReducedOutput& interval = expected.intervals[o];
      if (interval.lower < interval.upper) ++tally.wide_intervals;
      INFO("output " << o << " interpreter " << expected.outputs[o] << " [" << interval.lower << ", "
                     << interval.upper << "] double " << got.y_double[o] << " [" << got.low_double[o] << ", "
                     << got.high_double[o] << "] float " << got.y_float[o] << " [" << got.low_float[o] << ", "
                     << got.high_float[o] << "]");
      for (const auto& [value, reference] : {std::make_pair(got.y_double[o], expected.outputs[o]),
                                             std::make_pair(got.low_double[o], interval.lower),
                                             std::make_pair(got.high_double[o], interval.upper)})
        if (std::isfinite(value) && std::isfinite(reference))
          tally.worst_double = std::max(tally.worst_double, std::fabs(value - reference) / range);
      CHECK(same_or_both_nan(got.y_double[o], expected.outputs[o], 1e-12 * range));
      CHECK(same_or_both_nan(got.low_double[o], interval.lower, 1e-12 * range));
      CHECK(same_or_both_nan(got.high_double[o], interval.upper, 1e-12 * range));
      if (!float_comparable) continue;
      const auto tolerance = [range](double value) { return 1e-5 * std::max(range, std::fabs(value)); };
      const fmpc::TypeReducedOutput& interval_float = expected_float.intervals[o];
      CHECK(same_or_both_nan(got.y_float[o], expected_float.outputs[o], tolerance(expected_float.outputs[o])));
      CHECK(same_or_both_nan(got.low_float[o], interval_float.lower, tolerance(interval_float.lower)));
      CHECK(same_or_both_nan(got.high_float[o], interval_float.upper, tolerance(interval_float.upper)));
    }
  }
}

FuzzySystem load_single_system(const fs::path& path) {
  fmpc::DiagnosticList diagnostics;
  fmpc::RuleFile file = fmpc::load_rule_file(path.string(), read_text_file(path), diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(file.systems.size() == 1);
  return file.systems[0];
}

// Every interval type-2 system in the project's rule files and in ../shared/data/matlab-fis (when present).
std::vector<std::pair<std::string, FuzzySystem>> type2_rule_file_systems() {
  std::vector<fs::path> files;
  const fs::path source(FMPC_SOURCE_DIR);
  for (const fs::path& root : {source / "rulesets", source / "tests" / "golden"})
    for (const auto& entry : fs::recursive_directory_iterator(root))
      if (entry.path().extension() == ".fis") files.push_back(entry.path());
  const fs::path matlab = fs::path(FMPC_SHARED_DATA_DIR) / "matlab-fis";
  if (fs::is_directory(matlab)) {
    for (const auto& entry : fs::directory_iterator(matlab))
      if (entry.path().extension() == ".fis") files.push_back(entry.path());
  } else {
    WARN("skipping the MATLAB example files: " << matlab << " is absent");
  }
  std::sort(files.begin(), files.end());
  std::vector<std::pair<std::string, FuzzySystem>> systems;
  std::size_t matlab_type2 = 0;
  for (const fs::path& path : files) {
    fmpc::DiagnosticList diagnostics;
    fmpc::RuleFile file = fmpc::load_rule_file(path.string(), read_text_file(path), diagnostics);
    if (diagnostics.has_errors()) continue;  // golden cases of error messages
    for (FuzzySystem& system : file.systems) {
      if (!system.interval_type2) continue;
      if (path.parent_path() == matlab) ++matlab_type2;
      systems.emplace_back(fs::relative(path, source.parent_path()).string() + ":" + system.name,
                           std::move(system));
    }
  }
  if (fs::is_directory(matlab) && matlab_type2 == 0)
    WARN("no MATLAB type-2 .fis file in " << matlab << ": only the project's type-2 files are compiled");
  return systems;
}

}  // namespace

TEST_CASE("type-2 headers agree with the interpreter on every type-2 rule file", "[emit][type2]") {
  std::vector<Case> cases;
  std::uint64_t seed = 1;
  for (auto& [label, system] : type2_rule_file_systems()) {
    Case c;
    c.label = label;
    c.points = fmpc::testing::evaluator_test_points(system, seed++, 60);
    c.system = std::move(system);
    if (cases.size() % 2 == 1) c.target = EmitOptions::Target::Cuda;  // the CUDA header's host side as well
    cases.push_back(std::move(c));
  }
  // rulesets/liver_fibrosis/it2.fis and the golden cases' small_it2.
  REQUIRE(cases.size() >= 2);
  const auto results = compile_and_run(cases, "files");
  Tally tally;
  for (std::size_t c = 0; c < cases.size(); ++c) compare_with_interpreter(cases[c], results[c], tally);
  CHECK(tally.wide_intervals > tally.points / 2);
  CHECK(tally.float_checked > tally.points / 2);
  WARN("type-2 rule files: " << cases.size() << " systems, " << tally.points << " points, float compared on "
                             << tally.float_checked << "; largest double difference " << tally.worst_double
                             << " of the range");
}

TEST_CASE("type-2 headers agree with the interpreter on seeded random type-2 systems", "[emit][type2][heavy]") {
  fmpc::testing::RandomSystemOptions options;
  options.interval_type2 = true;
  options.exact_samples = false;
  options.consequent_negation = true;
  options.consequent_hedges = true;
  std::vector<Case> cases;
  std::size_t sugeno = 0;
  std::vector<int> reductions(4, 0);
  for (std::uint64_t seed = 300; seed < 348; ++seed) {
    Case c;
    c.system = fmpc::testing::random_system(seed, options);
    c.label = "random type-2 seed " + std::to_string(seed);
    c.points = fmpc::testing::evaluator_test_points(c.system, seed * 7, 30);
    if (seed % 3 == 0) c.target = EmitOptions::Target::Cuda;
    sugeno += c.system.type == fmpc::SystemType::Sugeno ? 1 : 0;
    reductions[static_cast<std::size_t>(c.system.type_reduction)] += 1;
    cases.push_back(std::move(c));
  }
  // The draw covers both system types and every type reduction.
  CHECK(sugeno >= 10);
  CHECK(cases.size() - sugeno >= 10);
  for (int count : reductions) CHECK(count > 0);
  const auto results = compile_and_run(cases, "random");
  Tally tally;
  for (std::size_t c = 0; c < cases.size(); ++c) compare_with_interpreter(cases[c], results[c], tally);
  CHECK(tally.wide_intervals > tally.points / 4);
  CHECK(tally.no_fire > 0);
  CHECK(tally.float_checked > tally.points / 2);
  WARN("random type-2 systems: " << cases.size() << " (" << sugeno << " sugeno), " << tally.points
                                 << " points, float compared on " << tally.float_checked
                                 << "; largest double difference " << tally.worst_double << " of the range");
}

TEST_CASE("type-2 headers equal the exhaustive search where lower grades are 1e-25", "[emit][type2]") {
  // The issue's two systems at their points, and 60 seeded one-input systems whose lower grades fall to 1e-25 and
  // below (tests/support/type_reduction_reference.h), at 15 points each: both ends of the generated double
  // evaluator's interval within 1e-12 of the points' range of an exhaustive search in long double over the
  // aggregated sets the interpreter explains.
  const fs::path golden = fs::path(FMPC_SOURCE_DIR) / "tests" / "golden";
  std::vector<Case> cases;
  for (const auto& [folder, x] : {std::make_pair("it2_km_end_of_range", 8.0), std::make_pair("it2_ekm_end_of_range", 0.0)}) {
    Case c;
    c.label = folder;
    c.system = load_single_system(golden / folder / "end_of_range.fis");
    c.points = {{x}};
    cases.push_back(std::move(c));
  }
  const char* methods[] = {"karnik_mendel", "enhanced_karnik_mendel", "eiasc"};
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    Case c;
    c.label = "tail system " + std::to_string(seed);
    fmpc::DiagnosticList diagnostics;
    fmpc::RuleFile file =
        fmpc::load_rule_file(c.label, fmpc::testing::tail_system(seed, methods[seed % 3]), diagnostics);
    REQUIRE_FALSE(diagnostics.has_errors());
    c.system = file.systems[0];
    for (int p = 0; p < 15; ++p) c.points.push_back({p < 10 ? static_cast<double>(p) : 10.0 * (p - 10) / 5.0 + 0.37});
    if (seed % 2 == 0) c.target = EmitOptions::Target::Cuda;
    cases.push_back(std::move(c));
  }
  const auto results = compile_and_run(cases, "exhaustive");
  std::size_t compared = 0;
  for (std::size_t c = 0; c < cases.size(); ++c) {
    for (std::size_t p = 0; p < cases[c].points.size(); ++p) {
      const fmpc::Explanation explained = fmpc::explain(cases[c].system, cases[c].points[p]);
      if (!explained.evaluation.flags.outputs_no_rule_fired.empty()) continue;
      const fmpc::OutputExplanation& set = explained.outputs[0];
      const auto exact = fmpc::testing::exact_type_reduction(set.x, set.membership_lower, set.membership);
      const double tolerance = fmpc::testing::type_reduction_tolerance(set.x);
      const Result& got = results[c][p];
      INFO(cases[c].label << " at x = " << cases[c].points[p][0] << ": [" << got.low_double[0] << ", "
                          << got.high_double[0] << "], exhaustive [" << static_cast<double>(exact.left) << ", "
                          << static_cast<double>(exact.right) << "]");
      CHECK(got.flags_double == expected_flags(explained.evaluation));
      CHECK(std::fabs(static_cast<double>(got.low_double[0] - exact.left)) <= tolerance);
      CHECK(std::fabs(static_cast<double>(got.high_double[0] - exact.right)) <= tolerance);
      ++compared;
    }
  }
  CHECK(compared > 600);
  CHECK(results[0][0].high_double[0] == 10.0);  // 9.65 on main at 6bad843
  CHECK(results[1][0].high_double[0] == 20.0);  // 19.9
}

TEST_CASE("fmpc compile's pipeline hands type-2 systems to the emitter", "[emit][type2]") {
  const FuzzySystem it2 =
      load_single_system(fs::path(FMPC_SOURCE_DIR) / "rulesets" / "liver_fibrosis" / "it2.fis");
  fmpc::PipelineOptions options;
  SECTION("refused unless the caller's back end takes type-2") {
    fmpc::DiagnosticList diagnostics;
    CHECK_FALSE(fmpc::run_pipeline(it2, {}, options, diagnostics));
    REQUIRE(diagnostics.error_count() == 1);
    CHECK(diagnostics.items()[0].message.find("interval type-2") != std::string::npos);
    CHECK(diagnostics.items()[0].range.line == it2.range.line);
  }
  options.interval_type2 = true;
  SECTION("every pass runs (tests/unit/type2_compile_test.cpp checks them); unbound, the outputs are the file's") {
    fmpc::DiagnosticList diagnostics;
    const auto compiled = fmpc::run_pipeline(it2, {}, options, diagnostics);
    REQUIRE(compiled);
    CHECK(diagnostics.empty());
    CHECK(compiled->reports.size() == fmpc::pipeline_pass_names().size());
    for (const fmpc::PassReport& report : compiled->reports) CHECK(report.summary.find("not run") == std::string::npos);
    CHECK(compiled->error_bound() == 0.0);
    CHECK(compiled->system.inputs.size() == it2.inputs.size());
    const fmpc::Evaluation before = fmpc::evaluate(it2, {7.5, 6.0, 12.0, 9.0, 8.0});
    const fmpc::Evaluation after = fmpc::evaluate(compiled->system, {7.5, 6.0, 12.0, 9.0, 8.0});
    CHECK(before.outputs == after.outputs);
  }
  SECTION("a fixed input is folded in") {
    fmpc::Bindings bindings;
    bindings.fixed.push_back({"HCV", 10.0, {}});
    fmpc::DiagnosticList diagnostics;
    const auto compiled = fmpc::run_pipeline(it2, bindings, options, diagnostics);
    REQUIRE(compiled);
    CHECK(compiled->system.inputs.size() == it2.inputs.size() - 1);
  }
}

TEST_CASE("type-2 headers: banner, #line per rule, the type-2 math verbatim, beside a type-1 header", "[emit][type2]") {
  const fs::path source(FMPC_SOURCE_DIR);
  const FuzzySystem it2 = load_single_system(source / "rulesets" / "liver_fibrosis" / "it2.fis");
  const FuzzySystem type1 = load_single_system(source / "rulesets" / "liver_fibrosis" / "mamdani.fis");
  for (const std::string& path : fmpc::type2_embedded_math_files()) {
    INFO(path);
    CHECK(std::string(fmpc::embedded_kernel_source(path)) == read_text_file(source / path));
  }

  EmitOptions options;
  options.source_path = "rulesets/liver_fibrosis/it2.fis";
  options.source_hash = 0xfeedfacecafebeefULL;
  options.namespace_name = "liver_it2";
  options.header_path = "liver_it2.h";
  fmpc::DiagnosticList diagnostics;
  const auto header = fmpc::emit_evaluator(it2, options, diagnostics);
  REQUIRE(header);
  CHECK(diagnostics.empty());
  CHECK(header->find("// source: rulesets/liver_fibrosis/it2.fis\n") != std::string::npos);
  CHECK(header->find("// source hash (FNV-1a 64): feedfacecafebeef\n") != std::string::npos);
  CHECK(header->find("FMPC_HD GradeInterval<T> footprint_membership(") != std::string::npos);
  CHECK(header->find("FMPC_HD TypeReducedInterval<T> karnik_mendel(") != std::string::npos);
  CHECK(header->find("fmpc_math::reduce_type(fmpc_math::TypeReduction::KarnikMendel") != std::string::npos);
  CHECK(header->find("namespace fmpc {") == std::string::npos);
  CHECK(header->find("#include \"kernels/") == std::string::npos);
  CHECK(header->find("__global__") == std::string::npos);

  // Each rule's #line names its line in the rule file; each return directive names its own next line.
  fmpc::testing::check_line_directives(*header, "liver_it2.h", "rulesets/liver_fibrosis/it2.fis", it2);
  options.line_directives = false;
  const auto plain = fmpc::emit_evaluator(it2, options, diagnostics);
  REQUIRE(plain);
  CHECK(plain->find("#line") == std::string::npos);

  // A type-1 and a type-2 header in one translation unit: their math copies live in different namespaces.
  options.target = EmitOptions::Target::Cuda;
  const auto cuda = fmpc::emit_evaluator(it2, options, diagnostics);
  REQUIRE(cuda);
  CHECK(cuda->find("__global__ void evaluate_kernel") != std::string::npos);
  EmitOptions type1_options;
  type1_options.namespace_name = "liver";
  const auto type1_header = fmpc::emit_evaluator(type1, type1_options, diagnostics);
  REQUIRE(type1_header);
  fmpc::testing::ScratchFolder folder("type2_beside_type1");
  write_text_file(folder.path() / "liver_it2.h", *cuda);
  write_text_file(folder.path() / "liver.h", *type1_header);
  write_text_file(folder.path() / "driver.cpp", R"(#include <cstdio>
#include "liver.h"
#include "liver_it2.h"
int main() {
  const double x[5] = {7.5, 6.0, 12.0, 9.0, 8.0};
  double type1 = 0.0, crisp = 0.0, low = 0.0, high = 0.0;
  const unsigned flags = liver::evaluate(x, &type1) | liver_it2::evaluate_interval(x, &crisp, &low, &high);
  std::printf("%u %a %a %a %a\n", flags, type1, crisp, low, high);
  return 0;
}
)");
  std::string log;
  const bool compiled =
      fmpc::testing::compile_generated_program(folder.path() / "driver.cpp", folder.path() / "driver", log);
  INFO(log.substr(0, 4000));
  REQUIRE(compiled);
  const std::string run = (folder.path() / "driver").string() + " > " + (folder.path() / "out.txt").string();
  REQUIRE(std::system(run.c_str()) == 0);
  std::istringstream printed(read_text_file(folder.path() / "out.txt"));
  unsigned flags = 99;
  std::string words[4];
  printed >> flags >> words[0] >> words[1] >> words[2] >> words[3];
  CHECK(flags == 0u);
  const std::vector<double> x{7.5, 6.0, 12.0, 9.0, 8.0};
  const fmpc::Evaluation expected1 = fmpc::evaluate(type1, x);
  const fmpc::Evaluation expected2 = fmpc::evaluate(it2, x);
  CHECK(std::strtod(words[0].c_str(), nullptr) == Approx(expected1.outputs[0]).margin(75e-12));
  CHECK(std::strtod(words[1].c_str(), nullptr) == Approx(expected2.outputs[0]).margin(75e-12));
  CHECK(std::strtod(words[2].c_str(), nullptr) == Approx(expected2.intervals[0].lower).margin(75e-12));
  CHECK(std::strtod(words[3].c_str(), nullptr) == Approx(expected2.intervals[0].upper).margin(75e-12));
  CHECK(expected2.intervals[0].lower < expected2.intervals[0].upper);
}

TEST_CASE("type-2 CUDA headers compile with nvcc for sm_90, kernels and launchers in float and double",
          "[emit][type2][nvcc]") {
  // The CUDA toolkit's usual place, where cmake/FmpcCuda.cmake looks too; the device run is the GPU tests' job.
  const fs::path nvcc = "/usr/local/cuda/bin/nvcc";
  if (!fs::exists(nvcc)) {
    WARN("skipping the nvcc compile test: " << nvcc << " is absent");
    return;
  }
  const fs::path source(FMPC_SOURCE_DIR);
  const std::vector<std::pair<std::string, fs::path>> systems = {
      {"stiffness_it2", source / "tests" / "golden" / "it2_eval" / "it2.fis"},  // Mamdani, every footprint form
      {"valve_it2", source / "tests" / "golden" / "compile_type2_cpp" / "valve_it2.fis"},  // Sugeno, EIASC
  };
  fmpc::testing::ScratchFolder folder("type2_nvcc");
  std::string driver = "#include <cstddef>\n";
  for (const auto& [name, path] : systems) {
    EmitOptions options;
    options.target = EmitOptions::Target::Cuda;
    options.source_path = path.string();
    options.namespace_name = name;
    options.header_path = name + ".cuh";
    fmpc::DiagnosticList diagnostics;
    const auto header = fmpc::emit_evaluator(load_single_system(path), options, diagnostics);
    REQUIRE(header);
    write_text_file(folder.path() / options.header_path, *header);
    driver += "#include \"" + options.header_path + "\"\n";
  }
  driver += "cudaError_t launch_all(const double* xd, double* yd, const float* xf, float* yf, std::size_t n) {\n"
            "  cudaError_t status = cudaSuccess;\n";
  for (const auto& entry : systems) {
    driver += "  if (status == cudaSuccess) status = " + entry.first + "::evaluate_batch_cuda(xd, yd, n);\n";
    driver += "  if (status == cudaSuccess) status = " + entry.first + "::evaluate_batch_cuda(xf, yf, n);\n";
  }
  driver += "  return status;\n}\n";
  write_text_file(folder.path() / "launch.cu", driver);
  const std::string command = nvcc.string() + " -std=c++17 -arch=sm_90 -O3 --Werror all-warnings -c " +
                              (folder.path() / "launch.cu").string() + " -o " +
                              (folder.path() / "launch.o").string() + " > " +
                              (folder.path() / "nvcc.log").string() + " 2>&1";
  const int status = std::system(command.c_str());
  INFO("nvcc output:\n" << read_text_file(folder.path() / "nvcc.log").substr(0, 4000));
  CHECK(status == 0);
  CHECK(fs::file_size(folder.path() / "launch.o") > 0);
}
