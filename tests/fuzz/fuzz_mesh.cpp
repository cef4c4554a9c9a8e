// libFuzzer target for one mesh reader (runtime/mesh/mesh_reader.h), chosen at build time by
// FMPC_FUZZ_MESH_READER (read_gmsh, read_obj, read_vtk) and FMPC_FUZZ_MESH_FILE; what it read then goes through the
// checks and repair every mesh from a file goes through (runtime/mesh/mesh_check.h).
#include <cstdint>
#include <string_view>

#include "runtime/mesh/mesh_check.h"
#include "runtime/mesh/mesh_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  fmpc::DiagnosticList diagnostics;
  if (auto mesh = fmpc::sim::FMPC_FUZZ_MESH_READER(text, FMPC_FUZZ_MESH_FILE, diagnostics)) {
    (void)fmpc::sim::check_mesh(*mesh);
    (void)fmpc::sim::repair_mesh(*mesh);
  }
  return 0;
}
