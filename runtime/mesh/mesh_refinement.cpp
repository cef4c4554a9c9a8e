#include "runtime/mesh/mesh_refinement.h"

#include <algorithm>
#include <utility>
#include <vector>

namespace fmpc::sim {

namespace {

std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

// The sorted distinct edges of the tetrahedra and triangles, as edge_key values.
std::vector<std::uint64_t> sorted_edges(const Mesh& mesh) {
  std::vector<std::uint64_t> edges;
  edges.reserve(mesh.tetrahedra.size() * 6 + mesh.triangles.size() * 3);
  for (const Tetrahedron& t : mesh.tetrahedra)
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) edges.push_back(edge_key(t[static_cast<std::size_t>(i)], t[static_cast<std::size_t>(j)]));
  for (const Triangle& t : mesh.triangles)
    for (int i = 0; i < 3; ++i) edges.push_back(edge_key(t[static_cast<std::size_t>(i)], t[static_cast<std::size_t>((i + 1) % 3)]));
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

}  // namespace

std::uint64_t distinct_edge_count(const Mesh& mesh) { return sorted_edges(mesh).size(); }

Mesh subdivide_tetrahedra(const Mesh& mesh) {
  const std::vector<std::uint64_t> edges = sorted_edges(mesh);
  const auto vertex_count = static_cast<std::int32_t>(mesh.points.size());
  Mesh refined;
  refined.source = mesh.source + ", refined 1:8";
  refined.points = mesh.points;
  refined.points.reserve(mesh.points.size() + edges.size());
  for (const std::uint64_t key : edges) {
    const Point3& a = mesh.points[static_cast<std::size_t>(key >> 32)];
    const Point3& b = mesh.points[static_cast<std::size_t>(key & 0xffffffffu)];
    refined.points.push_back({0.5 * (a[0] + b[0]), 0.5 * (a[1] + b[1]), 0.5 * (a[2] + b[2])});
  }
  const auto midpoint = [&](std::int32_t a, std::int32_t b) {
    const auto it = std::lower_bound(edges.begin(), edges.end(), edge_key(a, b));
    return vertex_count + static_cast<std::int32_t>(it - edges.begin());
  };

  refined.tetrahedra.reserve(mesh.tetrahedra.size() * 8);
  for (std::size_t e = 0; e < mesh.tetrahedra.size(); ++e) {
    const Tetrahedron& t = mesh.tetrahedra[e];
    const std::int32_t m01 = midpoint(t[0], t[1]), m02 = midpoint(t[0], t[2]), m03 = midpoint(t[0], t[3]);
    const std::int32_t m12 = midpoint(t[1], t[2]), m13 = midpoint(t[1], t[3]), m23 = midpoint(t[2], t[3]);
    // Corners: the parent scaled by 1/2 about each vertex, its vertex order (and so its orientation) kept.
    refined.tetrahedra.push_back({t[0], m01, m02, m03});
    refined.tetrahedra.push_back({m01, t[1], m12, m13});
    refined.tetrahedra.push_back({m02, m12, t[2], m23});
    refined.tetrahedra.push_back({m03, m13, m23, t[3]});
    // The octahedron around the shortest diagonal: the four other midpoints form a cycle around it (each is joined
    // to the next by an octahedron edge).
    const Point3* p = refined.points.data();
    const double d0 = squared_distance(p[m01], p[m23]);
    const double d1 = squared_distance(p[m02], p[m13]);
    const double d2 = squared_distance(p[m03], p[m12]);
    std::int32_t a = m01, b = m23;
    std::array<std::int32_t, 4> ring{m02, m03, m13, m12};
    if (d1 < d0 && d1 <= d2) {
      a = m02, b = m13;
      ring = {m01, m03, m23, m12};
    } else if (d2 < d0 && d2 < d1) {
      a = m03, b = m12;
      ring = {m01, m02, m23, m13};
    }
    const double parent = signed_volume(mesh, t);
    for (std::size_t k = 0; k < 4; ++k) {
      Tetrahedron child{a, b, ring[k], ring[(k + 1) % 4]};
      // Every inner child has the parent's orientation (the same sign of volume).
      if ((signed_volume(refined, child) < 0.0) != (parent < 0.0)) std::swap(child[2], child[3]);
      refined.tetrahedra.push_back(child);
    }
    if (e < mesh.tetrahedron_lines.size())
      refined.tetrahedron_lines.insert(refined.tetrahedron_lines.end(), 8, mesh.tetrahedron_lines[e]);
  }

  refined.triangles.reserve(mesh.triangles.size() * 4);
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    const std::int32_t m01 = midpoint(t[0], t[1]), m12 = midpoint(t[1], t[2]), m20 = midpoint(t[2], t[0]);
    // Same winding as the parent.
    refined.triangles.push_back({t[0], m01, m20});
    refined.triangles.push_back({m01, t[1], m12});
    refined.triangles.push_back({m20, m12, t[2]});
    refined.triangles.push_back({m01, m12, m20});
    if (f < mesh.triangle_lines.size()) refined.triangle_lines.insert(refined.triangle_lines.end(), 4, mesh.triangle_lines[f]);
  }
  return refined;
}

}  // namespace fmpc::sim
