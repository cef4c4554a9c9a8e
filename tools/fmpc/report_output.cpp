#include "tools/fmpc/report_output.h"

#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>

#include "runtime/io/atomic_file.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/text_files.h"

namespace fmpc::cli {

EvaluationOptions ReportOptions::evaluation() const {
  EvaluationOptions options;
  options.reference = semantics == "octave" ? Reference::Octave : Reference::Matlab;
  return options;
}

void add_report_options(CLI::App& command, ReportOptions& options, const std::string& table_help,
                        const std::string& plots_help) {
  command.add_option("--system", options.system, "Which system of the file");
  command.add_option("--column", options.columns, "Read an input from another column: INPUT=COLUMN (repeatable)");
  command.add_option("-o,--output,--markdown", options.markdown, "Write the markdown report to this file too")
      ->allow_extra_args(false);
  command.add_option("--table", options.table, table_help);
  command.add_option("--plots", options.plots, plots_help);
  command.add_option("--semantics", options.semantics, "matlab or octave (docs/numerics.md)")
      ->check(CLI::IsMember({"matlab", "octave"}));
}

int write_report(const ReportOptions& options, const std::string& markdown_file, const std::string& command, const std::string& markdown,
                 const std::function<std::string()>& table,
                 const std::function<std::vector<std::pair<std::string, std::string>>()>& plots) {
  std::vector<std::pair<std::string, std::string>> writes;
  if (!markdown_file.empty()) writes.emplace_back(markdown_file, markdown);
  if (!options.table.empty()) writes.emplace_back(options.table, table());
  if (!options.plots.empty()) {
    DiagnosticList folder;
    if (!sim::ensure_directory(options.plots, folder)) {
      print_diagnostics(folder, SourceFiles{}, std::cerr);
      return kExitErrors;
    }
    for (auto& [name, png] : plots()) writes.emplace_back((std::filesystem::path(options.plots) / name).string(), png);
  }
  std::string error;
  if (!write_text_files_atomically(writes, error)) {
    std::cerr << "fmpc " << command << ": error: " << error << "\n";
    return kExitErrors;
  }
  std::cout << markdown;
  return kExitOk;
}

}  // namespace fmpc::cli
