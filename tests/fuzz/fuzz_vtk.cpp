// libFuzzer target: the vtk mesh reader (runtime/mesh/vtk_reader.cpp), then the mesh checks and repair that
// every mesh read from a file goes through (runtime/mesh/mesh_check.h).
#include <cstdint>
#include <string_view>

#include "runtime/mesh/mesh_check.h"
#include "runtime/mesh/mesh_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  fmpc::DiagnosticList diagnostics;
  if (auto mesh = fmpc::sim::read_vtk(text, "fuzz.vtk", diagnostics)) {
    (void)fmpc::sim::check_mesh(*mesh);
    (void)fmpc::sim::repair_mesh(*mesh);
  }
  return 0;
}
