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

// The surface being bisected: its triangles (a bisected one is dead, its children appended) and, per edge, the two
// live triangles that share it (a closed surface has two on every edge).
class Bisection {
 public:
  Bisection(Mesh& surface, SurfaceSplit& split, std::size_t max_triangles)
      : surface_(surface), split_(split), max_triangles_(max_triangles) {
    alive_.assign(surface.triangles.size(), 1);
    for (std::size_t t = 0; t < surface.triangles.size(); ++t) attach(static_cast<int>(t));
  }

  bool alive(std::size_t t) const { return alive_[t] != 0; }
  // Whether a bisection was refused: it would have passed max_triangles live triangles.
  bool over_limit() const { return over_limit_; }

  // Bisects triangle t by the longest-edge propagation path (Rivara 1997): the neighbour across t's longest edge is
  // bisected first, recursively, until an edge is the longest of both its triangles; that edge is halved in both,
  // and so on until t itself is halved. Every step leaves the surface conforming.
  void refine(int t) {
    while (alive_[static_cast<std::size_t>(t)] && !over_limit_) {
      int current = t;
      for (;;) {
        const Edge longest = longest_edge(current);
        const int other = neighbour(current, longest);
        if (other < 0 || longest_edge(other) == longest) {
          halve(longest);
          break;
        }
        current = other;
      }
    }
  }

 private:
  // The longest edge; ties broken by the edge's vertex indices, so that both triangles on an edge agree.
  Edge longest_edge(int t) const {
    const Triangle& tri = surface_.triangles[static_cast<std::size_t>(t)];
    Edge best{-1, -1};
    double best_length = -1.0;
    for (int k = 0; k < 3; ++k) {
      const Edge e = side(tri, k);
      const double length = squared_distance(surface_.points[static_cast<std::size_t>(e.first)],
                                             surface_.points[static_cast<std::size_t>(e.second)]);
      if (length > best_length || (length == best_length && e < best)) best = e, best_length = length;
    }
    return best;
  }

  int neighbour(int t, const Edge& e) const {
    const auto it = edges_.find(e);
    if (it == edges_.end()) return -1;
    return it->second[0] == t ? it->second[1] : it->second[0];
  }

  void attach(int t) {
    const Triangle& tri = surface_.triangles[static_cast<std::size_t>(t)];
    for (int k = 0; k < 3; ++k) {
      auto& pair = edges_.try_emplace(side(tri, k), std::array<int, 2>{-1, -1}).first->second;
      (pair[0] < 0 ? pair[0] : pair[1]) = t;
    }
  }

  void detach(int t) {
    const Triangle& tri = surface_.triangles[static_cast<std::size_t>(t)];
    for (int k = 0; k < 3; ++k) {
      const auto it = edges_.find(side(tri, k));
      if (it == edges_.end()) continue;
      for (int& side : it->second)
        if (side == t) side = -1;
      if (it->second[0] < 0 && it->second[1] < 0) edges_.erase(it);
    }
    alive_[static_cast<std::size_t>(t)] = 0;
  }

  // Halves edge e at its midpoint in each triangle on it: (a, b, c) with e = ab becomes (a, m, c) and (m, b, c), in
  // the parent's orientation.
  void halve(const Edge& e) {
    // Each bisection replaces two live triangles by four.
    if (split_.triangles_before + 2 * (split_.parents.size() + 1) > max_triangles_) {
      over_limit_ = true;
      return;
    }
    const auto it = edges_.find(e);
    const std::array<int, 2> sides = it->second;
    const Point3& a = surface_.points[static_cast<std::size_t>(e.first)];
    const Point3& b = surface_.points[static_cast<std::size_t>(e.second)];
    const auto m = static_cast<std::int32_t>(surface_.points.size());
    surface_.points.push_back({(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0, (a[2] + b[2]) / 2.0});
    split_.parents.push_back({e.first, e.second});
    for (const int t : sides) {
      if (t < 0) continue;
      const Triangle tri = surface_.triangles[static_cast<std::size_t>(t)];
      // triangle_lines is empty or parallel to the triangles (split_surface_to_size makes it so).
      const int line = surface_.triangle_lines.empty() ? 0 : surface_.triangle_lines[static_cast<std::size_t>(t)];
      int k = 0;
      while (side(tri, k) != e) ++k;
      const std::int32_t p = tri[k], q = tri[(k + 1) % 3], r = tri[(k + 2) % 3];
      detach(t);
      for (const Triangle child : {Triangle{p, m, r}, Triangle{m, q, r}}) {
        surface_.triangles.push_back(child);
        if (!surface_.triangle_lines.empty()) surface_.triangle_lines.push_back(line);
        alive_.push_back(1);
        attach(static_cast<int>(surface_.triangles.size() - 1));
      }
    }
  }

  Mesh& surface_;
  SurfaceSplit& split_;
  std::size_t max_triangles_;
  bool over_limit_ = false;
  std::vector<unsigned char> alive_;
  std::map<Edge, std::array<int, 2>> edges_;
};

// Whether triangle t is coarser than the field: its longest edge against the field at its centroid.
bool too_coarse(const Mesh& surface, const Triangle& t, const SizeField& field) {
  const Point3& a = surface.points[static_cast<std::size_t>(t[0])];
  const Point3& b = surface.points[static_cast<std::size_t>(t[1])];
  const Point3& c = surface.points[static_cast<std::size_t>(t[2])];
  const double longest = std::max({distance(a, b), distance(b, c), distance(c, a)});
  const Point3 centroid{(a[0] + b[0] + c[0]) / 3.0, (a[1] + b[1] + c[1]) / 3.0, (a[2] + b[2] + c[2]) / 3.0};
  return longest > size_at(field, centroid);
}

}  // namespace

std::optional<SurfaceSplit> split_surface_to_size(Mesh& surface, const SizeField& field, std::size_t max_triangles,
                                                  DiagnosticList& diagnostics) {
  SurfaceSplit split;
  split.triangles_before = surface.triangles.size();
  if (surface.triangle_lines.size() != surface.triangles.size()) surface.triangle_lines.clear();
  Bisection bisection(surface, split, max_triangles);
  // Triangles in order, children after their parents: every triangle is visited once it exists, and refined while
  // it is coarser than the field (a neighbour's bisection may halve it first).
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    while (bisection.alive(t) && too_coarse(surface, surface.triangles[t], field)) {
      bisection.refine(static_cast<int>(t));
      if (!bisection.over_limit()) continue;
      diagnostics.error(SourceRange{surface.source, 0, 0, 0, 0},
                        "splitting the kept surface to the size field needs more than " +
                            std::to_string(max_triangles) +
                            " triangles, the mesher's limit: raise size_near or size_far, or shrink near_distance");
      return std::nullopt;
    }
  }
  std::vector<Triangle> live;
  std::vector<int> lines;
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    if (!bisection.alive(t)) continue;
    live.push_back(surface.triangles[t]);
    if (!surface.triangle_lines.empty()) lines.push_back(surface.triangle_lines[t]);
  }
  surface.triangles = std::move(live);
  surface.triangle_lines = std::move(lines);
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
