#pragma once
// Whether a triangle surface bounds a volume that can be meshed: closed (every edge on exactly two triangles),
// manifold (no edge on more than two, every vertex's triangles one fan), consistently oriented (each edge run once
// each way), every vertex used and no triangle degenerate. Findings are located: the file, the triangle's line where
// the reader knew it, and the edge, vertex or triangle index (0-based, in the file's numbering).
#include <cstddef>
#include <string>

#include "diagnostics/diagnostic.h"
#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

// At most this many defects are reported one by one; the rest are counted in a last error.
inline constexpr std::size_t kMaxSurfaceDefectsListed = 20;

struct SurfaceCheck {
  bool closed = false;  // no defect of any kind: the surface can be meshed
  bool inward = false;  // consistently oriented, but with normals pointing in (enclosed volume < 0)
  double volume = 0.0;  // enclosed volume (mesh units^3), by the divergence theorem; > 0 once oriented outwards
  double area = 0.0;    // surface area (mesh units^2)
  std::size_t defects = 0;
};

// Appends one located error per defect (the first kMaxSurfaceDefectsListed, in a fixed order: unused vertices,
// degenerate triangles, open edges, non-manifold edges, non-manifold vertices, flipped triangles; each by index).
SurfaceCheck check_closed_surface(const Mesh& surface, DiagnosticList& diagnostics);

// Where triangle t of a surface is: its line in the file when the reader knew it, else the file alone; and its name
// in messages, "triangle 12 (line 40)".
SourceRange triangle_range(const Mesh& surface, std::size_t t);
std::string triangle_name(const Mesh& surface, std::size_t t);

// Reverses every triangle (b and c swapped): an inward surface becomes outward.
void reverse_triangles(Mesh& surface);

}  // namespace fmpc::sim
