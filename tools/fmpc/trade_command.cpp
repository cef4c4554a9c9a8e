// fmpc trade FILE [--fix NAME=VALUE] [--vary NAME]: what speed costs in accuracy, measured on this machine.
// Every variant evaluates the same seeded held-out points of the specialised system and is compared with the
// interpreter in `samples exact` mode (interval type-2 systems: the interpreter as the file samples it, the crisp
// output (yl + yr) / 2): the interpreter itself (exact, and sampled as the rule file says), the
// generated C++ evaluator in double and float (compiled at run time and loaded with dlopen), and uniform lookup
// tables at several resolutions. docs/trade.md describes every column.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "compiler/backend/cpp/emit_cpp.h"
#include "compiler/backend/table/lookup_table.h"
#include "compiler/eval/interpreter.h"
#include "compiler/ir/content_hash.h"
#include "diagnostics/number_format.h"
#include "compiler/passes/pipeline.h"
#include "kernels/table_math.h"
#include "tools/fmpc/binding_arguments.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/compiled_evaluator.h"
#include "tools/fmpc/progress_line.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/scene_trade_command.h"
#include "tools/fmpc/text_files.h"
#include "tools/plot/pareto_plot.h"

namespace fmpc::cli {

namespace {

// The largest table trade builds: its grid inputs and values take (inputs + outputs) x 8 bytes per point
// (docs/limits.md).
constexpr std::uint64_t kMaxTradeGridPoints = std::uint64_t{1} << 24;

struct TradeOptions {
  std::string file;
  std::string system;
  std::vector<std::string> fix;
  std::vector<std::string> vary;
  std::size_t points = 2000;
  std::uint64_t seed = 1;
  std::vector<int> resolutions{3, 5, 9, 17, 33, 65};
  std::uint64_t max_grid_points = 1ULL << 22;
  double min_seconds = 0.2;
  std::string compiler;
  std::string flags = "-std=c++17 -O2";
  std::string csv;
  std::string markdown;
  std::string plot;
};

struct Row {
  std::string variant;
  std::string detail;
  double max_error = 0.0;
  double rms_error = 0.0;
  double evaluations_per_second = 0.0;
  double memory_bytes = 0.0;
  std::string memory_note;
};

// CPU time of this thread: on a shared machine wall time counts the other processes too.
double thread_seconds() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

// Runs `pass` (one evaluation of all the points) until `min_seconds` of CPU time have gone, at least once;
// returns evaluations per CPU second.
template <typename Pass>
double measure_rate(std::size_t points, double min_seconds, Pass pass) {
  std::size_t passes = 0;
  const double start = thread_seconds();
  double elapsed = 0.0;
  do {
    pass();
    ++passes;
    elapsed = thread_seconds() - start;
  } while (elapsed < min_seconds);
  return static_cast<double>(points * passes) / std::max(elapsed, 1e-9);
}

struct ErrorStats {
  double max = 0.0;
  double rms = 0.0;
};

// |got - reference| over every point and output; a NaN on one side only is an infinite error.
template <typename T>
ErrorStats error_against(const std::vector<double>& reference, const std::vector<T>& got) {
  ErrorStats stats;
  double sum = 0.0;
  for (std::size_t k = 0; k < reference.size(); ++k) {
    const double value = static_cast<double>(got[k]);
    double e = 0.0;
    if (std::isnan(reference[k]) || std::isnan(value)) {
      e = std::isnan(reference[k]) && std::isnan(value) ? 0.0 : std::numeric_limits<double>::infinity();
    } else {
      e = std::fabs(value - reference[k]);
    }
    stats.max = std::max(stats.max, e);
    sum += e * e;
  }
  stats.rms = reference.empty() ? 0.0 : std::sqrt(sum / static_cast<double>(reference.size()));
  return stats;
}

Row make_row(const std::string& variant, const std::string& detail, const ErrorStats& error) {
  Row row;
  row.variant = variant;
  row.detail = detail;
  row.max_error = error.max;
  row.rms_error = error.rms;
  return row;
}

std::string number(double value, int digits = 3) {
  if (std::isinf(value)) return "inf";
  char text[32];
  std::snprintf(text, sizeof text, "%.*g", digits, value);
  return text;
}

std::string bytes_text(double bytes) {
  if (bytes >= 1024.0 * 1024.0) return number(bytes / (1024.0 * 1024.0)) + " MiB";
  if (bytes >= 1024.0) return number(bytes / 1024.0) + " KiB";
  return number(bytes) + " B";
}

// What the interpreter keeps per system: MF parameters, the clauses, and the sampled output terms.
double interpreter_bytes(const FuzzySystem& system) {
  double bytes = 0.0;
  for (const auto* variables : {&system.inputs, &system.outputs})
    for (const Variable& v : *variables)
      for (const Term& t : v.terms) {
        bytes += 8.0 * static_cast<double>(t.mf.params.size());
        if (t.footprint) bytes += 8.0 * static_cast<double>(2 + t.footprint->lower.params.size());
      }
  for (const Rule& r : system.rules)
    bytes += static_cast<double>(sizeof(Clause) * (r.antecedent.size() + r.consequent.size()));
  // Type-2 systems keep both ends of every sampled term and of the aggregate.
  const double ends = system.interval_type2 ? 2.0 : 1.0;
  if (system.type == SystemType::Mamdani && system.samples > 0)
    for (const Variable& v : system.outputs)
      bytes += ends * 8.0 * static_cast<double>(system.samples) * static_cast<double>(v.terms.size() + 1);
  return bytes;
}

std::string output_unit(const FuzzySystem& system) {
  std::string unit;
  for (const Variable& output : system.outputs) {
    if (output.unit.empty()) continue;
    if (unit.empty()) unit = output.unit;
    else if (unit != output.unit) return "output units";
  }
  return unit;
}

int run_trade(const TradeOptions& options) {
  LoadedRuleFile file = load_rule_file_from_disk(options.file);
  if (file.diagnostics.has_errors()) {
    print_diagnostics(file.diagnostics, file.sources, std::cerr);
    return kExitErrors;
  }
  DiagnosticList diagnostics;
  const FuzzySystem* source = select_system(file, options.system, diagnostics);
  const Bindings bindings = parse_binding_arguments(options.fix, options.vary, diagnostics);
  std::optional<CompileResult> compiled;
  PipelineOptions pipeline;
  pipeline.interval_type2 = true;
  if (source) compiled = run_pipeline(*source, bindings, pipeline, diagnostics);
  if (!compiled || diagnostics.has_errors()) {
    print_diagnostics(diagnostics, file.sources, std::cerr);
    return kExitErrors;
  }
  print_diagnostics(diagnostics, file.sources, std::cerr);
  const FuzzySystem& system = compiled->system;
  const std::size_t d = system.inputs.size();
  const std::size_t m = system.outputs.size();
  const std::size_t n = options.points;
  // Every requested table is measured or the command fails: a resolution whose grid is over budget is an error
  // naming it, not a row left out.
  for (const int resolution : options.resolutions) {
    double grid = 1.0;
    for (std::size_t i = 0; i < d; ++i) grid *= resolution;
    if (d > 0 && grid > static_cast<double>(options.max_grid_points)) {
      std::cerr << "fmpc trade: error: --resolutions " << resolution << " on " << d << " varying input"
                << (d == 1 ? "" : "s") << " makes " << format_number(grid) << " grid points, above --max-grid-points "
                << options.max_grid_points << "; lower the resolution or raise --max-grid-points (at most "
                << kMaxTradeGridPoints << ")\n";
      return kExitErrors;
    }
  }

  // Held-out points, uniform over the varying inputs' ranges.
  std::mt19937_64 random(options.seed);
  std::vector<double> points(n * d);
  for (std::size_t p = 0; p < n; ++p)
    for (std::size_t i = 0; i < d; ++i) {
      const double u = static_cast<double>(random() >> 11) * 0x1.0p-53;
      points[p * d + i] = system.inputs[i].min + u * (system.inputs[i].max - system.inputs[i].min);
    }
  const auto point = [&](std::size_t p) {
    return std::vector<double>(points.begin() + static_cast<std::ptrdiff_t>(p * d),
                               points.begin() + static_cast<std::ptrdiff_t>((p + 1) * d));
  };

  std::vector<Row> rows;
  // Every variant measures for at least --min-seconds: with the compile, a run takes seconds to minutes.
  const std::size_t planned = 1 + (system.type == SystemType::Mamdani && !system.interval_type2 && system.samples > 0) +
                              2 + (d > 0 ? options.resolutions.size() : 0);
  ProgressLine progress("trade");
  const auto measured = [&] { progress.show_fraction(rows.size(), planned, "variant"); };
  // Within an interpreter variant (millions of points take minutes): its first pass is half of it, the timed
  // passes the other half.
  const auto interpreting = [&](std::size_t p, bool timed) {
    if (p % 4096 == 0)
      progress.show_fraction(static_cast<double>(rows.size()) + (timed ? 0.5 : 0.0) +
                                 0.5 * static_cast<double>(p) / static_cast<double>(n),
                             static_cast<double>(planned), "variant");
  };
  // The reference: the interpreter with `samples exact` (Mamdani); a Sugeno system has no sampling to remove, and an
  // interval type-2 Mamdani system is type-reduced over its samples (there is no exact mode): its reference is the
  // interpreter as the file says, and the sampled row below is left out.
  FuzzySystem exact_system = system;
  const bool exact_mode = exact_system.type == SystemType::Mamdani && !exact_system.interval_type2;
  if (exact_mode) exact_system.samples = 0;
  std::vector<double> reference(n * m);
  {
    Interpreter exact(exact_system);
    for (std::size_t p = 0; p < n; ++p) {
      interpreting(p, false);
      const Evaluation e = exact.evaluate(point(p));
      for (std::size_t o = 0; o < m; ++o) reference[p * m + o] = e.outputs[o];
    }
    Row row = make_row("interpreter",
                       exact_mode ? "samples exact (reference)"
                                  : system.interval_type2 ? "interval type-2, " + std::string(to_string(system.type_reduction)) + " (reference)"
                                                          : "reference",
                       ErrorStats{});
    row.evaluations_per_second = measure_rate(n, options.min_seconds, [&] {
      for (std::size_t p = 0; p < n; ++p) {
        interpreting(p, true);
        exact.evaluate(point(p));
      }
    });
    row.memory_bytes = interpreter_bytes(exact_system);
    row.memory_note = "IR data";
    rows.push_back(row);
    measured();
  }
  if (exact_mode && system.samples > 0) {
    Interpreter sampled(system);
    std::vector<double> got(n * m);
    for (std::size_t p = 0; p < n; ++p) {
      interpreting(p, false);
      const Evaluation e = sampled.evaluate(point(p));
      for (std::size_t o = 0; o < m; ++o) got[p * m + o] = e.outputs[o];
    }
    const ErrorStats error = error_against(reference, got);
    Row row = make_row("interpreter", std::to_string(system.samples) + " samples", error);
    row.evaluations_per_second = measure_rate(n, options.min_seconds, [&] {
      for (std::size_t p = 0; p < n; ++p) {
        interpreting(p, true);
        sampled.evaluate(point(p));
      }
    });
    row.memory_bytes = interpreter_bytes(system);
    row.memory_note = "IR data + sampled terms";
    rows.push_back(row);
    measured();
  }

  // The generated evaluator, compiled as a user would compile it.
  std::unique_ptr<CompiledEvaluator> evaluator;
  std::string compiler = options.compiler;
  if (compiler.empty()) compiler = std::getenv("CXX") ? std::getenv("CXX") : "c++";
  EmitOptions emit;
  emit.source_path = options.file;
  emit.namespace_name = "fmpc_trade";
  std::string read_error;
  if (const auto bytes = read_text_file(options.file, sim::kMaxRuleFileBytes, "rule file", read_error)) emit.source_hash = fnv1a64(*bytes);
  DiagnosticList emit_diagnostics;
  const std::optional<std::string> header = emit_evaluator(system, emit, emit_diagnostics);
  if (!header) {
    print_diagnostics(emit_diagnostics, file.sources, std::cerr);
    std::cerr << "fmpc trade: the compiled C++ and table rows are left out\n";
  } else {
    std::string error;
    progress.show("compiling the generated evaluator (" + compiler + " " + options.flags + ")");
    evaluator = CompiledEvaluator::build(*header, emit.namespace_name, compiler, options.flags, error);
    if (!evaluator) std::cerr << "fmpc trade: " << error << "\nfmpc trade: the compiled C++ and table rows are left out\n";
  }
  if (evaluator) {
    std::vector<double> got(n * m);
    evaluator->batch_double()(points.data(), got.data(), n);
    ErrorStats error = error_against(reference, got);
    Row row = make_row("compiled C++", "double, " + options.flags, error);
    row.evaluations_per_second =
        measure_rate(n, options.min_seconds, [&] { evaluator->batch_double()(points.data(), got.data(), n); });
    row.memory_bytes = static_cast<double>(evaluator->shared_object_bytes());
    row.memory_note = "shared object";
    rows.push_back(row);
    measured();

    std::vector<float> points_float(points.begin(), points.end()), got_float(n * m);
    evaluator->batch_float()(points_float.data(), got_float.data(), n);
    error = error_against(reference, got_float);
    row = make_row("compiled C++", "float, " + options.flags, error);
    row.evaluations_per_second = measure_rate(n, options.min_seconds, [&] {
      evaluator->batch_float()(points_float.data(), got_float.data(), n);
    });
    row.memory_bytes = static_cast<double>(evaluator->shared_object_bytes());
    row.memory_note = "shared object";
    rows.push_back(row);
    measured();

    // Uniform tables, their grid values from the compiled double evaluator (which agrees with the sampled
    // interpreter to 1e-12 of the range; tests/unit/emit_cpp_test.cpp).
    for (const int resolution : options.resolutions) {
      double grid = 1.0;
      for (std::size_t i = 0; i < d; ++i) grid *= resolution;
      if (d == 0) continue;  // nothing varies: no table to measure
      LookupTable table;
      table.axes.resize(d);
      for (std::size_t i = 0; i < d; ++i) {
        table.axes[i].input_name = system.inputs[i].name;
        for (int k = 0; k < resolution; ++k)
          table.axes[i].breakpoints.push_back(system.inputs[i].min + (system.inputs[i].max - system.inputs[i].min) *
                                                                         k / (resolution - 1));
      }
      const auto grid_points = static_cast<std::size_t>(grid);
      std::vector<double> grid_inputs(grid_points * d);
      for (std::size_t g = 0; g < grid_points; ++g) {
        std::size_t rest = g;
        for (std::size_t i = d; i-- > 0;) {  // last axis fastest (kernels/table_math.h)
          grid_inputs[g * d + i] = table.axes[i].breakpoints[rest % static_cast<std::size_t>(resolution)];
          rest /= static_cast<std::size_t>(resolution);
        }
      }
      table.values.resize(grid_points * m);
      evaluator->batch_double()(grid_inputs.data(), table.values.data(), grid_points);
      table.output_names.resize(m);
      std::vector<const double*> breakpoint_pointers;
      std::vector<int> counts;
      const TableView<double> view = view_of(table, breakpoint_pointers, counts);
      std::vector<double> got_table(n * m);
      const auto lookup_all = [&] {
        for (std::size_t p = 0; p < n; ++p) interpolate_table(view, points.data() + p * d, got_table.data() + p * m);
      };
      lookup_all();
      error = error_against(reference, got_table);
      std::string shape;
      for (std::size_t i = 0; i < d; ++i) shape += (i ? "x" : "") + std::to_string(resolution);
      row = make_row("table", shape + " uniform, double", error);
      row.evaluations_per_second = measure_rate(n, options.min_seconds, lookup_all);
      row.memory_bytes = 8.0 * static_cast<double>(table.values.size() + static_cast<std::size_t>(resolution) * d);
      row.memory_note = "values + breakpoints";
      rows.push_back(row);
      measured();
    }
  }

  progress.finish();
  const std::string unit = output_unit(system);
  std::ostringstream markdown;
  markdown << "# fmpc trade: " << system.name << " (" << options.file << ")\n\n";
  markdown << "Varying: ";
  for (std::size_t i = 0; i < d; ++i) markdown << (i ? ", " : "") << system.inputs[i].name;
  markdown << (d == 0 ? "nothing" : "") << ". Fixed:";
  if (compiled->fixed.empty()) markdown << " none";
  for (const auto& [index, value] : compiled->fixed)
    markdown << ' ' << source->inputs[static_cast<std::size_t>(index)].name << " = " << format_number(value) << ';';
  markdown << "\n" << n << " held-out points (seed " << options.seed
           << "); errors against the interpreter "
           << (system.interval_type2 ? "as the file samples it (interval type-2: the crisp output (yl + yr) / 2 that "
                                                   "`fmpc eval` prints)"
                                                 : "with `samples exact`")
           << ", in " << (unit.empty() ? "output units" : unit)
           << ", maximum and RMS over points and outputs; speed in evaluations per CPU second on one core.\n\n";
  markdown << "| variant | detail | max error | RMS error | evaluations/s | memory |\n";
  markdown << "| --- | --- | ---: | ---: | ---: | --- |\n";
  std::ostringstream csv;
  csv << "variant,detail,max_error,rms_error,evaluations_per_second,memory_bytes,memory_note\n";
  for (const Row& row : rows) {
    markdown << "| " << row.variant << " | " << row.detail << " | " << number(row.max_error) << " | "
             << number(row.rms_error) << " | " << number(row.evaluations_per_second) << " | "
             << bytes_text(row.memory_bytes) << " (" << row.memory_note << ") |\n";
    csv << row.variant << ",\"" << row.detail << "\"," << format_number(row.max_error) << ','
        << format_number(row.rms_error) << ',' << format_number(row.evaluations_per_second) << ','
        << format_number(row.memory_bytes) << ",\"" << row.memory_note << "\"\n";
  }
  std::cout << markdown.str();

  std::vector<std::pair<std::string, std::string>> writes;  // all or none
  if (!options.markdown.empty()) writes.emplace_back(options.markdown, markdown.str());
  if (!options.csv.empty()) writes.emplace_back(options.csv, csv.str());
  if (!options.plot.empty()) {
    plot::TradePlot figure;
    figure.error_unit = unit;
    figure.title = {"fmpc trade: " + system.name,
                    std::to_string(n) + " held-out points (seed " + std::to_string(options.seed) +
                        "), errors against the exact interpreter, speed on one core of this machine"};
    for (const Row& row : rows)
      if (row.evaluations_per_second > 0 && std::isfinite(row.max_error))
        figure.points.push_back({row.variant + " " + row.detail.substr(0, row.detail.find(',')),
                                 row.evaluations_per_second, row.max_error, row.variant});
    writes.emplace_back(options.plot, plot::render_trade_plot(figure, plot::image_format_for(options.plot)));
  }
  std::string error;
  if (!write_text_files_atomically(writes, error)) {
    std::cerr << "fmpc trade: error: " << error << '\n';
    return kExitErrors;
  }
  return kExitOk;
}

}  // namespace

void register_trade_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<TradeOptions>();
  CLI::App* command = app.add_subcommand(
      "trade",
      "Measure what speed costs in accuracy on this machine: the interpreter (exact and sampled), the generated\n"
      "C++ evaluator in double and float (compiled now with the system compiler and loaded), and lookup tables at\n"
      "several resolutions, each against the exact interpreter on the same held-out points. Prints markdown;\n"
      "--csv, --markdown and --plot (PNG) write files. docs/trade.md explains the columns.");
  command->add_option("file", options->file, "Rule file (fmpc or MATLAB .fis), or a scene (.yaml: docs/trade.md)")->required();
  command->add_option("--system", options->system, "Which system of the file");
  command->add_option("--fix", options->fix, "Fold an input in at a value: NAME=VALUE (repeatable)");
  command->add_option("--vary", options->vary, "Vary an input: NAME (the inputs not fixed vary)");
  command->add_option("--points", options->points, "Held-out points")->check(CLI::Range(1, 10000000));
  command->add_option("--seed", options->seed, "Seed of the held-out points");
  command->add_option("--resolutions", options->resolutions, "Table breakpoints per axis (uniform), e.g. 5,9,17")
      ->delimiter(',')
      ->check(CLI::Range(2, 1 << 24));
  command->add_option("--max-grid-points", options->max_grid_points, "Largest table measured")
      ->check(CLI::Range(std::uint64_t{2}, kMaxTradeGridPoints));
  command->add_option("--min-seconds", options->min_seconds, "CPU time each speed measurement runs at least")
      ->check(CLI::Range(0.0, 60.0));
  command->add_option("--cxx", options->compiler, "C++ compiler for the generated evaluator (default: $CXX or c++)");
  command->add_option("--cxx-flags", options->flags, "Its flags (default: -std=c++17 -O2)");
  command->add_option("--csv", options->csv, "Write the rows as CSV");
  command->add_option("-o,--output,--markdown", options->markdown, "Write the markdown table (also printed)");
  command->add_option("--plot", options->plot, "Write the Pareto plot (PNG, or SVG for NAME.svg)");
  // A scene file (.yaml) is traded as a simulation (tools/fmpc/scene_trade_command.cpp).
  const auto scene_arguments = add_scene_trade_options(*command);
  command->callback([options, scene_arguments, command, &exit_code] {
    if (is_scene_path(options->file))
      exit_code = run_scene_trade(*command, options->file, options->csv, options->markdown, options->plot,
                                  *scene_arguments);
    else if ((exit_code = refuse_scene_options(*command, options->file)) == kExitOk)
      exit_code = run_trade(*options);
  });
}

}  // namespace fmpc::cli
