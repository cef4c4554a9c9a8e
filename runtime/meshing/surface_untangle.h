#pragma once
// Surfaces from segmentations often fold through themselves at a few triangles (SOFA's liver-smooth.obj does at 8):
// no constrained Delaunay mesher can mesh them. On request, the vertices of the triangles that intersect are moved
// to the mean of their neighbours (one Jacobi step of Laplacian smoothing, Taubin 1995 with lambda = 1), widening by
// one ring of neighbours each round until nothing intersects; every move is measured and reported.
#include <cstddef>
#include <optional>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/mesh/mesh.h"

namespace fmpc::sim {

inline constexpr std::size_t kMaxUntangleRounds = 8;

struct SurfaceUntangling {
  std::size_t intersecting_triangles = 0;  // found before the first round
  std::size_t rounds = 0;
  std::size_t moved_vertices = 0;
  double largest_move = 0.0;  // mesh units
};

// Appends one located error per intersecting triangle (at most kMaxSurfaceDefectsListed) and says how to go on.
void report_self_intersections(const Mesh& surface, const std::vector<std::size_t>& triangles,
                               DiagnosticList& diagnostics);

// Smooths the surface until it no longer intersects itself; nullopt (with errors) when kMaxUntangleRounds are not
// enough or TetGen's check fails. `intersecting` is the check's first answer.
std::optional<SurfaceUntangling> untangle_surface(Mesh& surface, std::vector<std::size_t> intersecting,
                                                  DiagnosticList& diagnostics);

}  // namespace fmpc::sim
