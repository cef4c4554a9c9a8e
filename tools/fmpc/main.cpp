// fmpc: the command-line front of the toolkit. The only place that parses argv, prints and picks exit codes.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "tools/fmpc/commands.h"
#include "tools/fmpc/rule_file_session.h"

int main(int argc, char** argv) {
  CLI::App app{"fmpc: fuzzy mass-spring parameter compiler (rule files -> evaluators, tables, simulations)"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "fmpc 0.1.0");
  int exit_code = fmpc::cli::kExitOk;
  fmpc::cli::register_check_command(app, exit_code);
  fmpc::cli::register_fmt_command(app, exit_code);
  fmpc::cli::register_eval_command(app, exit_code);
  fmpc::cli::register_convert_command(app, exit_code);
  fmpc::cli::register_simulate_command(app, exit_code);
  fmpc::cli::register_compile_command(app, exit_code);
  fmpc::cli::register_plot_command(app, exit_code);
  fmpc::cli::register_trade_command(app, exit_code);
  fmpc::cli::register_thesis_benchmark_command(app, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : fmpc::cli::kExitErrors;
  } catch (const std::exception& e) {
    std::cerr << "fmpc: internal error: " << e.what() << "\nplease report this with the input that caused it\n";
    return 70;  // EX_SOFTWARE: a bug in fmpc, not in the user's input
  }
  return exit_code;
}
