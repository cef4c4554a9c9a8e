#pragma once
// Tetrahedral meshes built in code, at any resolution, for tests, benchmarks and scenes without a mesh file.
#include "diagnostics/diagnostic.h"
#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

struct BoxSpec {
  Point3 minimum{0.0, 0.0, 0.0};
  Point3 size{1.0, 1.0, 1.0};
  int cells_x = 1, cells_y = 1, cells_z = 1;  // each cell is split into 6 tetrahedra
};

struct EllipsoidSpec {
  Point3 centre{0.0, 0.0, 0.0};
  Point3 radii{1.0, 1.0, 1.0};
  int resolution = 4;  // cells along each half-axis of the underlying cube
};

// A box of (cells_x+1)(cells_y+1)(cells_z+1) vertices; each cube is cut into 6 tetrahedra around a main diagonal
// (Kuhn/Freudenthal subdivision), mirrored along every axis whose cell index is odd, so that the cut has no preferred
// direction (a 2 x 2 x 2 block of cells is symmetric under reflection in each axis) and neighbouring cubes share
// their face diagonals: a conforming mesh.
// Returns an empty mesh and an error for non-positive cell counts or sizes, or more than 2^31 vertices.
Mesh generate_box(const BoxSpec& spec, DiagnosticList& diagnostics);

// A tetrahedral ellipsoid: the box mesh of [-1,1]^3 mapped onto the unit ball by the radial map
// p -> p * |p|_inf / |p|_2 (cube shells onto spheres), then scaled by the radii. All tetrahedra keep positive volume.
Mesh generate_ellipsoid(const EllipsoidSpec& spec, DiagnosticList& diagnostics);

}  // namespace fmpc::sim
