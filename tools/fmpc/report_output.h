#pragma once
// What `fmpc validate` and `fmpc diff` share on the command line: the options that choose their outputs
// (-o/--output or --markdown, --table, --plots, --column, --system, --semantics) and writing the report: every file
// or none, then the markdown on stdout.
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "compiler/eval/interpreter.h"

namespace CLI {
class App;
}

namespace fmpc::cli {

struct ReportOptions {
  std::string system;
  std::vector<std::string> columns;  // INPUT=COLUMN
  std::vector<std::string> markdown;  // -o/--output, --markdown: read with output_file_argument (patient_data.h)
  std::string table;
  std::string plots;
  std::string semantics = "matlab";

  EvaluationOptions evaluation() const;
};

// Registers the options; `table_help` and `plots_help` say what those two write for this command.
void add_report_options(CLI::App& command, ReportOptions& options, const std::string& table_help,
                        const std::string& plots_help);

// Writes the markdown (into `markdown_file`, from -o/--output, when not empty), the table (--table) and the pictures
// (into --plots, created when missing), all or none, then prints the markdown; `table` and `plots` (file name, PNG) are only made when asked for. Returns the
// exit status, with a message naming `command` on failure.
int write_report(const ReportOptions& options, const std::string& markdown_file, const std::string& command, const std::string& markdown,
                 const std::function<std::string()>& table,
                 const std::function<std::vector<std::pair<std::string, std::string>>()>& plots);

}  // namespace fmpc::cli
