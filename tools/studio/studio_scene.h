#pragma once
// The studio's scene panel: the patient's scene run on the CPU through the simulator's public functions
// (runtime/scene: parse_scene, build_scene, run_scene), returning the probe's force curve and the tissue's surface
// before and after, for the page to draw in 3-D. Kept to this one file: the simulator's interfaces change.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "tools/studio/studio_rule_model.h"

namespace fmpc::studio {

// Larger scenes are refused here (run them with `fmpc simulate`): the page waits for the answer.
inline constexpr std::size_t kMaxSceneVertices = 20000;

// Runs `scene` (nullopt: the demo's indentation of a 4 x 4 x 2 cm liver block, rulesets/scenes/liver_indentation.yaml,
// with these rules) for the patient `inputs` of `system`, whose text is `rules_text` (the editor's, which need not
// be saved) from `rules_path`. A scene of the folder uses these rules and inputs when its material names the same
// rule file; otherwise it runs as it is, and the answer says so. nullopt with `error` (the scene's diagnostics as
// `fmpc simulate` prints them) when it cannot run.
std::optional<Json> run_patient_scene(const std::filesystem::path& rules_path, const std::string& rules_text,
                                      const FuzzySystem& system, const std::vector<double>& inputs,
                                      const std::optional<std::filesystem::path>& scene, std::string& error);

}  // namespace fmpc::studio
