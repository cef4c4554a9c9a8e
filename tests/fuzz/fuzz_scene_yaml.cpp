// libFuzzer target: scene YAML (runtime/scene/scene_file*.cpp: the duplicate-key scan, the field checks).
#include <cstdint>
#include <string>

#include "runtime/scene/scene_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  fmpc::DiagnosticList diagnostics;
  // A path in a folder that does not exist: file fields resolve under it and are never opened.
  (void)fmpc::sim::parse_scene("/nonexistent-fmpc-fuzz/scene.yaml", text, diagnostics);
  fmpc::SourceFiles sources;
  sources.add("/nonexistent-fmpc-fuzz/scene.yaml", text);
  (void)fmpc::render_all(diagnostics, sources);
  return 0;
}
