#pragma once
// `fmpc trade SCENE.yaml` (docs/trade.md, "Scenes"): the trade command's scene side. trade_command.cpp registers the
// command; these add the scene's options to it and run it when the file is a scene.
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace CLI {
class App;
}

namespace fmpc::cli {

struct SceneTradeArguments {
  std::vector<std::string> models;
  std::vector<std::string> precisions;
  std::vector<std::string> integrators;  // NAME or NAME:FACTOR
  std::vector<unsigned> refinements;
  std::optional<unsigned> reference_refinements;
  std::optional<double> reference_dt_factor;
  std::optional<double> duration;
  std::vector<std::string> variants;  // axes (trade_axes' names)
  std::vector<std::string> elements;  // element kinds' keywords
  std::vector<std::string> meshes;    // graded, uniform
  std::optional<double> max_error;
  std::vector<std::string> error;  // displacement, probe_force
  std::string plot_error;          // displacement or probe_force
  std::string write_scene;
  std::optional<double> max_reference_seconds;
  std::optional<unsigned> threads;
};

// Adds the scene options (--variants and each axis's values, --max-error, --error, --write-scene, the reference's
// options, --duration, --plot-error, --threads) to the trade command.
std::shared_ptr<SceneTradeArguments> add_scene_trade_options(CLI::App& command);

// A scene file by its extension (.yaml or .yml); anything else is a rule file.
bool is_scene_path(const std::string& path);

// The exit code of `fmpc trade SCENE.yaml`; rule-file options (--fix, --points, ...) given with a scene are refused.
int run_scene_trade(CLI::App& command, const std::string& scene_path, const std::string& csv,
                    const std::string& markdown, const std::string& plot, const SceneTradeArguments& arguments);

// Scene options given with a rule file: 2 after saying which; 0 when there are none.
int refuse_scene_options(CLI::App& command, const std::string& file);

}  // namespace fmpc::cli
