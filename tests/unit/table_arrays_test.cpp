// The table arrays header (`fmpc compile --target table -o NAME.h`, compiler/backend/table/table_arrays.h) compiled
// with the system compiler at test time, several tables per translation unit: its lookups (view() with
// interpolate_table, and interpolate_batch) agree with the .fzt loader's lookups of the same table (bit for bit in
// double, to float's rounding in float) and with the interpreter within the table's measured error, at grid
// points, at and beyond the upper and lower ends of every axis, at +-inf and at NaN. Also locate_on_axis
// (kernels/table_math.h): its proportional guess finds the binary search's cell on uniform, refined and extreme axes.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "compiler/backend/table/lookup_table.h"
#include "compiler/backend/table/table_arrays.h"
#include "compiler/backend/table/table_builder.h"
#include "compiler/eval/interpreter.h"
#include "compiler/frontend/rule_file_loader.h"
#include "tests/support/generated_program.h"

namespace {

using namespace fmpc;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

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

// Two outputs, so that the header's output stride is exercised; negative ranges and an offset axis.
const char* const kTwoOutputs = R"(system pair
  type mamdani
  and min  or max  implication min  aggregation max
  defuzzify centroid samples 101
input load in [-4, 6] dimensionless
  low is triangle(start -4, peak -4, end 2)
  high is triangle(start 0, peak 6, end 6)
input temperature in [20, 80] dimensionless
  cold is linear_z(start 20, end 60)
  hot is linear_s(start 40, end 80)
output force in [-10, 10] dimensionless
  pull is triangle(start -10, peak -5, end 0)
  push is triangle(start 0, peak 5, end 10)
output heat in [0, 1] dimensionless
  little is triangle(start 0, peak 0.2, end 0.5)
  much is triangle(start 0.4, peak 0.8, end 1)
rule r1: if load is low then force is pull
rule r2: if load is high then force is push
rule r3: if temperature is cold then heat is little
rule r4: if temperature is hot or load is high then heat is much
)";

FuzzySystem load_system(const char* name, const char* text) {
  DiagnosticList diagnostics;
  RuleFile file = load_rule_file(name, text, diagnostics);
  REQUIRE_FALSE(diagnostics.has_errors());
  return file.systems.front();
}

// One table under test: the system it tabulates (for the interpreter), the table, and the queries.
struct Case {
  std::string label;
  FuzzySystem source;
  LookupTable table;
  bool from_builder = true;  // false: a hand-made table with no source system
  std::vector<std::vector<double>> queries;
};

LookupTable build(const FuzzySystem& source, const Bindings& bindings, double max_error, BreakpointSpacing spacing,
                  TableValueType type) {
  DiagnosticList diagnostics;
  const std::optional<CompileResult> compiled = run_pipeline(source, bindings, PipelineOptions{}, diagnostics);
  REQUIRE(compiled);
  TableBuildOptions options;
  options.max_error = max_error;
  options.spacing = spacing;
  options.value_type = type;
  options.held_out_points = 100000;
  options.training_points = 5000;
  options.threads = 2;
  options.source_path = "test.fis";
  const std::optional<LookupTable> table = build_table(source, *compiled, options, diagnostics);
  INFO(render_all(diagnostics, SourceFiles{}));
  REQUIRE(table);
  return *table;
}

// 6 axes of 4 breakpoints, f = sum (a + 1) x_a: multilinear, so interpolation reproduces it; more axes than
// interpolate_table specialises, which takes its general loop.
LookupTable six_axis_table() {
  LookupTable t;
  t.system_name = "six";
  t.source_path = "six.fis";
  for (int a = 0; a < 6; ++a)
    t.axes.push_back(TableAxis{"x" + std::to_string(a), "", static_cast<std::uint32_t>(a),
                               {-1.0 - a, 0.5, 2.0 + 0.25 * a, 7.0 + a}});
  t.output_names = {"f"};
  t.output_units = {""};
  for (std::uint64_t p = 0; p < t.grid_points(); ++p) {
    double f = 0.0;
    std::uint64_t rest = p;
    for (int a = 5; a >= 0; --a) {
      f += (a + 1) * t.axes[static_cast<std::size_t>(a)].breakpoints[rest % 4];
      rest /= 4;
    }
    t.values.push_back(f);
  }
  t.max_error = 0.0;
  t.max_error_location = std::vector<double>(6, 0.0);
  return t;
}

// Random points inside the grid, random grid points, and per axis (the others random inside): exactly at the
// upper end, just below it, above it, +inf, exactly at the lower end, below it, -inf and NaN; then every axis at
// its upper end at once and every axis above it.
std::vector<std::vector<double>> queries_for(const LookupTable& table, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  const std::size_t d = table.axes.size();
  auto inside = [&] {
    std::vector<double> q(d);
    for (std::size_t a = 0; a < d; ++a) {
      const std::vector<double>& b = table.axes[a].breakpoints;
      q[a] = std::uniform_real_distribution<double>(b.front(), b.back())(random);
    }
    return q;
  };
  std::vector<std::vector<double>> queries;
  for (int i = 0; i < 300; ++i) queries.push_back(inside());
  for (int i = 0; i < 60; ++i) {
    std::vector<double> q(d);
    for (std::size_t a = 0; a < d; ++a) {
      const std::vector<double>& b = table.axes[a].breakpoints;
      q[a] = b[std::uniform_int_distribution<std::size_t>(0, b.size() - 1)(random)];
    }
    queries.push_back(q);
  }
  for (std::size_t a = 0; a < d; ++a) {
    const std::vector<double>& b = table.axes[a].breakpoints;
    const double span = b.back() - b.front();
    for (double x : {b.back(), std::nextafter(b.back(), -kInf), b.back() + span / 3, kInf, b.front(),
                     b.front() - span / 5, -kInf, kNaN}) {
      std::vector<double> q = inside();
      q[a] = x;
      queries.push_back(q);
    }
  }
  std::vector<double> upper(d), above(d);
  for (std::size_t a = 0; a < d; ++a) {
    upper[a] = table.axes[a].breakpoints.back();
    above[a] = upper[a] + 1.0;
  }
  queries.push_back(upper);
  queries.push_back(above);
  return queries;
}

std::string hex_float(double value) {
  char text[64];
  std::snprintf(text, sizeof text, "%a", value);
  return text;
}

// The driver reads, per case, "index n" and n queries, and prints per query the view() lookup's outputs, then the
// same queries through interpolate_batch (all n at once), as hex floats.
std::string driver_source(const std::vector<Case>& cases) {
  std::string text = "#include <cstdio>\n#include <cstdlib>\n#include <vector>\n";
  for (std::size_t c = 0; c < cases.size(); ++c) text += "#include \"case" + std::to_string(c) + ".h\"\n";
  text += R"(
template <typename Value, int Axes, int Outputs>
int run(std::FILE* in, std::FILE* out, std::size_t n, fmpc::TableView<Value> (*view)(),
        void (*batch)(const double*, Value*, std::size_t)) {
  std::vector<double> queries(n * Axes);
  for (double& q : queries) {
    char word[64];
    if (std::fscanf(in, "%63s", word) != 1) return 4;
    q = std::strtod(word, nullptr);
  }
  std::vector<Value> one(n * Outputs), all(n * Outputs);
  for (std::size_t i = 0; i < n; ++i) fmpc::interpolate_table(view(), &queries[i * Axes], &one[i * Outputs]);
  batch(queries.data(), all.data(), n);
  for (std::size_t i = 0; i < n * Outputs; ++i)
    std::fprintf(out, "%a %a\n", static_cast<double>(one[i]), static_cast<double>(all[i]));
  return 0;
}

int main(int argc, char** argv) {
  if (argc != 3) return 2;
  std::FILE* in = std::fopen(argv[1], "r");
  std::FILE* out = std::fopen(argv[2], "w");
  if (!in || !out) return 3;
  unsigned long index = 0, n = 0;
  while (std::fscanf(in, "%lu %lu", &index, &n) == 2) {
    int status = 5;
    switch (index) {
)";
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const std::string ns = "case" + std::to_string(c);
    text += "      case " + std::to_string(c) + ": status = run<" + ns + "::Value, " + ns + "::kAxes, " + ns +
            "::kOutputs>(in, out, n, &" + ns + "::view, &" + ns + "::interpolate_batch); break;\n";
  }
  text += R"(    }
    if (status != 0) return status;
  }
  return 0;
}
)";
  return text;
}

struct HeaderLookup {
  std::vector<double> one, batch;  // per query, table.outputs values each
};

// Writes every case's header, compiles them into one driver with fmpc's warnings as errors, runs the queries.
std::vector<HeaderLookup> compile_and_run(const std::vector<Case>& cases) {
  testing::ScratchFolder folder("table_arrays");
  std::string inputs;
  for (std::size_t c = 0; c < cases.size(); ++c) {
    TableArraysOptions options;
    options.namespace_name = "case" + std::to_string(c);
    DiagnosticList diagnostics;
    testing::write_text_file(folder.path() / ("case" + std::to_string(c) + ".h"),
                             write_table_arrays(cases[c].table, options, diagnostics).value());
    inputs += std::to_string(c) + " " + std::to_string(cases[c].queries.size()) + "\n";
    for (const std::vector<double>& q : cases[c].queries) {
      for (double x : q) inputs += hex_float(x) + " ";
      inputs += "\n";
    }
  }
  testing::write_text_file(folder.path() / "driver.cpp", driver_source(cases));
  testing::write_text_file(folder.path() / "queries.txt", inputs);
  // The header includes "kernels/table_math.h": the source tree goes on the include path, as fmpc_add_ruleset's
  // fmpc::kernels does for users. compile_generated_program's flags apply; the include path is passed through
  // CPLUS_INCLUDE_PATH so that it stays the one way generated programs are compiled.
  const std::string include_path = std::string("CPLUS_INCLUDE_PATH=") + FMPC_SOURCE_DIR;
  REQUIRE(putenv(const_cast<char*>(include_path.c_str())) == 0);
  std::string log;
  const bool compiled = testing::compile_generated_program(folder.path() / "driver.cpp", folder.path() / "driver", log);
  unsetenv("CPLUS_INCLUDE_PATH");
  INFO("compiler output:\n" << log.substr(0, 4000));
  REQUIRE(compiled);
  const std::string run = (folder.path() / "driver").string() + " " + (folder.path() / "queries.txt").string() +
                          " " + (folder.path() / "lookups.txt").string();
  REQUIRE(std::system(run.c_str()) == 0);

  std::vector<HeaderLookup> lookups(cases.size());
  std::istringstream lines(testing::read_text_file(folder.path() / "lookups.txt"));
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const std::size_t values = cases[c].queries.size() * cases[c].table.output_names.size();
    for (std::size_t k = 0; k < values; ++k) {
      std::string one, batch;
      lines >> one >> batch;
      lookups[c].one.push_back(std::strtod(one.c_str(), nullptr));
      lookups[c].batch.push_back(std::strtod(batch.c_str(), nullptr));
    }
  }
  REQUIRE(lines.good());
  return lookups;
}

bool same_bits_or_both_nan(double a, double b) { return (std::isnan(a) && std::isnan(b)) || a == b; }

// Where the query's coordinates are finite, the interpreter's inputs: each clamped to its axis (the table clamps),
// the fixed inputs at their values.
std::vector<double> interpreter_inputs(const Case& c, const std::vector<double>& query) {
  std::vector<double> inputs(c.source.inputs.size(), 0.0);
  for (const fmpc::TableFixedInput& fixed : c.table.fixed_inputs)
    for (std::size_t i = 0; i < c.source.inputs.size(); ++i)
      if (c.source.inputs[i].name == fixed.name) inputs[i] = fixed.value;
  for (std::size_t a = 0; a < c.table.axes.size(); ++a) {
    const std::vector<double>& b = c.table.axes[a].breakpoints;
    inputs[c.table.axes[a].input_index] = std::clamp(query[a], b.front(), b.back());
  }
  return inputs;
}

bool on_grid(const LookupTable& table, const std::vector<double>& query) {
  for (std::size_t a = 0; a < table.axes.size(); ++a) {
    const std::vector<double>& b = table.axes[a].breakpoints;
    const double x = std::clamp(query[a], b.front(), b.back());
    if (!std::binary_search(b.begin(), b.end(), x)) return false;
  }
  return true;
}

}  // namespace

TEST_CASE("table arrays headers compile and agree with the .fzt loader and the interpreter", "[table][arrays]") {
  const FuzzySystem tipper = load_system("tipper.fis", kTipper);
  const FuzzySystem pair = load_system("pair.fis", kTwoOutputs);
  std::vector<Case> cases;
  auto add = [&](std::string label, const FuzzySystem& source, LookupTable table) {
    Case c{std::move(label), source, std::move(table), true, {}};
    c.queries = queries_for(c.table, 17 + cases.size());
    cases.push_back(std::move(c));
  };
  // 1-D: two inputs fixed; 2-D: one fixed, refined; 3-D: nothing fixed, uniform, float values; 2 outputs with
  // a fixed point count on one axis.
  add("tipper 1-D", tipper,
      build(tipper, Bindings{{{"food", 2.0, {}}, {"mood", 0.75, {}}}, {}}, 0.05, BreakpointSpacing::Refined,
            TableValueType::Float64));
  add("tipper 2-D refined", tipper,
      build(tipper, Bindings{{{"mood", 0.25, {}}}, {}}, 0.1, BreakpointSpacing::Refined, TableValueType::Float64));
  add("tipper 3-D uniform float", tipper,
      build(tipper, Bindings{}, 1.0, BreakpointSpacing::Uniform, TableValueType::Float32));
  add("pair 2 outputs", pair,
      build(pair, Bindings{{}, {{"temperature", 25, {}}}}, 0.1, BreakpointSpacing::Refined, TableValueType::Float64));
  {
    Case six{"six axes (hand-made)", tipper, six_axis_table(), false, {}};
    six.queries = queries_for(six.table, 99);
    cases.push_back(std::move(six));
  }

  const std::vector<HeaderLookup> lookups = compile_and_run(cases);
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const Case& k = cases[c];
    INFO(k.label);
    // The loader's view of the same table, after a .fzt round trip (float32 tables come back rounded to float).
    DiagnosticList diagnostics;
    const std::optional<LookupTable> loaded = parse_fzt("t.fzt", serialize_fzt(k.table), diagnostics);
    REQUIRE(loaded);
    std::vector<const double*> pointers;
    std::vector<int> counts;
    const TableView<double> view = view_of(*loaded, pointers, counts);
    const bool as_float = k.table.value_type == TableValueType::Float32;
    double scale = 0.0;
    for (double v : loaded->values) scale = std::max(scale, std::fabs(v));
    // Double: the same code on the same values; 1e-15 of the largest value allows a compiler that contracts
    // a * b + c into an FMA in one build and not the other. Float: the header interpolates in float, the loader
    // in double on the same float values: d levels of lerps, each within a few float roundings of the scale.
    const double tolerance =
        as_float ? 4.0 * static_cast<double>(k.table.axes.size()) * 0x1.0p-24 * scale : 1e-15 * scale;
    const std::size_t m = k.table.output_names.size();
    std::size_t compared_with_interpreter = 0;
    for (std::size_t q = 0; q < k.queries.size(); ++q) {
      const std::vector<double>& query = k.queries[q];
      std::vector<double> expected(m);
      interpolate_table(view, query.data(), expected.data());
      bool finite = true, has_nan = false;
      for (double x : query) {
        finite = finite && std::isfinite(x);
        has_nan = has_nan || std::isnan(x);
      }
      std::vector<double> reference;
      if (k.from_builder && finite) reference = evaluate(k.source, interpreter_inputs(k, query)).outputs;
      for (std::size_t o = 0; o < m; ++o) {
        const double one = lookups[c].one[q * m + o], batch = lookups[c].batch[q * m + o];
        INFO("query " << q << " output " << o << ": header " << one << ", batch " << batch << ", loader "
                      << expected[o]);
        // interpolate_table (run-time axes) and interpolate_batch (compile-time axes) are the same arithmetic.
        CHECK(same_bits_or_both_nan(one, batch));
        if (has_nan) {
          CHECK(std::isnan(one));
          CHECK(std::isnan(expected[o]));
          continue;
        }
        REQUIRE(std::isfinite(one));
        CHECK(std::fabs(one - expected[o]) <= tolerance);
        if (!as_float) CHECK(std::fabs(one - expected[o]) <= 1e-15 * std::max(std::fabs(expected[o]), scale));
        if (reference.empty()) continue;
        ++compared_with_interpreter;
        const Variable& output = k.source.outputs[o];
        if (on_grid(k.table, query)) {
          // Grid points (also every clamped query at the ends) hold the specialised system's value there.
          const double grid_tolerance = 1e-12 * (output.max - output.min) + (as_float ? 0x1.0p-24 * scale : 0.0);
          CHECK(std::fabs(one - reference[o]) <= grid_tolerance);
        } else {
          // The recorded maximum error was measured on held-out points drawn like these (uniform in the grid).
          CHECK(std::fabs(one - reference[o]) <= k.table.max_error);
        }
      }
    }
    if (k.from_builder) CHECK(compared_with_interpreter > k.queries.size() / 2);
    // The hand-made table is multilinear: interpolation reproduces it, clamped at the ends.
    if (!k.from_builder)
      for (std::size_t q = 0; q < k.queries.size(); ++q) {
        const std::vector<double>& query = k.queries[q];
        if (std::any_of(query.begin(), query.end(), [](double x) { return std::isnan(x); })) continue;
        double f = 0.0;
        for (std::size_t a = 0; a < 6; ++a) {
          const std::vector<double>& b = k.table.axes[a].breakpoints;
          f += static_cast<double>(a + 1) * std::clamp(query[a], b.front(), b.back());
        }
        CHECK(lookups[c].one[q] == Approx(f).margin(1e-12));
      }
  }
}

TEST_CASE("locate_on_axis finds the binary search's cell on uniform, refined and extreme axes", "[table]") {
  // The reference: the cell with b[i] <= x < b[i + 1], the last cell at and above the upper end, the first at
  // and below the lower end (and for NaN).
  auto reference_cell = [](const std::vector<double>& b, double x) {
    if (!(x > b.front())) return 0;
    if (!(x < b.back())) return static_cast<int>(b.size()) - 2;
    return static_cast<int>(std::upper_bound(b.begin(), b.end(), x) - b.begin()) - 1;
  };
  std::vector<std::vector<double>> axes;
  for (int n : {2, 3, 9, 65, 1000}) {  // uniform, as the builder makes them (k * span / (n - 1))
    std::vector<double> b;
    for (int k = 0; k < n; ++k) b.push_back(-3.0 + 75.0 * k / (n - 1));
    axes.push_back(b);
  }
  axes.push_back({0.0, 1e-9, 2e-9, 5.0, 5.000001, 9.0, 10.0});  // refined: clustered breakpoints
  axes.push_back({-1e300, -1.0, 0.0, 1e-300, 1.0, 1e300});      // span beyond the largest double
  std::vector<double> geometric;
  for (int k = 0; k < 60; ++k) geometric.push_back(std::ldexp(1.0, k) - 1.0);
  axes.push_back(geometric);

  std::mt19937_64 random(7);
  for (const std::vector<double>& b : axes) {
    std::vector<double> xs = {kNaN, kInf, -kInf, b.front() - 1.0, b.back() * 2.0 + 1.0};
    for (std::size_t k = 0; k < b.size(); ++k) {
      xs.push_back(b[k]);
      xs.push_back(std::nextafter(b[k], kInf));
      xs.push_back(std::nextafter(b[k], -kInf));
      if (k + 1 < b.size()) xs.push_back(b[k] + 0.5 * (b[k + 1] - b[k]));
    }
    for (int i = 0; i < 2000; ++i) {
      const std::size_t k = std::uniform_int_distribution<std::size_t>(0, b.size() - 2)(random);
      xs.push_back(b[k] + std::uniform_real_distribution<double>(0.0, 1.0)(random) * (b[k + 1] - b[k]));
    }
    for (double x : xs) {
      int cell = -1;
      double fraction = -1.0;
      locate_on_axis(b.data(), static_cast<int>(b.size()), x, cell, fraction);
      INFO("axis of " << b.size() << " breakpoints from " << b.front() << ", x = " << hex_float(x));
      REQUIRE(cell == reference_cell(b, x));
      const auto i = static_cast<std::size_t>(cell);
      if (std::isnan(x) || !(x > b.front())) {
        CHECK(fraction == 0.0);
      } else if (!(x < b.back())) {
        CHECK(fraction == 1.0);
      } else {
        CHECK(fraction == (x - b[i]) / (b[i + 1] - b[i]));
        CHECK(fraction >= 0.0);
        CHECK(fraction <= 1.0);
      }
    }
  }
}

TEST_CASE("table arrays headers compile with nvcc for sm_90: every packed depth, float and double", "[table][arrays][nvcc]") {
  // The launcher instantiates both layouts' kernels; the packed reader takes lane pairs only where a group fills
  // a 32-byte sector (double from 2 axes, float from 3), so 1- and 2-axis float and 1-axis double tables take the
  // other path. The device run is the GPU tests' job (tests/gpu/evaluator).
  const std::filesystem::path nvcc = "/usr/local/cuda/bin/nvcc";
  if (!std::filesystem::exists(nvcc)) {
    WARN("skipping the nvcc compile test: " << nvcc << " is absent");
    return;
  }
  testing::ScratchFolder folder("table_arrays_nvcc");
  std::string driver = "#include <cstddef>\n";
  std::string launches;
  for (int axes = 1; axes <= 6; ++axes) {
    for (const TableValueType type : {TableValueType::Float32, TableValueType::Float64}) {
      const int outputs = axes % 2 + 1;
      LookupTable t;
      t.system_name = "grid";
      t.source_path = "grid.fis";
      t.value_type = type;
      for (int a = 0; a < axes; ++a)
        t.axes.push_back(TableAxis{"x" + std::to_string(a), "", static_cast<std::uint32_t>(a), {0.0, 1.0, 3.0}});
      for (int o = 0; o < outputs; ++o) {
        t.output_names.push_back("y" + std::to_string(o));
        t.output_units.push_back("");
      }
      t.values.assign(t.grid_points() * static_cast<std::uint64_t>(outputs), 0.5);
      t.max_error_location.assign(static_cast<std::size_t>(axes), 0.0);
      TableArraysOptions options;
      options.namespace_name =
          "t" + std::to_string(axes) + (type == TableValueType::Float32 ? "f" : "d");
      DiagnosticList diagnostics;
      testing::write_text_file(folder.path() / (options.namespace_name + ".h"),
                               write_table_arrays(t, options, diagnostics).value());
      driver += "#include \"" + options.namespace_name + ".h\"\n";
      const std::string value = type == TableValueType::Float32 ? "float" : "double";
      for (const char* layout : {"Grid", "SectorPacked"})
        launches += "  if (status == cudaSuccess) status = " + options.namespace_name +
                    "::interpolate_batch_cuda(q, reinterpret_cast<" + value + "*>(out), n, 0, fmpc::TableLayout::" +
                    layout + ");\n";
    }
  }
  driver += "cudaError_t launch_all(const double* q, void* out, std::size_t n) {\n  cudaError_t status = cudaSuccess;\n" +
            launches + "  return status;\n}\n";
  testing::write_text_file(folder.path() / "launch.cu", driver);
  const std::string command = nvcc.string() + " -std=c++17 -arch=sm_90 -O3 --Werror all-warnings -I" +
                              FMPC_SOURCE_DIR + " -c " + (folder.path() / "launch.cu").string() + " -o " +
                              (folder.path() / "launch.o").string() + " > " + (folder.path() / "nvcc.log").string() +
                              " 2>&1";
  const int status = std::system(command.c_str());
  INFO("nvcc output:\n" << testing::read_text_file(folder.path() / "nvcc.log").substr(0, 4000));
  CHECK(status == 0);
}
