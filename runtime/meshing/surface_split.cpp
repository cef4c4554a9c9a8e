#include "runtime/meshing/surface_split.h"

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <utility>

namespace fmpc::sim {

namespace {

using Edge = std::pair<std::int32_t, std::int32_t>;

Edge edge_of(std::int32_t a, std::int32_t b) { return a < b ? Edge{a, b} : Edge{b, a}; }

// Edge k of a triangle: from corner k to the next.
Edge side(const Triangle& t, int k) { return edge_of(t[k], t[(k + 1) % 3]); }

// How many of triangle t's edges are marked.
int marked_sides(const Triangle& t, const std::map<Edge, std::int32_t>& marked) {
  int count = 0;
  for (int k = 0; k < 3; ++k) count += marked.count(side(t, k)) > 0 ? 1 : 0;
  return count;
}

// Whether triangle t is coarser than the field: its longest edge against the field at its centroid.
bool too_coarse(const Mesh& surface, const Triangle& t, const SizeField& field) {
  const Point3& a = surface.points[static_cast<std::size_t>(t[0])];
  const Point3& b = surface.points[static_cast<std::size_t>(t[1])];
  const Point3& c = surface.points[static_cast<std::size_t>(t[2])];
  const double longest = std::max({distance(a, b), distance(b, c), distance(c, a)});
  const Point3 centroid{(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0, (a[2] + b[2] + c[2]) / 3.0};
  return longest > size_at(field, centroid);
}

// The edges one round splits: every edge of a coarse triangle, then, until nothing changes, the third edge of any
// triangle with two (a triangle is split in four or in two, never in three).
std::map<Edge, std::int32_t> edges_to_split(const Mesh& surface, const SizeField& field) {
  std::map<Edge, std::int32_t> marked;
  for (const Triangle& t : surface.triangles)
    if (too_coarse(surface, t, field))
      for (int k = 0; k < 3; ++k) marked.emplace(side(t, k), -1);
  for (bool changed = !marked.empty(); changed;) {
    changed = false;
    for (const Triangle& t : surface.triangles) {
      if (marked_sides(t, marked) != 2) continue;
      for (int k = 0; k < 3; ++k) changed = marked.emplace(side(t, k), -1).second || changed;
    }
  }
  return marked;
}

}  // namespace

std::optional<SurfaceSplit> split_surface_to_size(Mesh& surface, const SizeField& field, std::size_t max_triangles,
                                                  DiagnosticList& diagnostics) {
  SurfaceSplit split;
  split.triangles_before = surface.triangles.size();
  for (std::size_t round = 0; round < kMaxSurfaceSplitRounds; ++round) {
    std::map<Edge, std::int32_t> marked = edges_to_split(surface, field);
    if (marked.empty()) break;
    std::size_t red = 0, green = 0;
    for (const Triangle& t : surface.triangles) {
      const int count = marked_sides(t, marked);
      red += count == 3 ? 1 : 0;
      green += count == 1 ? 1 : 0;
    }
    const std::size_t after = surface.triangles.size() + 3 * red + green;
    if (after > max_triangles) {
      diagnostics.error(SourceRange{surface.source, 0, 0, 0, 0},
                        "splitting the kept surface to the size field would give " + std::to_string(after) +
                            " triangles; the mesher takes at most " + std::to_string(max_triangles) +
                            ": raise size_near or size_far, or shrink near_distance");
      return std::nullopt;
    }
    for (auto& [edge, middle] : marked) {
      middle = static_cast<std::int32_t>(surface.points.size());
      const Point3& a = surface.points[static_cast<std::size_t>(edge.first)];
      const Point3& b = surface.points[static_cast<std::size_t>(edge.second)];
      surface.points.push_back({(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, (a[2] + b[2]) / 2.0});
      split.parents.push_back({edge.first, edge.second});
    }
    std::vector<Triangle> triangles;
    std::vector<int> lines;
    triangles.reserve(after);
    lines.reserve(after);
    for (std::size_t i = 0; i < surface.triangles.size(); ++i) {
      const Triangle& t = surface.triangles[i];
      const int line = i < surface.triangle_lines.size() ? surface.triangle_lines[i] : 0;
      std::int32_t middle[3];  // of edge k (t[k], t[k + 1]); -1 where it stays whole
      int count = 0, only = 0;
      for (int k = 0; k < 3; ++k) {
        const auto it = marked.find(side(t, k));
        middle[k] = it == marked.end() ? -1 : it->second;
        if (middle[k] >= 0) ++count, only = k;
      }
      // Children keep the parent's orientation (its corners in the same cyclic order).
      const auto add = [&](std::int32_t a, std::int32_t b, std::int32_t c) {
        triangles.push_back({a, b, c});
        lines.push_back(line);
      };
      if (count == 0) {
        add(t[0], t[1], t[2]);
      } else if (count == 3) {
        add(t[0], middle[0], middle[2]);
        add(middle[0], t[1], middle[1]);
        add(middle[2], middle[1], t[2]);
        add(middle[0], middle[1], middle[2]);
      } else {
        const std::int32_t a = t[only], b = t[(only + 1) % 3], c = t[(only + 2) % 3], m = middle[only];
        add(a, m, c);
        add(m, b, c);
      }
    }
    surface.triangles = std::move(triangles);
    surface.triangle_lines = std::move(lines);
    ++split.rounds;
  }
  split.triangles_after = surface.triangles.size();
  return split;
}

std::size_t remove_flat_surface_tetrahedra(Mesh& mesh, const std::vector<Triangle>& surface) {
  const auto flat = [&](const Tetrahedron& t) { return signed_volume(mesh, t) == 0.0; };
  if (std::none_of(mesh.tetrahedra.begin(), mesh.tetrahedra.end(), flat)) return 0;
  std::set<Triangle> faces;
  for (Triangle t : surface) {
    std::sort(t.begin(), t.end());
    faces.insert(t);
  }
  const auto on_surface = [&](const Tetrahedron& t) {
    static constexpr int kFace[4][3] = {{1, 2, 3}, {0, 2, 3}, {0, 1, 3}, {0, 1, 2}};
    int count = 0;
    for (const auto& face : kFace) {
      Triangle f{t[face[0]], t[face[1]], t[face[2]]};
      std::sort(f.begin(), f.end());
      count += faces.count(f) > 0 ? 1 : 0;
    }
    return count >= 2;
  };
  const std::size_t before = mesh.tetrahedra.size();
  std::vector<Tetrahedron> kept;
  std::vector<int> lines;
  kept.reserve(before);
  for (std::size_t i = 0; i < before; ++i) {
    const Tetrahedron& t = mesh.tetrahedra[i];
    if (flat(t) && on_surface(t)) continue;
    kept.push_back(t);
    if (i < mesh.tetrahedron_lines.size()) lines.push_back(mesh.tetrahedron_lines[i]);
  }
  const std::size_t removed = before - kept.size();
  if (removed > 0) {
    mesh.tetrahedra = std::move(kept);
    if (!mesh.tetrahedron_lines.empty()) mesh.tetrahedron_lines = std::move(lines);
  }
  return removed;
}

void split_selection(const SurfaceSplit& split, std::size_t original_vertices, std::vector<unsigned char>& selected) {
  for (std::size_t k = 0; k < split.parents.size(); ++k) {
    const std::size_t v = original_vertices + k;
    if (v >= selected.size()) return;
    const auto [a, b] = split.parents[k];
    if (selected[static_cast<std::size_t>(a)] && selected[static_cast<std::size_t>(b)]) selected[v] = 1;
  }
}

}  // namespace fmpc::sim
