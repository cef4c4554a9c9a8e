#include "runtime/meshing/surface_check.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <utility>
#include <vector>

namespace fmpc::sim {

namespace {

// One use of an edge: the triangle and whether it runs the edge from the lower vertex to the higher one.
struct EdgeUse {
  std::int32_t low = 0, high = 0;
  std::int32_t triangle = 0;
  bool forward = false;
  bool operator<(const EdgeUse& other) const {
    return std::tie(low, high, triangle) < std::tie(other.low, other.high, other.triangle);
  }
};

// A triangle with a repeated vertex is reported once as such and left out of the edge and fan checks, which it
// would otherwise fail again.
bool repeats_vertex(const Triangle& tri) { return tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]; }

std::vector<EdgeUse> edge_uses(const Mesh& surface) {
  std::vector<EdgeUse> uses;
  uses.reserve(3 * surface.triangles.size());
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    const Triangle& tri = surface.triangles[t];
    if (repeats_vertex(tri)) continue;
    for (std::size_t k = 0; k < 3; ++k) {
      const std::int32_t a = tri[k], b = tri[(k + 1) % 3];
      uses.push_back({std::min(a, b), std::max(a, b), static_cast<std::int32_t>(t), a < b});
    }
  }
  std::sort(uses.begin(), uses.end());
  return uses;
}

class DefectReport {
 public:
  DefectReport(const Mesh& surface, DiagnosticList& diagnostics) : surface_(surface), diagnostics_(diagnostics) {}

  SourceRange triangle_range(std::int32_t t) const {
    return sim::triangle_range(surface_, static_cast<std::size_t>(t));
  }
  std::string triangle_name(std::int32_t t) const { return sim::triangle_name(surface_, static_cast<std::size_t>(t)); }
  void add(const SourceRange& range, const std::string& message) {
    ++count_;
    if (count_ <= kMaxSurfaceDefectsListed) diagnostics_.error(range, message);
  }
  void finish() {
    if (count_ > kMaxSurfaceDefectsListed)
      diagnostics_.error(SourceRange{surface_.source, 0, 0, 0, 0},
                         std::to_string(count_ - kMaxSurfaceDefectsListed) +
                             " more surface defects are not listed; fix the ones above and check again");
  }
  std::size_t count() const { return count_; }

 private:
  const Mesh& surface_;
  DiagnosticList& diagnostics_;
  std::size_t count_ = 0;
};

std::string edge_name(std::int32_t a, std::int32_t b) {
  return "the edge from vertex " + std::to_string(a) + " to vertex " + std::to_string(b) + " (0-based)";
}

// Triangles a vertex belongs to: CSR offsets over the vertices.
struct VertexTriangles {
  std::vector<std::size_t> offset;
  std::vector<std::int32_t> triangle;
};

VertexTriangles vertex_triangles(const Mesh& surface) {
  VertexTriangles out;
  out.offset.assign(surface.points.size() + 1, 0);
  for (const Triangle& tri : surface.triangles)
    if (!repeats_vertex(tri))
      for (const auto v : tri) ++out.offset[static_cast<std::size_t>(v) + 1];
  std::partial_sum(out.offset.begin(), out.offset.end(), out.offset.begin());
  out.triangle.resize(out.offset.back());
  std::vector<std::size_t> fill(out.offset.begin(), out.offset.end() - 1);
  for (std::size_t t = 0; t < surface.triangles.size(); ++t)
    if (!repeats_vertex(surface.triangles[t]))
      for (const auto v : surface.triangles[t])
        out.triangle[fill[static_cast<std::size_t>(v)]++] = static_cast<std::int32_t>(t);
  return out;
}

std::size_t find_root(std::vector<std::size_t>& parent, std::size_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// The number of fans the triangles around vertex v form: triangles are joined when they share an edge at v, i.e.
// another corner. O(k log k) in the k triangles at v (pairs sorted by that corner).
std::size_t fan_count(const Mesh& surface, const VertexTriangles& around, std::size_t v) {
  const std::size_t first = around.offset[v], count = around.offset[v + 1] - first;
  std::vector<std::size_t> parent(count);
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<std::pair<std::int32_t, std::size_t>> corners;  // (other corner, local triangle)
  corners.reserve(2 * count);
  for (std::size_t i = 0; i < count; ++i)
    for (const auto corner : surface.triangles[static_cast<std::size_t>(around.triangle[first + i])])
      if (static_cast<std::size_t>(corner) != v) corners.emplace_back(corner, i);
  std::sort(corners.begin(), corners.end());
  for (std::size_t k = 1; k < corners.size(); ++k)
    if (corners[k].first == corners[k - 1].first)
      parent[find_root(parent, corners[k].second)] = find_root(parent, corners[k - 1].second);
  std::size_t fans = 0;
  for (std::size_t i = 0; i < count; ++i) fans += find_root(parent, i) == i;
  return fans;
}

// Orientation by breadth-first search over manifold edges: a neighbour keeps the orientation when it runs the shared
// edge the other way. In each connected part the smaller class (ties: the one without the part's first triangle)
// is reported as flipped, with a neighbour of the larger class where it has one.
void report_flipped(const Mesh& surface, const std::vector<EdgeUse>& uses, DefectReport& report) {
  const std::size_t n = surface.triangles.size();
  std::vector<std::vector<std::pair<std::int32_t, bool>>> neighbours(n);  // (triangle, same direction)
  for (std::size_t i = 0; i + 1 < uses.size(); ++i) {
    const EdgeUse& a = uses[i];
    const EdgeUse& b = uses[i + 1];
    if (a.low != b.low || a.high != b.high) continue;
    const bool two = (i == 0 || uses[i - 1].low != a.low || uses[i - 1].high != a.high) &&
                     (i + 2 >= uses.size() || uses[i + 2].low != a.low || uses[i + 2].high != a.high);
    if (!two) continue;
    neighbours[static_cast<std::size_t>(a.triangle)].emplace_back(b.triangle, a.forward == b.forward);
    neighbours[static_cast<std::size_t>(b.triangle)].emplace_back(a.triangle, a.forward == b.forward);
  }
  std::vector<int> parity(n, -1);
  std::vector<std::int32_t> queue;
  for (std::size_t start = 0; start < n; ++start) {
    if (parity[start] >= 0) continue;
    queue.assign(1, static_cast<std::int32_t>(start));
    parity[start] = 0;
    bool orientable = true;
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const auto t = static_cast<std::size_t>(queue[head]);
      for (const auto& [u, same] : neighbours[t]) {
        const int expected = parity[t] ^ (same ? 1 : 0);
        auto& p = parity[static_cast<std::size_t>(u)];
        if (p < 0) {
          p = expected;
          queue.push_back(u);
        } else if (p != expected && orientable) {
          orientable = false;
          report.add(report.triangle_range(u), report.triangle_name(u) + " and " +
                                                   report.triangle_name(static_cast<std::int32_t>(t)) +
                                                   " close a loop that cannot be oriented (as on a Moebius strip); "
                                                   "the surface must have an inside and an outside");
        }
      }
    }
    if (!orientable) continue;
    std::size_t ones = 0;
    for (const auto t : queue) ones += static_cast<std::size_t>(parity[static_cast<std::size_t>(t)]);
    const int minority = ones * 2 <= queue.size() ? 1 : 0;
    const std::size_t minority_count = minority == 1 ? ones : queue.size() - ones;
    if (minority_count == 0) continue;
    std::sort(queue.begin(), queue.end());
    for (const auto t : queue) {
      if (parity[static_cast<std::size_t>(t)] != minority) continue;
      std::string against;
      for (const auto& [u, same] : neighbours[static_cast<std::size_t>(t)])
        if (same && parity[static_cast<std::size_t>(u)] != minority) {
          against = ": it runs an edge the same way as its neighbour " + report.triangle_name(u);
          break;
        }
      report.add(report.triangle_range(t), report.triangle_name(t) + " is flipped" + against +
                                               " (triangles oriented against the rest of "
                                               "their part: " +
                                               std::to_string(minority_count) + " of " + std::to_string(queue.size()) +
                                               "); reverse its vertex order");
    }
  }
}

}  // namespace

SourceRange triangle_range(const Mesh& surface, std::size_t t) {
  SourceRange range;
  range.file = surface.source;
  if (t < surface.triangle_lines.size() && surface.triangle_lines[t] > 0) {
    range.line = surface.triangle_lines[t];
    range.column = 1;
  }
  return range;
}

std::string triangle_name(const Mesh& surface, std::size_t t) {
  const SourceRange range = triangle_range(surface, t);
  return "triangle " + std::to_string(t) +
         (range.valid() ? " (line " + std::to_string(range.line) + ")" : " (0-based)");
}

void reverse_triangles(Mesh& surface) {
  for (Triangle& tri : surface.triangles) std::swap(tri[1], tri[2]);
}

SurfaceCheck check_closed_surface(const Mesh& surface, DiagnosticList& diagnostics) {
  SurfaceCheck result;
  DefectReport report(surface, diagnostics);
  const SourceRange file_range{surface.source, 0, 0, 0, 0};
  if (surface.triangles.empty()) {
    report.add(file_range, "the surface has no triangles; a volume mesh needs a closed triangle surface");
    report.finish();
    result.defects = report.count();
    return result;
  }
  // Unused vertices: the mesher would place them inside the volume, or drop them and renumber the rest.
  std::vector<unsigned char> used(surface.points.size(), 0);
  for (const Triangle& tri : surface.triangles)
    for (const auto v : tri) used[static_cast<std::size_t>(v)] = 1;
  for (std::size_t v = 0; v < used.size(); ++v)
    if (!used[v])
      report.add(file_range, "vertex " + std::to_string(v) +
                                 " (0-based) belongs to no triangle; remove it (a surface to mesh "
                                 "has only the vertices of its triangles)");
  // Degenerate triangles: a repeated vertex, or three corners on a line (area <= 1e-12 of the squared longest edge).
  for (std::size_t t = 0; t < surface.triangles.size(); ++t) {
    const Triangle& tri = surface.triangles[t];
    const auto name = report.triangle_name(static_cast<std::int32_t>(t));
    if (repeats_vertex(tri)) {
      report.add(report.triangle_range(static_cast<std::int32_t>(t)),
                 name + " repeats a vertex (" + std::to_string(tri[0]) + ", " + std::to_string(tri[1]) + ", " +
                     std::to_string(tri[2]) + "); remove it");
      continue;
    }
    const Point3& a = surface.points[static_cast<std::size_t>(tri[0])];
    const Point3& b = surface.points[static_cast<std::size_t>(tri[1])];
    const Point3& c = surface.points[static_cast<std::size_t>(tri[2])];
    const double longest = std::max({squared_distance(a, b), squared_distance(b, c), squared_distance(a, c)});
    if (!(triangle_area(a, b, c) > 1e-12 * longest))
      report.add(report.triangle_range(static_cast<std::int32_t>(t)),
                 name + " has no area (its corners lie on a line); remove it or move a corner");
  }
  // Edges: open (one triangle), non-manifold (more than two).
  const std::vector<EdgeUse> uses = edge_uses(surface);
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i + 1;
    while (j < uses.size() && uses[j].low == uses[i].low && uses[j].high == uses[i].high) ++j;
    const std::string edge = edge_name(uses[i].low, uses[i].high);
    if (j - i == 1) {
      report.add(report.triangle_range(uses[i].triangle),
                 "the surface is open at " + edge + ": only " + report.triangle_name(uses[i].triangle) +
                     " has it; close the hole (every edge of a closed surface is on exactly two triangles)");
    } else if (j - i > 2) {
      std::string list;
      for (std::size_t k = i; k < j; ++k)
        list += (k == i ? "" : k + 1 == j ? " and " : ", ") + std::to_string(uses[k].triangle);
      report.add(report.triangle_range(uses[i].triangle),
                 "the surface is non-manifold at " + edge + ": " + std::to_string(j - i) +
                     " triangles share it (0-based: " + list + "); a closed surface has exactly two on every edge");
    }
    i = j;
  }
  // Vertices whose triangles form several fans: two parts touching at a point.
  const VertexTriangles around = vertex_triangles(surface);
  for (std::size_t v = 0; v < surface.points.size(); ++v) {
    if (around.offset[v + 1] == around.offset[v]) continue;
    const std::size_t fans = fan_count(surface, around, v);
    if (fans > 1)
      report.add(report.triangle_range(around.triangle[around.offset[v]]),
                 "vertex " + std::to_string(v) + " (0-based) is non-manifold: its triangles form " +
                     std::to_string(fans) +
                     " separate fans (parts of the surface touch at this point); separate the parts");
  }
  report_flipped(surface, uses, report);
  report.finish();
  result.defects = report.count();
  // Enclosed volume by the divergence theorem: the sum over triangles of a . (b x c) / 6 (exact for a closed,
  // consistently oriented surface; positive when the normals point out).
  const Point3 origin = surface.points[static_cast<std::size_t>(surface.triangles.front()[0])];
  for (const Triangle& tri : surface.triangles) {
    const Point3& a = surface.points[static_cast<std::size_t>(tri[0])];
    const Point3& b = surface.points[static_cast<std::size_t>(tri[1])];
    const Point3& c = surface.points[static_cast<std::size_t>(tri[2])];
    result.volume += signed_volume(origin, a, b, c);
    result.area += triangle_area(a, b, c);
  }
  if (result.defects > 0) return result;
  if (!(std::abs(result.volume) > 0.0)) {
    report.add(file_range, "the surface encloses no volume; a volume mesh needs a closed surface around a solid");
    result.defects = report.count();
    return result;
  }
  result.closed = true;
  result.inward = result.volume < 0.0;
  return result;
}

}  // namespace fmpc::sim
