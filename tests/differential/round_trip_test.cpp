// Round trips that must keep the meaning: MATLAB -> IR -> MATLAB -> IR, fmpc -> MATLAB -> fmpc and
// MATLAB -> fmpc -> MATLAB, on the shared MATLAB/Octave files and on seeded random systems. "Keep the meaning"
// is checked twice: the IRs are equal (parameters bit for bit) and the interpreter gives identical outputs on
// 1,000 seeded random points per system.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "compiler/eval/interpreter.h"
#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/matlab_fis.h"
#include "diagnostics/number_format.h"
#include "compiler/sema/check.h"
#include "tests/support/random_system.h"
#include "tests/support/system_comparison.h"

namespace {

using namespace fmpc;

constexpr std::size_t kPointsPerSystem = 1000;
constexpr std::uint64_t kRandomSystems = 60;

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream buffer;
  buffer << in.rdbuf();
  return buffer.str();
}

std::string rendered(const DiagnosticList& diagnostics, const std::string& path, const std::string& text) {
  SourceFiles sources;
  sources.add(path, text);
  return render_all(diagnostics, sources);
}

// The shared .fis files, or none (with a visible message) when ../shared/data is absent.
std::vector<std::filesystem::path> shared_fis_files() {
  const std::filesystem::path folder = std::filesystem::path(FMPC_SHARED_DATA_DIR) / "matlab-fis";
  std::vector<std::filesystem::path> files;
  if (!std::filesystem::is_directory(folder)) {
    WARN("skipped: " << folder.string() << " is absent");
    return files;
  }
  for (const auto& entry : std::filesystem::directory_iterator(folder))
    if (entry.path().extension() == ".fis") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  return files;
}

// Reads MATLAB text that must be free of errors (warnings are the reader's business, tested elsewhere).
FuzzySystem read_matlab_clean(const std::string& path, const std::string& text) {
  DiagnosticList diagnostics;
  const RuleFile file = read_matlab_fis(path, text, diagnostics);
  INFO(text << "\n" << rendered(diagnostics, path, text));
  REQUIRE(diagnostics.error_count() == 0);
  REQUIRE(file.systems.size() == 1);
  return file.systems[0];
}

FuzzySystem read_fmpc_clean(const std::string& path, const std::string& text) {
  DiagnosticList diagnostics;
  const RuleFile file = read_fmpc(path, text, diagnostics);
  INFO(text << "\n" << rendered(diagnostics, path, text));
  REQUIRE(diagnostics.error_count() == 0);
  REQUIRE(file.systems.size() == 1);
  return file.systems[0];
}

std::string as_fmpc(const FuzzySystem& system) {
  RuleFile file;
  file.path = "round_trip.fis";
  file.systems.push_back(system);
  return write_fmpc(file);
}

std::string as_matlab(const FuzzySystem& system) {
  DiagnosticList diagnostics;  // what MATLAB cannot hold is tested in tests/unit/matlab_fis_test.cpp
  return write_matlab_fis(system, diagnostics);
}

// Whether the interpreter may run `system` (its precondition is a system without sema errors).
bool passes_sema(const FuzzySystem& system, const std::string& name) {
  DiagnosticList diagnostics;
  check_system(system, diagnostics);
  if (!diagnostics.has_errors()) return true;
  std::string messages;
  for (const Diagnostic& d : diagnostics.items())
    if (d.severity == Severity::Error) messages += "\n  " + d.message;
  WARN("outputs not compared for " << name << ": sema rejects it" << messages);
  return false;
}

// Identical outputs (NaN matching NaN) of `expected` and `actual` on kPointsPerSystem seeded points.
void require_same_outputs(const FuzzySystem& expected, const FuzzySystem& actual, std::uint64_t seed) {
  const auto points = testing::random_inputs(expected, seed, kPointsPerSystem);
  for (const std::vector<double>& point : points) {
    const Evaluation a = evaluate(expected, point);
    const Evaluation b = evaluate(actual, point);
    REQUIRE(a.outputs.size() == b.outputs.size());
    for (std::size_t o = 0; o < a.outputs.size(); ++o) {
      const bool same = a.outputs[o] == b.outputs[o] || (std::isnan(a.outputs[o]) && std::isnan(b.outputs[o]));
      if (!same) {
        std::string at;
        for (double x : point) at += format_number(x) + " ";
        FAIL("output " << o + 1 << " differs at [ " << at << "]: " << format_number(a.outputs[o]) << " vs "
                       << format_number(b.outputs[o]));
      }
    }
  }
}

}  // namespace

TEST_CASE("round trip: MATLAB file -> IR -> MATLAB -> IR keeps the IR and the outputs", "[round-trip]") {
  std::uint64_t seed = 0;
  for (const std::filesystem::path& path : shared_fis_files()) {
    ++seed;
    const std::string name = path.filename().string();
    INFO(name);
    const FuzzySystem original = read_matlab_clean(path.string(), read_text(path));
    const std::string written = as_matlab(original);
    const FuzzySystem back = read_matlab_clean(name, written);
    CHECK(testing::first_difference(original, back) == "");
    CHECK(as_matlab(back) == written);  // the writer is a fixed point after one trip
    if (passes_sema(original, name)) require_same_outputs(original, back, seed);
  }
}

TEST_CASE("round trip: random system -> MATLAB -> IR keeps the IR and the outputs", "[heavy][round-trip]") {
  const testing::RandomSystemOptions options = testing::RandomSystemOptions::matlab_fis();
  for (std::uint64_t seed = 1; seed <= kRandomSystems; ++seed) {
    INFO("random_system(" << seed << ", matlab_fis())");
    const FuzzySystem original = testing::random_system(seed, options);
    const std::string written = as_matlab(original);
    const FuzzySystem back = read_matlab_clean("random.fis", written);
    REQUIRE(testing::first_difference(original, back) == "");
    REQUIRE(passes_sema(original, "random_system(" + std::to_string(seed) + ")"));
    require_same_outputs(original, back, seed);
  }
}

TEST_CASE("round trip: fmpc -> MATLAB -> fmpc keeps the IR and the outputs", "[heavy][round-trip]") {
  const testing::RandomSystemOptions options = testing::RandomSystemOptions::matlab_fis();
  for (std::uint64_t seed = 1; seed <= kRandomSystems; ++seed) {
    INFO("random_system(" << seed << ", matlab_fis())");
    const std::string fmpc_text = as_fmpc(testing::random_system(seed, options));
    const FuzzySystem from_fmpc = read_fmpc_clean("random.fis", fmpc_text);
    const FuzzySystem via_matlab = read_matlab_clean("random_matlab.fis", as_matlab(from_fmpc));
    const FuzzySystem again = read_fmpc_clean("random_again.fis", as_fmpc(via_matlab));
    REQUIRE(testing::first_difference(from_fmpc, again) == "");
    REQUIRE(passes_sema(from_fmpc, "random_system(" + std::to_string(seed) + ")"));
    require_same_outputs(from_fmpc, again, seed);
  }
}

TEST_CASE("round trip: MATLAB -> fmpc -> MATLAB keeps the IR and the outputs", "[heavy][round-trip]") {
  std::uint64_t seed = 100;
  for (const std::filesystem::path& path : shared_fis_files()) {
    ++seed;
    const std::string name = path.filename().string();
    INFO(name);
    const FuzzySystem original = read_matlab_clean(path.string(), read_text(path));
    // A system sema rejects (juggler.fis repeats the term name 'out1mf', which MATLAB allows) cannot be written
    // as an fmpc file that reads back, since fmpc rules name terms.
    if (!passes_sema(original, name)) continue;
    const FuzzySystem via_fmpc = read_fmpc_clean("via_fmpc.fis", as_fmpc(original));
    const FuzzySystem back = read_matlab_clean("back.fis", as_matlab(via_fmpc));
    CHECK(testing::first_difference(original, via_fmpc) == "");
    CHECK(testing::first_difference(original, back) == "");
    require_same_outputs(original, back, seed);
  }
}
