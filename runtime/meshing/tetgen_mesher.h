#pragma once
// The one file that calls TetGen (libtet1.5-dev, AGPL-3+; README, "Dependencies"): a build with FMPC_MESHER=OFF
// compiles tetgen_mesher_off.cpp instead and links no TetGen.
#include <cstddef>
#include <optional>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/mesh/mesh.h"
#include "runtime/meshing/volume_mesher.h"

namespace fmpc::sim {

// Constrained Delaunay refinement of the checked, outward surface's volume with options' size field and bounds, at
// most `max_inserted` vertices added. The result's tetrahedra are as TetGen orients them.
std::optional<Mesh> tetgen_tetrahedralize(const Mesh& surface, const VolumeMeshOptions& options,
                                          std::size_t max_inserted, DiagnosticList& diagnostics);
bool tetgen_available();
// Defined beside fmpc's terminatetetgen (tetgen_termination.cpp), which replaces TetGen's.
bool tetgen_termination_interposed();

// The triangles of the surface that intersect another part of it (TetGen's -d check, Si 2015 section 4.2), sorted;
// nullopt after an error. TetGen meshes nothing for such a surface, and Debian's TetGen 1.5.0 corrupts its heap when
// it stops on one (see terminatetetgen in tetgen_mesher.cpp), so every surface is checked first.
std::optional<std::vector<std::size_t>> tetgen_self_intersections(const Mesh& surface, DiagnosticList& diagnostics);

}  // namespace fmpc::sim
