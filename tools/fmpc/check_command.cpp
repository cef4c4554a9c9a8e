#include <CLI/CLI.hpp>
#include <iostream>

#include "diagnostics/number_format.h"
#include "runtime/io/input_file.h"
#include "runtime/io/rule_file_input.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "tools/fmpc/commands.h"
#include "tools/fmpc/rule_file_session.h"
#include "tools/fmpc/scene_trade_command.h"
#include "tools/fmpc/text_files.h"
#include "tools/fmpc/warning_policy.h"

namespace fmpc::cli {

namespace {

struct CheckOptions {
  std::vector<std::string> files;
  bool werror = false;
  bool no_lint = false;
  double coverage_threshold = LintOptions{}.coverage_threshold;
};

// `fmpc check SCENE.yaml`: everything `simulate` does before its first step (the scene's fields, the mesh, the
// material and its rule file, springs or elements, loads, the stability analysis that chooses dt) and nothing after:
// nothing runs and nothing is written. False after errors.
bool check_scene(const std::string& path) {
  DiagnosticList diagnostics;
  SourceFiles sources;
  std::string read_error;
  const std::optional<std::string> text = read_text_file(path, sim::kMaxSceneFileBytes, "scene file", read_error);
  std::optional<sim::Scene> scene;
  std::optional<sim::BuiltScene> built;
  std::optional<sim::StabilityReport> stability;
  if (!text) {
    diagnostics.error(SourceRange{path, 0, 0, 0, 0}, read_error);
  } else {
    sources.add(path, *text);
    scene = sim::parse_scene(path, *text, diagnostics);
  }
  if (scene) built = sim::build_scene(*scene, diagnostics);
  if (built) {
    for (const auto& [source_path, source] : built->sources) sources.add(source_path, source);
    stability = sim::check_stability(built->setup, diagnostics);
  }
  std::optional<std::size_t> steps;
  if (stability) steps = sim::planned_step_count(*scene, stability->time_step, diagnostics);
  diagnostics.sort_by_position();
  print_diagnostics(diagnostics, sources, std::cerr);
  if (diagnostics.has_errors() || !steps) return false;
  std::cout << path << ": builds: " << built->mesh.points.size() << " vertices, " << built->mesh.tetrahedra.size()
            << " tetrahedra, " << built->setup.springs.size() << " springs; " << *steps << " steps of "
            << format_number(stability->time_step) << " s" << (scene->dt ? "" : " (dt auto)") << "; nothing was run\n";
  return true;
}

int run_check(const CheckOptions& options) {
  if (options.werror) process_warning_policy().all_errors = true;
  bool any_error = false;
  for (const std::string& path : options.files) {
    if (is_scene_path(path)) {
      any_error = !check_scene(path) || any_error;
      continue;
    }
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
                         "Check rule files (fmpc, MATLAB .fis, FLL, FCL): every error and lint warning, compiler-style;\n"
                         "or scene files (.yaml): everything simulate does before its first step, and nothing after.");
  command->add_option("files", options->files, "Rule files or scene files (.yaml) to check")->required();
  command->add_flag("--werror", options->werror, "The same as -Werror: warnings print as errors and the exit status is 1");
  command->add_flag("--no-lint", options->no_lint, "Report errors only");
  command
      ->add_option("--coverage-threshold", options->coverage_threshold,
                   "Firing strength below which a point counts as a coverage hole")
      ->check(CLI::Range(0.0, 1.0));
  command->callback([options, &exit_code] { exit_code = run_check(*options); });
}

}  // namespace fmpc::cli
