// The build without TetGen (FMPC_MESHER=OFF): surfaces are refused with the reason, and no AGPL code is linked.
#include "runtime/meshing/tetgen_mesher.h"

namespace fmpc::sim {

bool tetgen_available() { return false; }

std::optional<Mesh> tetgen_tetrahedralize(const Mesh& surface, const VolumeMeshOptions&, std::size_t,
                                          DiagnosticList& diagnostics) {
  diagnostics.error(SourceRange{surface.source, 0, 0, 0, 0},
                    "this fmpc was built without the volume mesher (FMPC_MESHER=OFF); rebuild with libtet1.5-dev "
                    "installed and FMPC_MESHER=ON, or mesh the surface elsewhere and give the .msh as mesh.file");
  return std::nullopt;
}

std::optional<std::vector<std::size_t>> tetgen_self_intersections(const Mesh& surface, DiagnosticList& diagnostics) {
  return tetgen_tetrahedralize(surface, VolumeMeshOptions{}, 0, diagnostics)
             ? std::vector<std::size_t>{}
             : std::optional<std::vector<std::size_t>>{};
}

}  // namespace fmpc::sim
