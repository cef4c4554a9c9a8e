// fmpc compile: rule file + bindings -> specialised system (compiler/passes/pipeline.h) -> an evaluator header
// (--target cpp|cuda, compiler/backend/cpp/emit_cpp.h) or a lookup table (--target table: .fzt and/or arrays).
#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <sstream>

#include "compiler/backend/cpp/emit_cpp.h"
#include "compiler/backend/cpp/namespace_name.h"
#include "compiler/backend/table/lookup_table.h"
#include "compiler/backend/table/table_arrays.h"
#include "compiler/backend/table/table_builder.h"
#include "compiler/ir/content_hash.h"
#include "diagnostics/number_format.h"
#include "compiler/passes/pipeline.h"
#include "runtime/io/memory_limit.h"
#include "tools/fmpc/binding_arguments.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/progress_line.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"

namespace fmpc::cli {

namespace {

struct CompileOptions {
  std::string file;
  std::string system;
  std::string target;
  std::vector<std::string> fix;   // NAME=VALUE
  std::vector<std::string> vary;  // NAME or NAME:points
  double max_error = 0.0;         // 0 = 1% of the narrowest output range
  std::string spacing = "refined";
  std::string precision = "double";
  bool report = false;
  std::vector<std::string> dump_after;
  std::vector<std::string> outputs;
  double prune_epsilon = 0.0;
  std::uint64_t max_grid_points = 1ULL << 21;
  std::size_t held_out = 100000;
  std::uint64_t seed = 1;
  int threads = 2;
  std::string namespace_name = "fmpc_generated";
  std::string semantics = "matlab";
};

std::string with_unit(double value, const std::string& unit) {
  return format_number(value) + (unit.empty() || unit == "dimensionless" ? "" : " " + unit);
}

std::string bound_text(double bound, const std::string& note, const std::string& unit) {
  if (bound == 0.0) return "0 (" + note + ")";
  if (std::isinf(bound)) return "none known";
  return with_unit(bound, unit) + " (" + note + ")";
}

std::string output_unit(const FuzzySystem& system) {
  if (system.outputs.empty()) return "";
  const std::string& unit = system.outputs.front().unit;
  for (const Variable& output : system.outputs)
    if (output.unit != unit) return "output units";
  return unit;
}

void write_pass_report(const FuzzySystem& source, const CompileResult& compiled, std::ostream& out) {
  const std::string unit = output_unit(source);
  out << "fixed:";
  if (compiled.fixed.empty()) out << " none";
  for (std::size_t k = 0; k < compiled.fixed.size(); ++k) {
    const Variable& input = source.inputs[static_cast<std::size_t>(compiled.fixed[k].first)];
    out << (k ? ", " : " ") << input.name << " = " << with_unit(compiled.fixed[k].second, input.unit);
  }
  out << "\nvarying (in this order):";
  for (std::size_t k = 0; k < compiled.system.inputs.size(); ++k) out << (k ? ", " : " ") << compiled.system.inputs[k].name;
  out << '\n';
  for (const PassReport& report : compiled.reports) {
    out << report.pass << ": " << report.summary << "; error bound " << bound_text(report.error_bound, report.error_note, unit)
        << '\n';
    for (const std::string& line : report.details) out << "  " << line << '\n';
  }
  out << "passes: " << source.rules.size() << " -> " << compiled.system.rules.size() << " rules, error bound "
      << (compiled.error_bound() == 0.0 ? "0 (exact)" : with_unit(compiled.error_bound(), unit)) << '\n';
}

void write_table_report(const LookupTable& table, const TableBuildOptions& options, const TableBuildStatistics& stats,
                        const std::string& unit, std::ostream& out) {
  out << "table: ";
  for (std::size_t a = 0; a < table.axes.size(); ++a) out << (a ? " x " : "") << table.axes[a].breakpoints.size();
  if (table.axes.size() > 1) out << " = " << table.grid_points();
  out << " grid points, " << table.output_names.size() << " output"
      << (table.output_names.size() == 1 ? "" : "s") << ", "
      << (table.value_type == TableValueType::Float32 ? "float32" : "float64") << ", "
      << (options.spacing == BreakpointSpacing::Uniform ? "uniform" : "refined") << " breakpoints\n";
  for (const TableAxis& axis : table.axes)
    out << "  " << axis.input_name << ": " << axis.breakpoints.size() << " breakpoints in ["
        << format_number(axis.breakpoints.front()) << ", " << format_number(axis.breakpoints.back()) << "]\n";
  std::string location;
  for (std::size_t a = 0; a < table.axes.size(); ++a)
    location += (a ? ", " : "") + table.axes[a].input_name + " = " + format_number(table.max_error_location[a]);
  if (table.error_kind == TableErrorKind::Bound) {
    out << "max error " << with_unit(table.max_error, unit) << " (target " << with_unit(options.max_error, unit)
        << "): a bound, |table - interpreter| everywhere on the axes, derived cell by cell from the rules ("
        << stats.cells << " cells, " << stats.cells_bounded << " cell bounds with subdivisions, " << stats.rounds
        << " rounds); largest in the cell around " << location << "\n";
  } else {
    out << "max error " << with_unit(table.max_error, unit) << " (target " << with_unit(options.max_error, unit)
        << "): an estimate, the largest error found over " << stats.held_out_points << " held-out points (seed "
        << options.seed << ", " << stats.held_out_sets << (stats.held_out_sets == 1 ? " set" : " sets") << "), the "
        << stats.cells << " cell centres and " << stats.local_searches << " local searches (" << stats.rounds
        << " rounds), at " << location << "; not a bound: " << stats.bound_limitation << "\n";
  }
}

bool is_header_path(const std::string& path) {
  for (const char* suffix : {".h", ".hpp", ".hh", ".cuh"}) {
    const std::string s = suffix;
    if (path.size() >= s.size() && path.compare(path.size() - s.size(), s.size(), s) == 0) return true;
  }
  return false;
}

int run_compile(const CompileOptions& options) {
  LoadedRuleFile file = load_rule_file_from_disk(options.file);
  if (file.diagnostics.has_errors()) {
    print_diagnostics(file.diagnostics, file.sources, std::cerr);
    return kExitErrors;
  }
  DiagnosticList diagnostics;
  const FuzzySystem* system = select_system(file, options.system, diagnostics);
  const Bindings bindings = parse_binding_arguments(options.fix, options.vary, diagnostics);
  if (options.outputs.empty())
    diagnostics.error(kCommandLine, "no output file", {"add -o FILE"});
  if (options.target != "table" && options.outputs.size() > 1)
    diagnostics.error(kCommandLine,
                      "--target " + options.target + " writes one header; " + std::to_string(options.outputs.size()) +
                          " -o files were given");
  std::optional<CompileResult> compiled;
  if (system) {  // also after binding errors, so that every mistake is reported at once
    PipelineOptions pipeline;
    pipeline.prune_epsilon = options.prune_epsilon;
    pipeline.dump_after = options.dump_after;
    pipeline.interval_type2 = true;  // every target takes interval type-2 systems
    compiled = run_pipeline(*system, bindings, pipeline, diagnostics);
  }
  if (!compiled || diagnostics.has_errors()) {
    print_diagnostics(diagnostics, file.sources, std::cerr);
    return kExitErrors;
  }
  bool artefact_on_stdout = false;
  for (const std::string& path : options.outputs) artefact_on_stdout = artefact_on_stdout || path == "-";
  std::ostream& report_stream = artefact_on_stdout ? std::cerr : std::cout;
  for (const IrDump& dump : compiled->dumps) report_stream << "# IR after " << dump.pass << '\n' << dump.text;

  std::string read_error;
  const std::optional<std::string> bytes = read_text_file(options.file, sim::kMaxRuleFileBytes, "rule file", read_error);
  const std::uint64_t source_hash = bytes ? fnv1a64(*bytes) : 0;
  std::ostringstream report;
  if (options.report) {
    report << "compile " << system->name << " from " << options.file << " for --target " << options.target << '\n';
    write_pass_report(*system, *compiled, report);
  }

  std::vector<std::pair<std::string, std::string>> writes;  // (path, contents)
  if (options.target == "table") {
    TableBuildOptions table_options;
    table_options.max_error = options.max_error;
    if (table_options.max_error == 0.0) table_options.max_error = default_table_max_error(*system);
    table_options.spacing = options.spacing == "uniform" ? BreakpointSpacing::Uniform : BreakpointSpacing::Refined;
    table_options.value_type = options.precision == "float" ? TableValueType::Float32 : TableValueType::Float64;
    table_options.max_grid_points = options.max_grid_points;
    const sim::MemoryLimit memory = sim::memory_limit();
    table_options.memory_limit_bytes = memory.bytes;
    table_options.memory_limit_source = memory.source;
    table_options.held_out_points = options.held_out;
    table_options.seed = options.seed;
    table_options.threads = options.threads;
    table_options.evaluation.reference = options.semantics == "octave" ? Reference::Octave : Reference::Matlab;
    table_options.source_path = options.file;
    table_options.source_hash = source_hash;
    ProgressLine progress("compile");
    table_options.progress = [&](const TableBuildProgress& p) {
      // Time left, at the rate of grid points built so far, to the optimistic size estimate: a lower bound.
      const double rate = static_cast<double>(p.grid_points) / std::max(progress.elapsed_seconds(), 1e-3);
      const double left = std::max(0.0, p.estimated_grid_points - static_cast<double>(p.grid_points)) / rate;
      progress.show("round " + std::to_string(p.round) + ", " + std::to_string(p.grid_points) + " grid points (budget " +
                    std::to_string(p.budget) + "), error " + format_number(p.training_error) + " (target " +
                    format_number(p.target) + "); estimated " + format_number(std::round(p.estimated_grid_points)) +
                    " points, at least " + duration_text(left) + " left");
    };
    TableBuildStatistics stats;
    const std::optional<LookupTable> table = build_table(*system, *compiled, table_options, diagnostics, &stats);
    progress.finish();
    if (!table) {
      print_diagnostics(diagnostics, file.sources, std::cerr);
      return kExitErrors;
    }
    if (options.report) write_table_report(*table, table_options, stats, output_unit(*system), report);
    TableArraysOptions arrays;
    arrays.namespace_name = options.namespace_name;
    for (const std::string& path : options.outputs) {
      if (!is_header_path(path) && path != "-") {
        writes.emplace_back(path, serialize_fzt(*table));
      } else if (const std::optional<std::string> header = write_table_arrays(*table, arrays, diagnostics)) {
        writes.emplace_back(path, *header);
      } else {
        print_diagnostics(diagnostics, file.sources, std::cerr);
        return kExitErrors;
      }
    }
  } else {
    EmitOptions emit;
    emit.target = options.target == "cuda" ? EmitOptions::Target::Cuda : EmitOptions::Target::Cpp;
    emit.source_path = options.file;
    emit.source_hash = source_hash;
    emit.namespace_name = options.namespace_name;
    for (const auto& [index, value] : compiled->fixed) {
      const Variable& input = system->inputs[static_cast<std::size_t>(index)];
      emit.banner_notes.push_back("fixed " + input.name + " = " + with_unit(value, input.unit));
    }
    for (const PassReport& pass : compiled->reports) emit.banner_notes.push_back(pass.pass + ": " + pass.summary);
    if (!options.outputs.empty() && options.outputs.front() != "-") emit.header_path = options.outputs.front();
    const std::optional<std::string> header = emit_evaluator(compiled->system, emit, diagnostics);
    if (!header) {
      print_diagnostics(diagnostics, file.sources, std::cerr);
      return kExitErrors;
    }
    writes.emplace_back(options.outputs.front(), *header);
  }
  print_diagnostics(diagnostics, file.sources, std::cerr);
  std::string error;
  if (!write_text_files_atomically(writes, error)) {  // all or none (-o t.fzt -o missing/t.h writes neither)
    std::cerr << "fmpc compile: error: " << error << '\n';
    return kExitErrors;
  }
  for (const auto& write : writes)
    if (options.report && write.first != "-") report << "wrote " << write.first << '\n';
  report_stream << report.str();
  return kExitOk;
}

}  // namespace

void register_compile_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<CompileOptions>();
  CLI::App* command = app.add_subcommand(
      "compile",
      "Specialise a rule file for fixed inputs and compile it into an evaluator header (--target cpp|cuda) or a\n"
      "lookup table over the varying inputs (--target table: .fzt, or C++/CUDA arrays for -o NAME.h).\n"
      "Inputs neither fixed nor varied vary. docs/compiler.md has the details.");
  command->add_option("file", options->file, "Rule file (fmpc or MATLAB .fis)")->required();
  command->add_option("--target", options->target, "What to produce")
      ->required()
      ->check(CLI::IsMember({"cpp", "cuda", "table"}));
  command->add_option("--system", options->system, "Which system of the file to compile");
  command->add_option("--fix", options->fix, "Fold an input in at a value: NAME=VALUE (repeatable)");
  command->add_option("--vary", options->vary,
                      "Vary an input: NAME, or NAME:POINTS to fix its table axis at POINTS uniform breakpoints");
  command
      ->add_option("--max-error", options->max_error,
                   "Largest interpolation error a table may have, absolute, in output units (default: 1% of the "
                   "narrowest output range)")
      ->check(CLI::PositiveNumber);
  command->add_option("--spacing", options->spacing, "Table breakpoints: uniform (nested doubling) or refined")
      ->check(CLI::IsMember({"uniform", "refined"}));
  command->add_option("--precision", options->precision, "Table value type")
      ->check(CLI::IsMember({"float", "double"}));
  command->add_flag("--report", options->report, "Print what each pass removed, its error bound, and the table built");
  command->add_option("--dump-after", options->dump_after,
                      "Print the IR after a pass: specialize, prune_rules, fuse_consequents, drop_dead_terms, all");
  command->add_option("-o,--output", options->outputs,
                      "Output file; for --target table: .fzt, or .h/.hpp/.cuh for arrays (both: give -o twice)")
      ->required();
  command
      ->add_option("--prune-epsilon", options->prune_epsilon,
                   "Also remove rules whose firing strength is provably below this (type-1 Mamdani, max aggregation; "
                   "refused on interval type-2 systems); the report states the error bound it costs")
      ->check(CLI::Range(0.0, 1.0));
  command->add_option("--max-grid-points", options->max_grid_points, "Table budget: most grid points")
      ->check(CLI::Range(static_cast<std::uint64_t>(2), kMaxFztValues));
  command->add_option("--held-out", options->held_out, "Held-out points the table's error is measured on")
      ->check(CLI::Range(static_cast<std::size_t>(100000), static_cast<std::size_t>(100000000)));
  command->add_option("--seed", options->seed, "Seed of the training and held-out points");
  command->add_option("--threads", options->threads, "Threads building and measuring the table")
      ->check(CLI::Range(1, 256));
  command->add_option("--namespace", options->namespace_name, "C++ namespace of generated headers")
      ->check([](const std::string& name) {
        const std::optional<std::string> problem = namespace_name_problem(name);
        return problem ? "it cannot name the generated code's namespace: " + *problem +
                             "; use identifiers joined by '::', e.g. scene::liver"
                       : std::string();
      });
  command
      ->add_option("--semantics", options->semantics,
                   "Whose numbers the table reproduces where MATLAB and Octave differ (docs/numerics.md)")
      ->check(CLI::IsMember({"matlab", "octave"}));
  command->callback([options, &exit_code] { exit_code = run_compile(*options); });
}

}  // namespace fmpc::cli
