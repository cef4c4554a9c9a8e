#include <CLI/CLI.hpp>
#include <iostream>

#include "tools/fmpc/commands.h"
#include "tools/fmpc/rule_file_session.h"
#include "runtime/io/rule_file_input.h"
#include "tools/fmpc/warning_policy.h"

namespace fmpc::cli {

namespace {

struct CheckOptions {
  std::vector<std::string> files;
  bool werror = false;
  bool no_lint = false;
  double coverage_threshold = LintOptions{}.coverage_threshold;
};

int run_check(const CheckOptions& options) {
  if (options.werror) process_warning_policy().all_errors = true;
  bool any_error = false;
  for (const std::string& path : options.files) {
    LoadedRuleFile file = load_rule_file_from_disk(path);
    if (!options.no_lint) {
      LintOptions lint_options;
      lint_options.coverage_threshold = options.coverage_threshold;
      lint_rule_file(file, lint_options);
    }
    print_diagnostics(file.diagnostics, file.sources, std::cerr);
    any_error = any_error || file.diagnostics.has_errors();
  }
  // --werror is -Werror (warning_policy.h): the warnings were printed as errors and main() exits 1.
  return any_error ? kExitErrors : kExitOk;
}

}  // namespace

void register_check_command(CLI::App& app, int& exit_code) {
  auto options = std::make_shared<CheckOptions>();
  CLI::App* command =
      app.add_subcommand("check",
                         "Check rule files (fmpc or MATLAB .fis): every error and lint warning, compiler-style.");
  command->add_option("files", options->files, "Rule files to check")->required();
  command->add_flag("--werror", options->werror, "The same as -Werror: warnings print as errors and the exit status is 1");
  command->add_flag("--no-lint", options->no_lint, "Report errors only");
  command
      ->add_option("--coverage-threshold", options->coverage_threshold,
                   "Firing strength below which a point counts as a coverage hole")
      ->check(CLI::Range(0.0, 1.0));
  command->callback([options, &exit_code] { exit_code = run_check(*options); });
}

}  // namespace fmpc::cli
