#pragma once
// Reading a scene file's YAML document, the first step of parse_scene (scene_file.h): a pass over yaml-cpp's parse
// events before the document is built, and the positions and name lists every scene-file message uses. Internal to
// the scene-file reader (runtime/scene/scene_file*.cpp).
#include <yaml-cpp/mark.h>

#include <string>
#include <vector>

#include "diagnostics/diagnostic.h"

namespace fmpc::sim {

// The position of a yaml-cpp mark as a one-character range in `path` (the file alone where the mark has none).
SourceRange mark_range(const std::string& path, const YAML::Mark& mark);

// "a, b or c".
std::string join_names(const std::vector<std::string>& names);

// Checks `text` as parse events, before the document is built: yaml-cpp keeps the last of two equal keys silently
// (`material` given twice would use one of them), so duplicate keys are errors here, with both positions; so are a
// second document ('---') and nesting deeper than kMaxSceneNesting. Aliases are events, not copies, so a "billion
// laughs" file costs what its text costs. Errors go to `diagnostics`; text that is not YAML throws YAML::Exception.
void scan_scene_yaml(const std::string& path, const std::string& text, DiagnosticList& diagnostics);

}  // namespace fmpc::sim
