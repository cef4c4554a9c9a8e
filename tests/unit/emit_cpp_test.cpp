// The C++/CUDA emitter (compiler/backend/cpp/emit_cpp.h). The generated headers are compiled with the system
// compiler at test time (several systems per translation unit, to keep the suite fast) and run against the
// reference interpreter on every golden rule file and on seeded random systems: double agrees to 1e-12 of the
// output range, float to 1e-5 (docs/codegen.md gives the exceptions and why).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "compiler/backend/cpp/embedded_kernels.h"
#include "compiler/backend/cpp/embedded_math.h"
#include "compiler/backend/cpp/emit_cpp.h"
#include "compiler/eval/interpreter.h"
#include "compiler/frontend/rule_file_loader.h"
#include "compiler/ir/content_hash.h"
#include "compiler/passes/pipeline.h"
#include "tests/support/generated_program.h"
#include "tests/support/random_system.h"

namespace {

namespace fs = std::filesystem;
using fmpc::Defuzzifier;
using fmpc::EmitOptions;
using fmpc::FuzzySystem;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void write_text(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

// A fresh folder under the system's temporary directory, removed when the test ends.
struct ScratchFolder {
  fs::path path;
  explicit ScratchFolder(const std::string& tag) {
    std::random_device device;
    path = fs::temp_directory_path() / ("fmpc_emit_" + tag + "_" + std::to_string(device()));
    fs::create_directories(path);
  }
  ~ScratchFolder() {
    std::error_code ignored;
    fs::remove_all(path, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
};

std::string hex_float(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%a", value);
  return text;
}

// One system under test: its emitted header, the points to evaluate, and how to judge float.
struct Case {
  std::string label;
  FuzzySystem system;
  std::vector<std::vector<double>> points;
  EmitOptions::Target target = EmitOptions::Target::Cpp;
};

struct Result {
  unsigned flags_double = 0, flags_float = 0, flags_batch_double = 0, flags_batch_float = 0;
  std::vector<double> outputs_double, outputs_float, outputs_batch_double, outputs_batch_float;
};

// The driver reads "case x1 .. xd" lines (hex floats) and prints, per line, "flags_d flags_f flags_bd flags_bf
// y_d... y_f... y_bd... y_bf...": evaluate<double> and evaluate<float> point by point, and evaluate_batch<double>
// and evaluate_batch<float> over all of a case's points in one call (several blocks of lanes, the last one
// partial, edge points among ordinary ones).
std::string driver_source(const std::vector<Case>& cases) {
  std::string text = "#include <cstdio>\n#include <cstdlib>\n#include <vector>\n";
  for (std::size_t c = 0; c < cases.size(); ++c) text += "#include \"case" + std::to_string(c) + ".h\"\n";
  text += R"(
struct Entry {
  std::size_t inputs, outputs;
  unsigned (*evaluate_double)(const double*, double*);
  unsigned (*evaluate_float)(const float*, float*);
  void (*batch_double)(const double*, double*, std::size_t, unsigned*);
  void (*batch_float)(const float*, float*, std::size_t, unsigned*);
};
static const Entry kEntries[] = {
)";
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const std::string ns = "case" + std::to_string(c);
    text += "  {" + ns + "::kInputCount, " + ns + "::kOutputCount, &" + ns + "::evaluate<double>, &" + ns +
            "::evaluate<float>, &" + ns + "::evaluate_batch<double>, &" + ns + "::evaluate_batch<float>},\n";
  }
  text += R"(};
int main(int argc, char** argv) {
  if (argc != 3) return 2;
  std::FILE* in = std::fopen(argv[1], "r");
  std::FILE* out = std::fopen(argv[2], "w");
  if (!in || !out) return 3;
  // Every case's points, in file order (the cases' lines are consecutive).
  std::vector<unsigned long> order;
  std::vector<std::vector<double>> xd(sizeof kEntries / sizeof kEntries[0]);
  std::vector<std::size_t> count(xd.size(), 0);
  unsigned long index = 0;
  while (std::fscanf(in, "%lu", &index) == 1) {
    const Entry& e = kEntries[index];
    order.push_back(index);
    ++count[index];
    for (std::size_t i = 0; i < e.inputs; ++i) {
      char word[64];
      if (std::fscanf(in, "%63s", word) != 1) return 4;
      xd[index].push_back(std::strtod(word, nullptr));
    }
  }
  std::vector<std::size_t> next(xd.size(), 0);
  std::vector<std::vector<double>> ybd(xd.size());
  std::vector<std::vector<float>> ybf(xd.size());
  std::vector<std::vector<unsigned>> fbd(xd.size()), fbf(xd.size());
  for (std::size_t c = 0; c < xd.size(); ++c) {
    const Entry& e = kEntries[c];
    const std::size_t n = count[c];
    const std::vector<float> xf(xd[c].begin(), xd[c].end());
    ybd[c].assign(n * e.outputs + 1, 0.0);
    ybf[c].assign(n * e.outputs + 1, 0.0f);
    fbd[c].assign(n + 1, 0u);
    fbf[c].assign(n + 1, 0u);
    e.batch_double(xd[c].data(), ybd[c].data(), n, fbd[c].data());
    e.batch_float(xf.data(), ybf[c].data(), n, fbf[c].data());
  }
  for (const unsigned long c : order) {
    const Entry& e = kEntries[c];
    const std::size_t p = next[c]++;
    std::vector<double> x(xd[c].begin() + static_cast<long>(p * e.inputs),
                          xd[c].begin() + static_cast<long>((p + 1) * e.inputs));
    x.push_back(0.0);
    std::vector<float> xf(x.begin(), x.end());
    std::vector<double> yd(e.outputs + 1);
    std::vector<float> yf(e.outputs + 1);
    const unsigned fd = e.evaluate_double(x.data(), yd.data());
    const unsigned ff = e.evaluate_float(xf.data(), yf.data());
    std::fprintf(out, "%u %u %u %u", fd, ff, fbd[c][p], fbf[c][p]);
    for (std::size_t o = 0; o < e.outputs; ++o) std::fprintf(out, " %a", yd[o]);
    for (std::size_t o = 0; o < e.outputs; ++o) std::fprintf(out, " %a", static_cast<double>(yf[o]));
    for (std::size_t o = 0; o < e.outputs; ++o) std::fprintf(out, " %a", ybd[c][p * e.outputs + o]);
    for (std::size_t o = 0; o < e.outputs; ++o)
      std::fprintf(out, " %a", static_cast<double>(ybf[c][p * e.outputs + o]));
    std::fprintf(out, "\n");
  }
  return 0;
}
)";
  return text;
}

// Emits every case into one translation unit, compiles it with the warnings fmpc's own code obeys, runs it.
// `defines`: extra compiler arguments, e.g. -DFMPC_NO_TARGET_CLONES (evaluate_batch for the baseline x86-64 only;
// without it, the clone this CPU supports runs).
std::vector<std::vector<Result>> compile_and_run(const std::vector<Case>& cases, const std::string& tag,
                                                 const std::string& defines = "") {
  ScratchFolder folder(tag);
  for (std::size_t c = 0; c < cases.size(); ++c) {
    EmitOptions options;
    options.target = cases[c].target;
    options.source_path = cases[c].label;
    options.source_hash = 0x0123456789abcdefULL;
    options.namespace_name = "case" + std::to_string(c);
    options.header_path = "case" + std::to_string(c) + ".h";
    fmpc::DiagnosticList diagnostics;
    const auto header = fmpc::emit_evaluator(cases[c].system, options, diagnostics);
    INFO(cases[c].label);
    REQUIRE(header);
    REQUIRE(diagnostics.empty());
    write_text(folder.path / options.header_path, *header);
  }
  write_text(folder.path / "driver.cpp", driver_source(cases));
  std::string inputs;
  for (std::size_t c = 0; c < cases.size(); ++c)
    for (const auto& point : cases[c].points) {
      inputs += std::to_string(c);
      for (double x : point) inputs += " " + hex_float(x);
      inputs += "\n";
    }
  write_text(folder.path / "inputs.txt", inputs);

  const std::string compile = std::string(FMPC_CXX_COMPILER) +
                              " -std=c++17 -O1 -Wall -Wextra -Wpedantic -Wshadow -Wconversion -Wdouble-promotion "
                              "-Wold-style-cast -Werror " + defines + " -o " +
                              (folder.path / "driver").string() + " " + (folder.path / "driver.cpp").string() +
                              " > " + (folder.path / "compile.log").string() + " 2>&1";
  const int compiled = std::system(compile.c_str());
  INFO("compiler output:\n" << read_text(folder.path / "compile.log").substr(0, 4000));
  REQUIRE(compiled == 0);
  const std::string run = (folder.path / "driver").string() + " " + (folder.path / "inputs.txt").string() + " " +
                          (folder.path / "outputs.txt").string();
  REQUIRE(std::system(run.c_str()) == 0);

  std::vector<std::vector<Result>> results(cases.size());
  std::istringstream lines(read_text(folder.path / "outputs.txt"));
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const std::size_t m = cases[c].system.outputs.size();
    for (std::size_t p = 0; p < cases[c].points.size(); ++p) {
      Result result;
      lines >> result.flags_double >> result.flags_float >> result.flags_batch_double >> result.flags_batch_float;
      std::string word;
      for (auto* outputs : {&result.outputs_double, &result.outputs_float, &result.outputs_batch_double,
                            &result.outputs_batch_float})
        for (std::size_t o = 0; o < m; ++o) {
          lines >> word;
          outputs->push_back(std::strtod(word.c_str(), nullptr));
        }
      results[c].push_back(result);
    }
  }
  REQUIRE(lines.good());
  return results;
}

bool defuzzifier_is_continuous(Defuzzifier method) {
  return method == Defuzzifier::Centroid || method == Defuzzifier::WeightedAverage ||
         method == Defuzzifier::WeightedSum;
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

struct Tally {
  std::size_t points = 0, float_checked = 0, float_skipped = 0;
};

// Checks double against the interpreter to 1e-12 of each output's range, flags exactly, and float to 1e-5 where
// float can carry the computation: the firing strengths must be representable (a firing of 1e-40 is a normal
// double but 0 in float, which turns "this rule fired weakly" into "no rule fired"), and the defuzzifier must be
// continuous (bisector, mom, som and lom pick one of the samples, and float rounding may tip a tie).
void compare_with_interpreter(const Case& c, const std::vector<Result>& results, Tally& tally) {
  fmpc::Interpreter interpreter(c.system);
  for (std::size_t p = 0; p < c.points.size(); ++p) {
    const fmpc::Evaluation expected = interpreter.evaluate(c.points[p]);
    const Result& got = results[p];
    ++tally.points;
    INFO(c.label << " point " << p);
    CHECK(got.flags_double == expected_flags(expected));
    CHECK(got.flags_batch_double == expected_flags(expected));
    double weakest_firing = kInf;
    for (double w : expected.firing_strengths)
      if (w > 0.0) weakest_firing = std::min(weakest_firing, w);
    const bool float_comparable = defuzzifier_is_continuous(c.system.defuzzifier) && weakest_firing > 1e-30 &&
                                  got.flags_float == got.flags_double;
    if (float_comparable) ++tally.float_checked;
    else ++tally.float_skipped;
    for (std::size_t o = 0; o < c.system.outputs.size(); ++o) {
      const double range = c.system.outputs[o].max - c.system.outputs[o].min;
      INFO("output " << o << " interpreter " << expected.outputs[o] << " double " << got.outputs_double[o]
                     << " float " << got.outputs_float[o]);
      CHECK(same_or_both_nan(got.outputs_double[o], expected.outputs[o], 1e-12 * range));
      CHECK(same_or_both_nan(got.outputs_batch_double[o], expected.outputs[o], 1e-12 * range));
      // A Sugeno output may lie far outside its declared range (linear consequents): float's own resolution is
      // relative to the value, so the float tolerance is 1e-5 of the range or of the value, whichever is larger.
      // A linear consequent c0 + sum c_j x_j that cancels (juggler's, near 0) carries float's rounding of its
      // largest term, not of its result: the scale includes the largest sum of |terms| over the output's terms.
      double consequent_magnitude = 0.0;
      for (const fmpc::Term& term : c.system.outputs[o].terms) {
        if (term.mf.kind != fmpc::MfKind::Linear) continue;
        const std::vector<double>& k = term.mf.params;
        double magnitude = k.empty() ? 0.0 : std::fabs(k.back());
        for (std::size_t j = 0; j + 1 < k.size() && j < c.points[p].size(); ++j)
          magnitude += std::fabs(k[j] * c.points[p][j]);
        consequent_magnitude = std::max(consequent_magnitude, magnitude);
      }
      const double float_scale = std::max({range, std::fabs(expected.outputs[o]), consequent_magnitude});
      if (float_comparable) {
        CHECK(same_or_both_nan(got.outputs_float[o], expected.outputs[o], 1e-5 * float_scale));
        CHECK(got.flags_batch_float == got.flags_float);
        CHECK(same_or_both_nan(got.outputs_batch_float[o], expected.outputs[o], 1e-5 * float_scale));
      }
    }
  }
}

// Uniform points plus the edges every module must handle: the range ends, out of range, +-inf and NaN.
std::vector<std::vector<double>> test_points(const FuzzySystem& system, std::uint64_t seed, std::size_t count) {
  std::vector<std::vector<double>> points = fmpc::testing::random_inputs(system, seed, count);
  const std::size_t d = system.inputs.size();
  std::vector<double> low(d), high(d), below(d), above(d), infinite(d), nan(d);
  for (std::size_t i = 0; i < d; ++i) {
    const fmpc::Variable& v = system.inputs[i];
    low[i] = v.min;
    high[i] = v.max;
    below[i] = v.min - (v.max - v.min) / 3.0;
    above[i] = v.max + (v.max - v.min) / 7.0;
    infinite[i] = i % 2 ? kInf : -kInf;
    nan[i] = i == d / 2 ? kNaN : v.min;
  }
  for (auto* edge : {&low, &high, &below, &above, &infinite, &nan}) points.push_back(*edge);
  return points;
}

std::vector<fs::path> golden_rule_files() {
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
  return files;
}

FuzzySystem liver_system() {
  const fs::path path = fs::path(FMPC_SOURCE_DIR) / "rulesets" / "liver_fibrosis" / "mamdani.fis";
  fmpc::DiagnosticList diagnostics;
  fmpc::RuleFile file = fmpc::load_rule_file(path.string(), read_text(path), diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(file.systems.size() == 1);
  return file.systems[0];
}

EmitOptions default_options() {
  EmitOptions options;
  options.source_path = "rulesets/liver_fibrosis/mamdani.fis";
  options.source_hash = 0xfeedfacecafebeefULL;
  options.namespace_name = "liver";
  return options;
}

}  // namespace

TEST_CASE("emitted headers agree with the interpreter on every golden rule file", "[emit][heavy]") {
  std::vector<Case> cases;
  std::size_t skipped = 0;
  std::uint64_t seed = 1;
  for (const fs::path& path : golden_rule_files()) {
    fmpc::DiagnosticList diagnostics;
    fmpc::RuleFile file = fmpc::load_rule_file(path.string(), read_text(path), diagnostics);
    if (diagnostics.has_errors()) continue;  // golden cases of error messages
    for (FuzzySystem& system : file.systems) {
      if (system.interval_type2 || (system.type == fmpc::SystemType::Mamdani && system.samples <= 0)) {
        ++skipped;  // type-2: tests/unit/emit_type2_test.cpp; samples exact: the error is tested below
        continue;
      }
      Case c;
      c.label = path.filename().string() + ":" + system.name;
      c.points = test_points(system, seed++, 40);
      c.system = std::move(system);
      // Every third system through the CUDA header: its host side must compile and agree as well.
      if (cases.size() % 3 == 2) c.target = EmitOptions::Target::Cuda;
      cases.push_back(std::move(c));
    }
  }
  REQUIRE(cases.size() >= 10);
  const auto results = compile_and_run(cases, "golden");
  Tally tally;
  for (std::size_t c = 0; c < cases.size(); ++c) compare_with_interpreter(cases[c], results[c], tally);
  CHECK(tally.float_checked > tally.points / 2);
  WARN("golden systems: " << cases.size() << " emitted, " << skipped << " skipped (type-2 or samples exact); "
                          << tally.points << " points, float compared on " << tally.float_checked);
}

TEST_CASE("emitted headers agree with the interpreter on seeded random systems", "[emit]") {
  fmpc::testing::RandomSystemOptions options;
  options.exact_samples = false;
  options.consequent_negation = true;
  options.consequent_hedges = true;
  std::vector<Case> cases;
  for (std::uint64_t seed = 100; seed < 148; ++seed) {
    Case c;
    c.system = fmpc::testing::random_system(seed, options);
    c.label = "random seed " + std::to_string(seed);
    c.points = test_points(c.system, seed * 7, 30);
    cases.push_back(std::move(c));
  }
  // The baseline x86-64 evaluate_batch; the golden files run the clone this CPU supports.
  const auto results = compile_and_run(cases, "random", "-DFMPC_NO_TARGET_CLONES");
  Tally tally;
  for (std::size_t c = 0; c < cases.size(); ++c) compare_with_interpreter(cases[c], results[c], tally);
  CHECK(tally.float_checked > tally.points / 2);
}

TEST_CASE("a specialised system (inputs fixed by the pipeline) is emitted with its folded grades", "[emit]") {
  const FuzzySystem liver = liver_system();
  fmpc::Bindings bindings;
  bindings.fixed.push_back({"HCV", 10.0, {}});
  bindings.fixed.push_back({"ALD", 22.0, {}});
  fmpc::DiagnosticList diagnostics;
  const auto compiled = fmpc::run_pipeline(liver, bindings, {}, diagnostics);
  REQUIRE(compiled);
  REQUIRE(compiled->system.inputs.size() == 3);
  Case c;
  c.label = "liver HCV=10 ALD=22";
  c.system = compiled->system;
  c.points = test_points(c.system, 5, 60);
  const auto results = compile_and_run({c}, "specialised");
  Tally tally;
  compare_with_interpreter(c, results[0], tally);
  // And against the unspecialised system with the fixed values put back: the pipeline's error bound.
  fmpc::Interpreter full(liver);
  for (std::size_t p = 0; p < 60; ++p) {
    const auto& x = c.points[p];
    const double expected = full.evaluate({10.0, x[0], 22.0, x[1], x[2]}).outputs[0];
    CHECK(std::fabs(results[0][p].outputs_double[0] - expected) <= compiled->error_bound() + 1e-12 * 75.0);
  }
}

TEST_CASE("the emitter refuses what it cannot compile, with located errors", "[emit]") {
  FuzzySystem liver = liver_system();
  SECTION("samples exact") {
    liver.samples = 0;
    fmpc::DiagnosticList diagnostics;
    CHECK_FALSE(fmpc::emit_evaluator(liver, default_options(), diagnostics));
    REQUIRE(diagnostics.error_count() == 1);
    CHECK(diagnostics.items()[0].message.find("samples exact") != std::string::npos);
  }
  SECTION("namespace names") {
    for (const char* bad : {"", "1liver", "liver::", "::liver", "a b", "liver-model", "a:::b"}) {
      EmitOptions options = default_options();
      options.namespace_name = bad;
      fmpc::DiagnosticList diagnostics;
      INFO(bad);
      CHECK_FALSE(fmpc::emit_evaluator(liver, options, diagnostics));
      CHECK(diagnostics.error_count() == 1);
    }
    EmitOptions options = default_options();
    options.namespace_name = "scene::liver_2";
    fmpc::DiagnosticList diagnostics;
    CHECK(fmpc::emit_evaluator(liver, options, diagnostics));
    CHECK(diagnostics.empty());
  }
}

TEST_CASE("the banner names the source and its hash; #line points at rules and back at the header", "[emit]") {
  const FuzzySystem liver = liver_system();
  EmitOptions options = default_options();
  options.header_path = "liver_evaluator.h";
  options.banner_notes = {"fixed: none"};
  fmpc::DiagnosticList diagnostics;
  const auto header = fmpc::emit_evaluator(liver, options, diagnostics);
  REQUIRE(header);
  CHECK(header->find("// source: rulesets/liver_fibrosis/mamdani.fis\n") != std::string::npos);
  CHECK(header->find("// source hash (FNV-1a 64): feedfacecafebeef\n") != std::string::npos);
  CHECK(header->find("// fixed: none\n") != std::string::npos);
  CHECK(header->find("kSourceHash = 0xfeedfacecafebeefull;") != std::string::npos);
  // The units (issue 11: a compiled artefact must say what its numbers are in).
  CHECK(header->find("inline constexpr const char* kInputUnits[] = {\"kPa\", \"kPa\", \"kPa\", \"kPa\", "
                     "\"kPa\"};") != std::string::npos);
  CHECK(header->find("inline constexpr const char* kOutputUnits[] = {\"kPa\"};") != std::string::npos);

  // Each rule's #line names its line in the rule file; each return directive names its own next line.
  fmpc::testing::check_line_directives(*header, "liver_evaluator.h", "rulesets/liver_fibrosis/mamdani.fis", liver);

  options.line_directives = false;
  const auto plain = fmpc::emit_evaluator(liver, options, diagnostics);
  REQUIRE(plain);
  CHECK(plain->find("#line") == std::string::npos);
}

TEST_CASE("generated headers carry the kernel math verbatim, renamed, and only the CUDA target a kernel", "[emit]") {
  for (const char* path : {"kernels/fmpc_hd.h", "kernels/fuzzy_kinds.h", "kernels/fuzzy_math.h",
                           "kernels/lane_exp_math.h"}) {
    INFO(path);
    CHECK(std::string(fmpc::embedded_kernel_source(path)) ==
          read_text(fs::path(FMPC_SOURCE_DIR) / path));
  }
  CHECK(fmpc::embedded_kernel_source("kernels/no_such_file.h").empty());
  const std::string math = fmpc::embedded_fuzzy_math("copy_ns");
  CHECK(math.find("namespace copy_ns {") != std::string::npos);
  CHECK(math.find("namespace fmpc {") == std::string::npos);
  CHECK(math.find("#include \"kernels/") == std::string::npos);
  CHECK(math.find("FMPC_HD T triangle(T x, T a, T b, T c)") != std::string::npos);

  const FuzzySystem liver = liver_system();
  EmitOptions options = default_options();
  fmpc::DiagnosticList diagnostics;
  const auto cpp = fmpc::emit_evaluator(liver, options, diagnostics);
  options.target = EmitOptions::Target::Cuda;
  const auto cuda = fmpc::emit_evaluator(liver, options, diagnostics);
  REQUIRE(cpp);
  REQUIRE(cuda);
  CHECK(cpp->find("__global__") == std::string::npos);
  CHECK(cuda->find("__global__ void evaluate_kernel") != std::string::npos);
  CHECK(cuda->find("return cudaGetLastError();") != std::string::npos);
  // Only the MF families the system uses are called (liver: Gaussian and one triangle).
  CHECK(cpp->find("fmpc_math::mf::gaussian(x0") != std::string::npos);
  CHECK(cpp->find("fmpc_math::mf::triangle(x3") != std::string::npos);
  CHECK(cpp->find("fmpc_math::mf::sigmoid(x") == std::string::npos);
  // The lanes' exp: kernels/lane_exp_math.h's definitions, verbatim, in the header's own namespace.
  const std::string lane_exp = fmpc::embedded_namespace_body("kernels/lane_exp_math.h");
  CHECK(lane_exp.rfind("// exp for the lanes of evaluate_batch:\n", 0) == 0);
  CHECK(lane_exp.find("inline double lane_exp(double argument, double lowest) {") != std::string::npos);
  CHECK(lane_exp.find("namespace") == std::string::npos);
  CHECK(cpp->find("inline constexpr std::size_t kBatchLanes = 16;\n\n" + lane_exp + "\n") != std::string::npos);
  CHECK(fmpc::embedded_namespace_body("kernels/no_such_file.h").empty());
}

TEST_CASE("evaluate_batch runs blocks of lanes for centroid Mamdani systems, and the loop over evaluate otherwise",
          "[emit]") {
  FuzzySystem liver = liver_system();
  fmpc::DiagnosticList diagnostics;
  const auto lanes = fmpc::emit_evaluator(liver, default_options(), diagnostics);
  REQUIRE(lanes);
  CHECK(lanes->find("inline constexpr std::size_t kBatchLanes = 16;") != std::string::npos);
  CHECK(lanes->find("lane_gaussian(x[0][j], T(0.91), T(7.64), lowest)") != std::string::npos);
  CHECK(lanes->find("fmpc_math::mf::triangle(x[3][j], T(-20), T(0), T(20))") != std::string::npos);
  // The 247 rules' min / max, factored and shared: 195 operations (evaluate() takes 271 minima and 243 maxima).
  std::istringstream lines(*lanes);
  std::string line;
  int lattice_operations = 0;
  while (std::getline(lines, line))
    if (line.rfind("      const T f", 0) == 0) ++lattice_operations;
  CHECK(lattice_operations == 195);
  // The liver's 4 columns x 101 samples, less the grades below 1e-36 (the F0-F1, F2 and F3 tails): 210 grades.
  CHECK(lanes->find("inline const volatile double kLaneGrades0[210] = {") != std::string::npos);
  // Points whose aggregate total is below the floor go through evaluate() (test "... too small for its shortcuts").
  CHECK(lanes->find("const T total_floor = sizeof(T) < sizeof(double) ? T(") != std::string::npos);
  CHECK(lanes->find("f = evaluate(inputs + (start + j) * kInputCount, y);") != std::string::npos);
  CHECK(lanes->find("FMPC_GENERATED_BATCH_CLONES\ninline void evaluate_batch(") != std::string::npos);

  for (const Defuzzifier method : {Defuzzifier::Bisector, Defuzzifier::MeanOfMaximum}) {
    liver.defuzzifier = method;
    const auto loop = fmpc::emit_evaluator(liver, default_options(), diagnostics);
    REQUIRE(loop);
    CHECK(loop->find("kBatchLanes") == std::string::npos);
    CHECK(loop->find("const unsigned f = evaluate(inputs + i * kInputCount, outputs + i * kOutputCount);") !=
          std::string::npos);
  }
  liver.defuzzifier = Defuzzifier::Centroid;
  liver.aggregation = fmpc::SNorm::ProbabilisticSum;
  const auto sum = fmpc::emit_evaluator(liver, default_options(), diagnostics);
  REQUIRE(sum);
  CHECK(sum->find("kBatchLanes") == std::string::npos);
  CHECK(diagnostics.empty());
}

TEST_CASE("evaluate_batch gives evaluate() the points whose aggregate is too small for its shortcuts", "[emit]") {
  // evaluate_batch flushes input grades below 3.3e-308 to 0 and leaves out consequent grades below 1e-36; points
  // whose aggregate total is below the floor that makes both harmless go through evaluate(). Each point below
  // would come out wrong without that: at x = 38.2 `near` is 2e-317 (a subnormal: the rule fired, but the lanes
  // see 0, "no rule fired"); at x = 46.68 `far` is 1e-60, which clips `large` at 1e-60 wherever it exceeds that,
  // also where the lanes left its grades (below 1e-36, y < 1.6) out. Others: a normal grade of 5e-306, a NaN, out
  // of range on both sides, and ordinary points the lanes evaluate.
  const std::string text = R"(system tails "Rules that fire very weakly"
  type mamdani
  defuzzify centroid samples 101
  when no rule fires: midrange

input x "Position" in [0, 50] mm
  near is gauss(mean 0, sd 1)
  far is gauss(mean 50, sd 0.2)

output y "Force" in [0, 10] N
  small is triangle(start 0, peak 2, end 4)
  large is gauss(mean 8, sd 0.5)

rule r1: if x is near then y is small
rule r2: if x is far then y is large
)";
  fmpc::DiagnosticList diagnostics;
  fmpc::RuleFile file = fmpc::load_rule_file("tails.fis", text, diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  REQUIRE(file.systems.size() == 1);
  Case c;
  c.label = "tails";
  c.system = file.systems[0];
  for (const double x : {0.5, 3.0, 20.0, 37.5, 38.2, 38.5, 46.68, 47.0, 49.0, 50.0, 50.1, 55.0, -1.0, kNaN})
    c.points.push_back({x});
  const auto results = compile_and_run({c}, "tails", "-DFMPC_NO_TARGET_CLONES");
  Tally tally;
  compare_with_interpreter(c, results[0], tally);
  // The subnormal firing at 38.2: the interpreter fires, and so must evaluate_batch.
  CHECK(results[0][4].flags_batch_double == 0u);
  CHECK(std::fabs(results[0][4].outputs_batch_double[0] - 2.0) < 0.01);
}

TEST_CASE("evaluate_batch's lane_exp is within 2 ulp of exp (float: 1) down to its lowest argument, 0 below",
          "[emit]") {
  ScratchFolder folder("lane_exp");
  fmpc::DiagnosticList diagnostics;
  const auto header = fmpc::emit_evaluator(liver_system(), default_options(), diagnostics);
  REQUIRE(header);
  write_text(folder.path / "liver.h", *header);
  // Prints, for double then float: the largest distance in ulp from exp at arguments from `lowest` up, the number
  // of results that are neither 0 nor normal (lane_exp never computes a subnormal), the number of arguments below
  // `lowest` whose result is not 0, and the number of arguments whose result is not the expected value (1 at 0, a
  // normal number at `lowest`, 0 just below it, far below, at -inf and at NaN). Then `lowest` itself.
  write_text(folder.path / "driver.cpp", R"(#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include "liver.h"
template <typename T>
void measure(std::FILE* out, T lowest, T far_below) {
  std::mt19937_64 random(7);
  double worst_ulp = 0;
  long not_normal = 0, below_misses = 0, special_misses = 0;
  for (long i = 0; i < 2000000; ++i) {
    const double spans[] = {1.0, 40.0, static_cast<double>(-lowest), static_cast<double>(-far_below)};
    const T a = static_cast<T>(-std::uniform_real_distribution<double>(0.0, spans[i % 4])(random));
    const T expected = std::exp(a), got = liver::lane_exp(a, lowest);
    if (got != T(0) && !(got >= std::numeric_limits<T>::min())) ++not_normal;
    if (a >= lowest) {
      const double ulp = static_cast<double>(std::nextafter(expected, T(2)) - expected);
      worst_ulp = std::fmax(worst_ulp, std::fabs(static_cast<double>(got) - static_cast<double>(expected)) / ulp);
    } else if (got != T(0)) {
      ++below_misses;
    }
  }
  const T inf = std::numeric_limits<T>::infinity();
  if (liver::lane_exp(T(0), lowest) != T(1) || liver::lane_exp(-T(0), lowest) != T(1)) ++special_misses;
  if (!(liver::lane_exp(lowest, lowest) >= std::numeric_limits<T>::min())) ++special_misses;
  for (const T a : {std::nextafter(lowest, -inf), far_below, T(10) * far_below, -inf,
                    std::numeric_limits<T>::quiet_NaN()})
    if (liver::lane_exp(a, lowest) != T(0)) ++special_misses;
  std::fprintf(out, "%g %ld %ld %ld %g\n", worst_ulp, not_normal, below_misses, special_misses,
               static_cast<double>(lowest));
}
int main(int, char** argv) {
  std::FILE* out = std::fopen(argv[1], "w");
  if (!out) return 3;
  measure<double>(out, liver::lane_exp_lowest(0.0), -760.0);
  measure<float>(out, liver::lane_exp_lowest(0.0f), -110.0f);
  return 0;
}
)");
  const std::string compile = std::string(FMPC_CXX_COMPILER) + " -std=c++17 -O2 -Wall -Wextra -Werror -o " +
                              (folder.path / "driver").string() + " " + (folder.path / "driver.cpp").string() +
                              " > " + (folder.path / "compile.log").string() + " 2>&1";
  const int compiled = std::system(compile.c_str());
  INFO("compiler output:\n" << read_text(folder.path / "compile.log").substr(0, 4000));
  REQUIRE(compiled == 0);
  REQUIRE(std::system(((folder.path / "driver").string() + " " + (folder.path / "out.txt").string()).c_str()) == 0);
  std::istringstream results(read_text(folder.path / "out.txt"));
  // lowest: exp(-708) = 3.3e-308 and exp(-86) = 4.5e-38 are normal, and within a factor 1.5 (float: 3.7) of the
  // smallest normal number.
  for (const auto& [allowed_ulp, lowest] : {std::pair{2.0, -708.0}, std::pair{1.0, -86.0}}) {
    double worst_ulp = -1, got_lowest = 0;
    long not_normal = -1, below_misses = -1, special_misses = -1;
    results >> worst_ulp >> not_normal >> below_misses >> special_misses >> got_lowest;
    INFO("allowed " << allowed_ulp << " ulp");
    CHECK(worst_ulp >= 0.0);
    CHECK(worst_ulp <= allowed_ulp);
    CHECK(not_normal == 0);
    CHECK(below_misses == 0);
    CHECK(special_misses == 0);
    CHECK(got_lowest == lowest);
  }
  REQUIRE_FALSE(results.fail());
}
