#pragma once
// Each command registers itself on the CLI11 app; its callback stores the process exit code in `exit_code`.
namespace CLI {
class App;
}

namespace fmpc::cli {

void register_check_command(CLI::App& app, int& exit_code);
void register_fmt_command(CLI::App& app, int& exit_code);
void register_eval_command(CLI::App& app, int& exit_code);
void register_convert_command(CLI::App& app, int& exit_code);
void register_simulate_command(CLI::App& app, int& exit_code);
void register_compile_command(CLI::App& app, int& exit_code);
void register_plot_command(CLI::App& app, int& exit_code);
void register_trade_command(CLI::App& app, int& exit_code);
void register_thesis_benchmark_command(CLI::App& app, int& exit_code);

}  // namespace fmpc::cli
