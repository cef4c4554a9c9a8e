// fmpc: the command-line front of the toolkit. The only place that parses argv, prints and picks exit codes.
#include <CLI/CLI.hpp>
#include <exception>
#include <iostream>

#include "tools/fmpc/commands.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/warning_policy.h"

int main(int argc, char** argv) {
  // Named here, not from argv[0], so that help never shows where the binary was built.
  CLI::App app{"fmpc: fuzzy mass-spring parameter compiler (rule files -> evaluators, tables, simulations)", "fmpc"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "fmpc 0.1.0");
  // Every option's default shows in --help.
  app.option_defaults()->always_capture_default();
  int exit_code = fmpc::cli::kExitOk;
  fmpc::cli::register_check_command(app, exit_code);
  fmpc::cli::register_fmt_command(app, exit_code);
  fmpc::cli::register_eval_command(app, exit_code);
  fmpc::cli::register_convert_command(app, exit_code);
  fmpc::cli::register_simulate_command(app, exit_code);
  fmpc::cli::register_mesh_command(app, exit_code);
  fmpc::cli::register_compile_command(app, exit_code);
  fmpc::cli::register_plot_command(app, exit_code);
  fmpc::cli::register_trade_command(app, exit_code);
  fmpc::cli::register_thesis_benchmark_command(app, exit_code);
  fmpc::cli::register_tune_command(app, exit_code);
  fmpc::cli::register_lsp_command(app, exit_code);
  fmpc::cli::register_validate_command(app, exit_code);
  fmpc::cli::register_diff_command(app, exit_code);
  fmpc::cli::register_studio_command(app, exit_code);
  const char* exit_rule =
      "Exit status (every command, docs/cli.md): 0 done; 1 done, but warnings made errors by -Werror (or files\n"
      "`fmt --check` would change); 2 errors in the input or the command line; 70 an internal error in fmpc.";
  app.footer(exit_rule);
  for (CLI::App* command : app.get_subcommands([](CLI::App*) { return true; })) {
    fmpc::cli::add_warning_options(*command);
    command->footer(exit_rule);
    for (CLI::Option* option : command->get_options()) {
      // An empty list has no default worth showing ("=[]").
      if (option->get_default_str() == "[]") option->default_str("");
      // An empty value given on purpose is a mistake (`-o ''`, `--csv "$UNSET"`): an empty path once sent
      // simulate's outputs to the default folder and trade's CSV nowhere, silently. Only compiler flags may be
      // empty.
      if (option->get_items_expected_max() > 0 && option->get_name() != "--cxx-flags")
        option->check([](const std::string& value) {
          return value.empty() ? std::string("an empty value names nothing: give one, or leave the option out")
                               : std::string();
        });
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : fmpc::cli::kExitErrors;
  } catch (const std::exception& e) {
    std::cerr << "fmpc: internal error: " << e.what() << "\nplease report this with the input that caused it\n";
    return 70;  // EX_SOFTWARE: a bug in fmpc, not in the user's input
  }
  // One rule for every command (docs/cli.md): warnings that -Werror turned into errors make a finished command exit 1.
  if (exit_code == fmpc::cli::kExitOk && fmpc::cli::promoted_warning_count() > 0) return fmpc::cli::kExitWarnings;
  return exit_code;
}
