#pragma once
// Each command registers itself on the CLI11 app; its callback stores the process exit code in `exit_code`.
#include "diagnostics/source_range.h"

namespace CLI {
class App;
}

namespace fmpc::cli {

// Where an error in the command line's options is reported.
inline const SourceRange kCommandLine{"command line", 0, 0, 0, 0};

void register_check_command(CLI::App& app, int& exit_code);
void register_fmt_command(CLI::App& app, int& exit_code);
void register_eval_command(CLI::App& app, int& exit_code);
void register_convert_command(CLI::App& app, int& exit_code);
void register_simulate_command(CLI::App& app, int& exit_code);
void register_mesh_command(CLI::App& app, int& exit_code);
void register_compile_command(CLI::App& app, int& exit_code);
void register_plot_command(CLI::App& app, int& exit_code);
void register_trade_command(CLI::App& app, int& exit_code);
void register_thesis_benchmark_command(CLI::App& app, int& exit_code);
void register_lsp_command(CLI::App& app, int& exit_code);
void register_tune_command(CLI::App& app, int& exit_code);
void register_validate_command(CLI::App& app, int& exit_code);
void register_diff_command(CLI::App& app, int& exit_code);
void register_studio_command(CLI::App& app, int& exit_code);

}  // namespace fmpc::cli
