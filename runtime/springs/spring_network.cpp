#include "runtime/springs/spring_network.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <string>
#include <utility>

#include "diagnostics/number_format.h"
#include "runtime/integrate/worker_pool.h"

namespace fmpc::sim {

namespace {

using Edge = std::pair<std::int32_t, std::int32_t>;

Edge make_edge(std::int32_t a, std::int32_t b) { return a < b ? Edge{a, b} : Edge{b, a}; }

// An edge as one sortable number: (first << 32) | second.
std::uint64_t edge_code(const Edge& edge) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(edge.first)) << 32) |
         static_cast<std::uint32_t>(edge.second);
}
Edge edge_of(std::uint64_t code) {
  return {static_cast<std::int32_t>(code >> 32), static_cast<std::int32_t>(code & 0xffffffffu)};
}

// The adjacency is indexed by int32: 2 x springs entries must stay below 2^31.
constexpr std::size_t kMaxSprings = (std::size_t{1} << 30) - 1;

SourceRange mesh_range(const Mesh& mesh, int line) {
  SourceRange range;
  range.file = mesh.source;
  range.line = line;
  range.column = line > 0 ? 1 : 0;
  return range;
}

SpringNetwork empty_network(std::size_t vertex_count) {
  SpringNetwork network;
  network.vertex_count = vertex_count;
  return network;
}

// The first index in [0, count) where bad(i) holds, or count.
template <class Bad>
std::size_t first_where(WorkerPool& pool, std::size_t count, const Bad& bad) {
  std::vector<std::size_t> first(pool.parts(count), count);
  pool.run_parts(count, [&](unsigned part, std::size_t begin, std::size_t end) {
    for (std::size_t i = begin; i < end; ++i) {
      if (bad(i)) {
        first[part] = i;
        return;
      }
    }
  });
  return *std::min_element(first.begin(), first.end());
}

template <std::size_t N>
bool check_indices(const Mesh& mesh, const std::vector<std::array<std::int32_t, N>>& elements,
                   const std::vector<int>& lines, const char* what, DiagnosticList& diagnostics, WorkerPool& pool) {
  const auto out_of_range = [&](std::int32_t v) { return v < 0 || static_cast<std::size_t>(v) >= mesh.points.size(); };
  const std::size_t e = first_where(pool, elements.size(), [&](std::size_t i) {
    return std::any_of(elements[i].begin(), elements[i].end(), out_of_range);
  });
  if (e == elements.size()) return true;
  const std::int32_t v = *std::find_if(elements[e].begin(), elements[e].end(), out_of_range);
  diagnostics.error(mesh_range(mesh, e < lines.size() ? lines[e] : 0),
                    std::string(what) + " " + std::to_string(e) + " refers to vertex " + std::to_string(v) + " of " +
                        std::to_string(mesh.points.size()) + "; repair the mesh first (repair_mesh)");
  return false;
}

// For every vertex, the elements that use it, in increasing order (an element once however often it names it;
// indices out of range are left out: the functions that use the grouping refuse such meshes first).
template <std::size_t N>
KeyGroups group_at_vertices(std::size_t vertex_count, const std::vector<std::array<std::int32_t, N>>& elements,
                            WorkerPool& pool) {
  return group_by_key(pool, vertex_count, elements.size(), [&](std::size_t e, auto emit) {
    const auto& element = elements[e];
    for (std::size_t k = 0; k < N; ++k) {
      if (element[k] < 0 || static_cast<std::size_t>(element[k]) >= vertex_count) continue;
      bool repeated = false;
      for (std::size_t m = 0; m < k; ++m) repeated = repeated || element[m] == element[k];
      if (!repeated) emit(static_cast<std::size_t>(element[k]));
    }
  });
}

// The caller's grouping of the elements by vertex, or one built here.
struct GroupingLease {
  template <std::size_t N>
  GroupingLease(const VertexElements* given, std::size_t vertex_count,
                const std::vector<std::array<std::int32_t, N>>& elements, WorkerPool& pool)
      : own(given ? VertexElements{} : group_at_vertices(vertex_count, elements, pool)), at(given ? *given : own) {}
  VertexElements own;
  const VertexElements& at;
};

// The grouping handed to springs_from_* (no offsets: not given), or one built here.
template <std::size_t N>
VertexElements given_or_grouped(VertexElements given, std::size_t vertex_count,
                                const std::vector<std::array<std::int32_t, N>>& elements, WorkerPool& pool) {
  return given.offset.empty() ? group_at_vertices(vertex_count, elements, pool) : std::move(given);
}

// A triangle side met from its smaller endpoint.
struct EdgeVisit {
  std::int32_t other;     // the larger endpoint
  std::int32_t element;
  std::int32_t place;     // the side: i for vertices i and i+1 (mod 3)
  std::int32_t opposite;  // the third vertex
};

bool operator<(const EdgeVisit& a, const EdgeVisit& b) {
  if (a.other != b.other) return a.other < b.other;
  if (a.element != b.element) return a.element < b.element;
  return a.place < b.place;
}

// The sides of the triangles at vertex a whose smaller endpoint is a, sorted by (other endpoint, triangle, place):
// per edge, in the order in which a loop over the triangles (and over each triangle's sides) meets it, which is the
// order the opposite vertices were listed in before (a std::map of lists keyed by edge).
void sides_from(std::size_t a, const KeyGroups& at, const std::vector<Triangle>& triangles,
                std::vector<EdgeVisit>& visits) {
  visits.clear();
  const auto self = static_cast<std::int32_t>(a);
  for (auto g = at.offset[a]; g < at.offset[a + 1]; ++g) {
    const std::int32_t e = at.item[static_cast<std::size_t>(g)];
    const Triangle& triangle = triangles[static_cast<std::size_t>(e)];
    for (std::size_t i = 0; i < 3; ++i) {
      const std::int32_t x = triangle[i], y = triangle[(i + 1) % 3];
      if (x != y && std::min(x, y) == self)
        visits.push_back({std::max(x, y), e, static_cast<std::int32_t>(i), triangle[(i + 2) % 3]});
    }
  }
  std::sort(visits.begin(), visits.end());
}

// The edges of the elements at vertex a whose smaller endpoint is a, in the order of a loop over the elements (and
// over each element's edges), unsorted: the other endpoint and the element of each. `unique` receives the distinct
// other endpoints, sorted.
template <std::size_t N>
void edges_in_loop_order(std::size_t a, const KeyGroups& at, const std::vector<std::array<std::int32_t, N>>& elements,
                         std::vector<std::int32_t>& others, std::vector<std::int32_t>& owners,
                         std::vector<std::int32_t>& unique) {
  others.clear();
  owners.clear();
  const auto self = static_cast<std::int32_t>(a);
  for (auto g = at.offset[a]; g < at.offset[a + 1]; ++g) {
    const std::int32_t e = at.item[static_cast<std::size_t>(g)];
    const auto& element = elements[static_cast<std::size_t>(e)];
    for (std::size_t i = 0; i < N; ++i) {
      for (std::size_t j = i + 1; j < N; ++j) {  // a triangle's sides, a tetrahedron's six edges
        if (element[i] != element[j] && std::min(element[i], element[j]) == self) {
          others.push_back(std::max(element[i], element[j]));
          owners.push_back(e);
        }
      }
    }
  }
  unique = others;
  std::sort(unique.begin(), unique.end());
  unique.erase(std::unique(unique.begin(), unique.end()), unique.end());
}

// One spring per distinct element edge, sorted by (first, second), element_measure = the sum of the measures of the
// elements that contain it, added in element order (the order in which a loop over the elements accumulated them
// in a std::map before, so the sums keep its bits); `begin` receives each vertex's first spring (vertex_count + 1
// entries). Two passes over the vertices: count, then fill in place.
template <std::size_t N>
bool element_edge_springs(const Mesh& mesh, const std::vector<std::array<std::int32_t, N>>& elements,
                          const KeyGroups& at, const std::vector<double>& measure, SpringKind kind,
                          SpringNetwork& network, std::vector<std::int64_t>& begin, DiagnosticList& diagnostics,
                          WorkerPool& pool) {
  const std::size_t n = mesh.points.size();
  resize_large(begin, n + 1);
  begin[0] = 0;
  pool.run(n, [&](std::size_t first, std::size_t last) {
    std::vector<std::int32_t> others, owners, unique;
    for (std::size_t a = first; a < last; ++a) {
      edges_in_loop_order(a, at, elements, others, owners, unique);
      begin[a + 1] = static_cast<std::int64_t>(unique.size());
    }
  });
  for (std::size_t a = 0; a < n; ++a) begin[a + 1] += begin[a];
  const auto total = static_cast<std::size_t>(begin[n]);
  if (total > kMaxSprings) {
    diagnostics.error(mesh_range(mesh, 0), "the mesh has " + std::to_string(total) + " edges, more than the " +
                                               std::to_string(kMaxSprings) +
                                               " springs a network can index (int32 adjacency); use a coarser mesh");
    return false;
  }
  resize_large(network.first, total);
  resize_large(network.second, total);
  resize_large(network.kind, total);
  resize_large(network.element_measure, total);
  pool.run(n, [&](std::size_t first, std::size_t last) {
    std::vector<std::int32_t> others, owners, unique;
    std::vector<double> sums;
    for (std::size_t a = first; a < last; ++a) {
      edges_in_loop_order(a, at, elements, others, owners, unique);
      sums.assign(unique.size(), 0.0);
      for (std::size_t k = 0; k < others.size(); ++k) {
        const auto slot = std::lower_bound(unique.begin(), unique.end(), others[k]) - unique.begin();
        sums[static_cast<std::size_t>(slot)] += measure[static_cast<std::size_t>(owners[k])];
      }
      const auto s = static_cast<std::size_t>(begin[a]);
      for (std::size_t k = 0; k < unique.size(); ++k) {
        network.first[s + k] = static_cast<std::int32_t>(a);
        network.second[s + k] = unique[k];
        network.kind[s + k] = kind;
        network.element_measure[s + k] = sums[k];
      }
    }
  });
  return true;
}

// Whether springs [begin[u], begin[u+1]) of a network sorted by (first, second) join u < w.
bool joined(const SpringNetwork& network, const std::vector<std::int64_t>& begin, const Edge& edge) {
  const auto first = network.second.begin() + begin[static_cast<std::size_t>(edge.first)];
  const auto last = network.second.begin() + begin[static_cast<std::size_t>(edge.first) + 1];
  return std::binary_search(first, last, edge.second);
}

// The bending links of springs_from_triangles: for every vertex j and structural neighbour i, the neighbour k of j
// with the most negative cos(i-j-k), kept when the angle reaches min_angle_degrees and no structural spring joins
// i and k and no pair of triangles has them opposite a shared edge (`across`, sorted codes). Ties go to the smaller
// k (neighbours are visited in increasing order), so the result does not depend on the order of the triangles.
std::vector<std::uint64_t> bending_links(const Mesh& mesh, const std::vector<Point3>& points, const KeyGroups& at,
                                         const SpringNetwork& structural, const std::vector<std::int64_t>& begin,
                                         const std::vector<std::uint64_t>& across, double min_angle_degrees,
                                         WorkerPool& pool) {
  const double pi = std::acos(-1.0);
  const double max_cosine = std::cos(min_angle_degrees * pi / 180.0);
  std::vector<std::vector<std::uint64_t>> found(pool.parts(points.size()));
  pool.run_parts(points.size(), [&](unsigned part, std::size_t first, std::size_t last) {
    std::vector<std::int32_t> around;
    for (std::size_t j = first; j < last; ++j) {
      const auto self = static_cast<std::int32_t>(j);
      around.clear();
      for (auto g = at.offset[j]; g < at.offset[j + 1]; ++g) {
        const Triangle& t = mesh.triangles[static_cast<std::size_t>(at.item[static_cast<std::size_t>(g)])];
        for (std::size_t i = 0; i < 3; ++i) {
          const std::int32_t x = t[i], y = t[(i + 1) % 3];
          if (x == y) continue;
          if (x == self) around.push_back(y);
          if (y == self) around.push_back(x);
        }
      }
      std::sort(around.begin(), around.end());
      around.erase(std::unique(around.begin(), around.end()), around.end());
      const Point3& centre = points[j];
      for (const std::int32_t i : around) {
        const Point3& a = points[static_cast<std::size_t>(i)];
        std::int32_t best = -1;
        double best_cosine = 2.0;
        for (const std::int32_t k : around) {
          if (k == i) continue;
          const Point3& b = points[static_cast<std::size_t>(k)];
          double dot = 0.0;
          for (std::size_t c = 0; c < 3; ++c) dot += (a[c] - centre[c]) * (b[c] - centre[c]);
          const double cosine = dot / (distance(a, centre) * distance(b, centre));
          if (cosine < best_cosine) {
            best_cosine = cosine;
            best = k;
          }
        }
        if (best < 0 || !(best_cosine <= max_cosine)) continue;
        const Edge link = make_edge(i, best);
        if (!joined(structural, begin, link) && !std::binary_search(across.begin(), across.end(), edge_code(link)))
          found[part].push_back(edge_code(link));
      }
    }
  });
  std::vector<std::uint64_t> links;
  for (const auto& part : found) links.insert(links.end(), part.begin(), part.end());
  parallel_sort(pool, links, std::less<std::uint64_t>());
  links.erase(std::unique(links.begin(), links.end()), links.end());
  return links;
}

void append_links(SpringNetwork& network, const std::vector<std::uint64_t>& links, SpringKind kind) {
  for (const std::uint64_t code : links) {
    const Edge edge = edge_of(code);
    network.first.push_back(edge.first);
    network.second.push_back(edge.second);
    network.kind.push_back(kind);
    network.element_measure.push_back(0.0);
  }
}

}  // namespace

const char* mapping_citation(StiffnessMapping mapping) {
  switch (mapping) {
    case StiffnessMapping::Uniform:
      return "uniform stiffness";
    case StiffnessMapping::StiffnessOverLength:
      return "stiffness over rest length (SOFA)";
    case StiffnessMapping::VanGelder1998:
      return "Van Gelder 1998";
    case StiffnessMapping::LloydSzekelyHarders2007:
      return "Lloyd, Szekely & Harders 2007";
  }
  return "unknown mapping";
}

bool is_modulus_mapping(StiffnessMapping mapping) {
  return mapping == StiffnessMapping::VanGelder1998 || mapping == StiffnessMapping::LloydSzekelyHarders2007;
}

VertexElements elements_at_vertices(const Mesh& mesh, WorkerPool* given_pool) {
  PoolLease lease(given_pool, 0, mesh.points.size() + mesh.tetrahedra.size() + mesh.triangles.size());
  return mesh.tetrahedra.empty() ? group_at_vertices(mesh.points.size(), mesh.triangles, lease.pool())
                                 : group_at_vertices(mesh.points.size(), mesh.tetrahedra, lease.pool());
}

SpringNetwork springs_from_tetrahedra(const Mesh& mesh, DiagnosticList& diagnostics, WorkerPool* pool) {
  return springs_from_tetrahedra(mesh, mesh.points, diagnostics, pool);
}

SpringNetwork springs_from_tetrahedra(const Mesh& mesh, const std::vector<Point3>& points, DiagnosticList& diagnostics,
                                     WorkerPool* given_pool, VertexElements given_at) {
  PoolLease lease(given_pool, 0, mesh.points.size() + mesh.tetrahedra.size());
  WorkerPool& pool = lease.pool();
  SpringNetwork network;
  network.vertex_count = mesh.points.size();
  if (!check_indices(mesh, mesh.tetrahedra, mesh.tetrahedron_lines, "tetrahedron", diagnostics, pool)) return network;
  std::vector<double> volume;
  resize_large(volume, mesh.tetrahedra.size());
  pool.run(volume.size(), [&](std::size_t first, std::size_t last) {
    for (std::size_t e = first; e < last; ++e) {
      const Tetrahedron& t = mesh.tetrahedra[e];
      volume[e] = std::abs(signed_volume(points[static_cast<std::size_t>(t[0])], points[static_cast<std::size_t>(t[1])],
                                         points[static_cast<std::size_t>(t[2])], points[static_cast<std::size_t>(t[3])]));
    }
  });
  std::vector<std::int64_t> begin;
  {
    // Released before the CSR is built: the grouping and the CSR are the two largest arrays of the build after the
    // springs themselves, and are never held together.
    const VertexElements at = given_or_grouped(std::move(given_at), mesh.points.size(), mesh.tetrahedra, pool);
    if (!element_edge_springs(mesh, mesh.tetrahedra, at, volume, SpringKind::TetrahedronEdge, network, begin,
                              diagnostics, pool))
      return empty_network(mesh.points.size());
  }
  std::vector<double>().swap(volume);
  std::vector<std::int64_t>().swap(begin);
  build_adjacency(network, &pool);
  return network;
}

SpringNetwork springs_from_triangles(const Mesh& mesh, const TriangleSpringOptions& options,
                                     DiagnosticList& diagnostics, WorkerPool* pool) {
  return springs_from_triangles(mesh, mesh.points, options, diagnostics, pool);
}

SpringNetwork springs_from_triangles(const Mesh& mesh, const std::vector<Point3>& points,
                                     const TriangleSpringOptions& options, DiagnosticList& diagnostics,
                                     WorkerPool* given_pool, VertexElements given_at) {
  PoolLease lease(given_pool, 0, mesh.points.size() + mesh.triangles.size());
  WorkerPool& pool = lease.pool();
  SpringNetwork network;
  network.vertex_count = mesh.points.size();
  if (!check_indices(mesh, mesh.triangles, mesh.triangle_lines, "triangle", diagnostics, pool)) return network;
  std::vector<double> area(mesh.triangles.size());
  pool.run(area.size(), [&](std::size_t first, std::size_t last) {
    for (std::size_t e = first; e < last; ++e) {
      const Triangle& t = mesh.triangles[e];
      area[e] = triangle_area(points[static_cast<std::size_t>(t[0])], points[static_cast<std::size_t>(t[1])],
                              points[static_cast<std::size_t>(t[2])]);
    }
  });
  VertexElements at = given_or_grouped(std::move(given_at), mesh.points.size(), mesh.triangles, pool);
  // Structural springs (every triangle edge once), and for each edge the pairs of vertices opposite it in two of
  // its triangles (`across`): the flexion candidates.
  SpringNetwork structural;
  structural.vertex_count = mesh.points.size();
  std::vector<std::int64_t> begin;
  if (!element_edge_springs(mesh, mesh.triangles, at, area, SpringKind::Structural, structural, begin, diagnostics,
                            pool))
    return network;
  // For each edge, the vertices opposite it in its triangles, in the order the triangles meet it; every pair of
  // distinct ones is a flexion candidate.
  std::vector<std::uint64_t> across;
  {
    std::vector<std::vector<std::uint64_t>> found(pool.parts(mesh.points.size()));
    pool.run_parts(mesh.points.size(), [&](unsigned part, std::size_t first, std::size_t last) {
      std::vector<EdgeVisit> visits;
      for (std::size_t a = first; a < last; ++a) {
        sides_from(a, at, mesh.triangles, visits);
        for (std::size_t i = 0; i < visits.size();) {
          std::size_t j = i;
          while (j < visits.size() && visits[j].other == visits[i].other) ++j;
          for (std::size_t p = i; p < j; ++p) {
            for (std::size_t q = p + 1; q < j; ++q) {
              if (visits[p].opposite == visits[q].opposite) continue;
              found[part].push_back(edge_code(make_edge(visits[p].opposite, visits[q].opposite)));
            }
          }
          i = j;
        }
      }
    });
    for (const auto& part : found) across.insert(across.end(), part.begin(), part.end());
    parallel_sort(pool, across, std::less<std::uint64_t>());
    across.erase(std::unique(across.begin(), across.end()), across.end());
  }
  std::vector<double>().swap(area);
  if (options.structural) network = structural;
  network.vertex_count = mesh.points.size();
  if (options.flexion) {
    std::vector<std::uint64_t> flexion;
    for (const std::uint64_t code : across)
      if (!joined(structural, begin, edge_of(code))) flexion.push_back(code);
    append_links(network, flexion, SpringKind::Flexion);
  }
  if (options.bending) {
    append_links(network,
                 bending_links(mesh, points, at, structural, begin, across, options.bending_min_angle_degrees, pool),
                 SpringKind::Bending);
  }
  if (network.size() > kMaxSprings) {
    diagnostics.error(mesh_range(mesh, 0), "the mesh gives " + std::to_string(network.size()) + " springs, more than the " +
                                               std::to_string(kMaxSprings) +
                                               " a network can index (int32 adjacency); use a coarser mesh");
    return empty_network(mesh.points.size());
  }
  // Not held with the CSR (see springs_from_tetrahedra).
  at = VertexElements{};
  structural = SpringNetwork{};
  std::vector<std::int64_t>().swap(begin);
  std::vector<std::uint64_t>().swap(across);
  build_adjacency(network, &pool);
  return network;
}

bool compute_rest_lengths(SpringNetwork& network, const std::vector<Point3>& points, DiagnosticList& diagnostics,
                          double min_relative_length, WorkerPool* given_pool) {
  PoolLease lease(given_pool, 0, network.size());
  WorkerPool& pool = lease.pool();
  resize_large(network.rest_length, network.size());
  pool.run(network.size(), [&](std::size_t first, std::size_t last) {
    for (std::size_t s = first; s < last; ++s)
      network.rest_length[s] = distance(points[static_cast<std::size_t>(network.first[s])],
                                        points[static_cast<std::size_t>(network.second[s])]);
  });
  if (network.size() == 0) return true;
  double total = 0.0;  // in spring order, one thread: the mean has the same bits for every thread count
  for (const double length : network.rest_length) total += length;
  const double mean = total / static_cast<double>(network.size());
  const std::size_t s = first_where(pool, network.size(), [&](std::size_t i) {
    const double length = network.rest_length[i];
    return !(length > min_relative_length * mean) || !std::isfinite(length);
  });
  if (s == network.size()) return true;
  const double length = network.rest_length[s];
  SourceRange range;
  diagnostics.error(range, "spring " + std::to_string(s) + " between vertices " + std::to_string(network.first[s]) +
                               " and " + std::to_string(network.second[s]) + " has rest length " +
                               std::to_string(length) + " (mean " + std::to_string(mean) +
                               "); its direction is undefined: merge the duplicate vertices (repair_mesh)");
  return false;
}

void build_adjacency(SpringNetwork& network, WorkerPool* given_pool) {
  PoolLease lease(given_pool, 0, network.size());
  WorkerPool& pool = lease.pool();
  const std::size_t n = network.vertex_count;
  // Each spring at both its ends (twice at one end if it joins a vertex to itself), each vertex's list sorted by
  // spring: the order of the sequential fill that walks the springs in order.
  KeyGroups groups = group_by_key(pool, n, network.size(), [&](std::size_t s, auto emit) {
    emit(static_cast<std::size_t>(network.first[s]));
    emit(static_cast<std::size_t>(network.second[s]));
  });
  resize_large(network.adjacency_offset, n + 1);
  pool.run(n + 1, [&](std::size_t first, std::size_t last) {
    for (std::size_t v = first; v < last; ++v) network.adjacency_offset[v] = static_cast<std::int32_t>(groups.offset[v]);
  });
  std::vector<std::int64_t>().swap(groups.offset);
  network.adjacency_spring = std::move(groups.item);
}

void write_adjacency_neighbours(const SpringNetwork& network, std::int32_t base, std::int32_t* out, WorkerPool& pool) {
  pool.run(network.vertex_count, [&](std::size_t first, std::size_t last) {
    for (std::size_t v = first; v < last; ++v)
      for (auto e = network.adjacency_offset[v]; e < network.adjacency_offset[v + 1]; ++e)
        out[static_cast<std::size_t>(e)] = base + adjacency_neighbour(network, v, static_cast<std::size_t>(e));
  });
}

std::vector<std::int32_t> adjacency_neighbours(const SpringNetwork& network, WorkerPool* given_pool) {
  std::vector<std::int32_t> out;
  if (network.adjacency_offset.size() != network.vertex_count + 1) return out;
  resize_large(out, network.adjacency_spring.size());
  PoolLease lease(given_pool, 0, out.size());
  write_adjacency_neighbours(network, 0, out.data(), lease.pool());
  return out;
}

bool assign_stiffness(SpringNetwork& network, const StiffnessSpec& spec, DiagnosticList& diagnostics,
                      WorkerPool* given_pool, ElementMeasures measures) {
  PoolLease lease(given_pool, 0, network.size());
  WorkerPool& pool = lease.pool();
  SourceRange range;
  const auto refuse = [&](const std::string& message) {
    diagnostics.error(range, message);
    if (measures == ElementMeasures::Release) std::vector<double>().swap(network.element_measure);
    return false;
  };
  if (!spec.per_spring.empty() && spec.per_spring.size() != network.size()) {
    return refuse("per-spring stiffness values: " + std::to_string(spec.per_spring.size()) + " given for " +
                  std::to_string(network.size()) + " springs; give one per spring");
  }
  if (network.rest_length.size() != network.size())
    return refuse("rest lengths are missing; call compute_rest_lengths first");
  const bool modulus = is_modulus_mapping(spec.mapping);
  if (modulus && !(spec.thickness > 0.0 && std::isfinite(spec.thickness))) {
    return refuse(std::string("the membrane thickness must be a positive number for the ") +
                  mapping_citation(spec.mapping) + " mapping");
  }
  if (modulus && network.element_measure.size() != network.size()) {
    return refuse(std::string("the ") + mapping_citation(spec.mapping) +
                  " mapping needs the springs' element measures; build the network with springs_from_tetrahedra or "
                  "springs_from_triangles");
  }
  // Release: each spring's stiffness is written over its own measure once that was read, so the two arrays are
  // never held together. Without measures (a mapping that needs none) the stiffness gets an array of its own.
  const bool in_place = measures == ElementMeasures::Release && network.element_measure.size() == network.size();
  if (in_place) network.stiffness.swap(network.element_measure);
  if (measures == ElementMeasures::Release) std::vector<double>().swap(network.element_measure);
  if (!in_place) resize_large(network.stiffness, network.size());
  const std::vector<double>& measure = in_place ? network.stiffness : network.element_measure;
  const auto spring_name = [&](std::size_t s) {
    return "spring " + std::to_string(s) + " (vertices " + std::to_string(network.first[s]) + " and " +
           std::to_string(network.second[s]) + ")";
  };
  // The error for spring s, if its value or its elements cannot give it a stiffness (checked in this order).
  const auto spring_error = [&](std::size_t s) -> std::optional<std::string> {
    const double value = spec.per_spring.empty() ? spec.value : spec.per_spring[s];
    if (modulus && !(value > 0.0 && std::isfinite(value))) {
      // A zero modulus leaves the network without stiffness (every vertex free), NaN would reach the integrator.
      return spring_name(s) + ": Young's modulus " + format_number(value) + " Pa (" + mapping_citation(spec.mapping) +
             " mapping) is not a positive, finite number; fix the material value";
    }
    if (!(value >= 0.0) || !std::isfinite(value)) {
      return spring_name(s) + ": stiffness parameter " + std::to_string(value) +
             " is not a finite, non-negative number; fix the material value";
    }
    const SpringKind kind = network.kind[s];
    const bool element_spring = kind == SpringKind::TetrahedronEdge || kind == SpringKind::Structural;
    if (modulus && element_spring && !(measure[s] > 0.0)) {
      return spring_name(s) + " belongs only to elements of zero " +
             (kind == SpringKind::Structural ? "area" : "volume") +
             ", so the mapping gives it no stiffness; repair the mesh (repair_mesh drops degenerate elements)";
    }
    return std::nullopt;
  };
  const auto stiffness_of = [&](std::size_t s) {
    const double value = spec.per_spring.empty() ? spec.value : spec.per_spring[s];
    const double length = network.rest_length[s];
    const SpringKind kind = network.kind[s];
    // Read only by the modulus mappings: a network built by hand may have no measures.
    const auto element = [&] { return kind == SpringKind::Structural ? spec.thickness * measure[s] : measure[s]; };
    switch (spec.mapping) {
      case StiffnessMapping::Uniform:
        return value;
      case StiffnessMapping::StiffnessOverLength:
        return value / length;
      case StiffnessMapping::VanGelder1998:
        return value * element() / (length * length);
      case StiffnessMapping::LloydSzekelyHarders2007: {
        // Lloyd et al. 2007: k = (2 sqrt 2 / 25) E l on a regular tetrahedron = (24/25) E V / l^2; the equilateral
        // triangle's k = (sqrt 3 / 4) E h = E h A / l^2 (see StiffnessMapping).
        const double factor = kind == SpringKind::TetrahedronEdge ? 24.0 / 25.0 : 1.0;
        return factor * value * element() / (length * length);
      }
    }
    return 0.0;
  };
  // The springs before the first bad one get their stiffness and the rest 0, as a loop that stops there would leave
  // them. Each part keeps its first error's message: in place, the bad spring's measure is gone once it is read.
  std::vector<std::size_t> bad(pool.parts(network.size()), network.size());
  std::vector<std::string> bad_message(bad.size());
  pool.run_parts(network.size(), [&](unsigned part, std::size_t first, std::size_t last) {
    for (std::size_t s = first; s < last; ++s) {
      if (bad[part] == network.size()) {
        if (auto error = spring_error(s)) {
          bad[part] = s;
          bad_message[part] = std::move(*error);
        }
      }
      network.stiffness[s] = bad[part] == network.size() ? stiffness_of(s) : 0.0;
    }
  });
  const auto worst = std::min_element(bad.begin(), bad.end());
  const std::size_t first_bad = *worst;
  if (first_bad < network.size()) {
    pool.run(network.size() - first_bad, [&](std::size_t first, std::size_t last) {
      for (std::size_t s = first_bad + first; s < first_bad + last; ++s) network.stiffness[s] = 0.0;
    });
    diagnostics.error(range, bad_message[static_cast<std::size_t>(worst - bad.begin())]);
    return false;
  }
  if (modulus) {
    // Flexion and bending springs: a fraction of the mean structural stiffness at their two endpoints (which this
    // pass does not change).
    pool.run(network.size(), [&](std::size_t first, std::size_t last) {
      for (std::size_t s = first; s < last; ++s) {
        if (network.kind[s] != SpringKind::Flexion && network.kind[s] != SpringKind::Bending) continue;
        double sum = 0.0;
        int count = 0;
        for (const std::int32_t v : {network.first[s], network.second[s]}) {
          const auto vi = static_cast<std::size_t>(v);
          for (auto e = network.adjacency_offset[vi]; e < network.adjacency_offset[vi + 1]; ++e) {
            const auto other = static_cast<std::size_t>(network.adjacency_spring[static_cast<std::size_t>(e)]);
            if (network.kind[other] == SpringKind::Structural) {
              sum += network.stiffness[other];
              ++count;
            }
          }
        }
        network.stiffness[s] = count > 0 ? spec.flexion_fraction * sum / count : 0.0;
      }
    });
  }
  return true;
}

std::vector<double> lumped_masses(const Mesh& mesh, const MassSpec& spec, DiagnosticList& diagnostics,
                                  WorkerPool* pool) {
  return lumped_masses(mesh, mesh.points, spec, diagnostics, pool);
}

namespace {

// mass[v] = the sum of share[e] over the elements at v, in increasing element order, once for each time the
// element names v: the bits of a loop over the elements that adds each share to each of its vertices.
template <std::size_t N>
void gather_shares(const std::vector<std::array<std::int32_t, N>>& elements, const std::vector<double>& share,
                   const VertexElements* given_at, std::vector<double>& mass, WorkerPool& pool) {
  const GroupingLease grouping(given_at, mass.size(), elements, pool);
  const KeyGroups& at = grouping.at;
  pool.run(mass.size(), [&](std::size_t first, std::size_t last) {
    for (std::size_t v = first; v < last; ++v) {
      double sum = 0.0;
      for (auto g = at.offset[v]; g < at.offset[v + 1]; ++g) {
        const auto e = static_cast<std::size_t>(at.item[static_cast<std::size_t>(g)]);
        for (const std::int32_t corner : elements[e])
          if (static_cast<std::size_t>(corner) == v) sum += share[e];
      }
      mass[v] = sum;
    }
  });
}

}  // namespace

std::vector<double> lumped_masses(const Mesh& mesh, const std::vector<Point3>& points, const MassSpec& spec,
                                  DiagnosticList& diagnostics, WorkerPool* given_pool, const VertexElements* at) {
  PoolLease lease(given_pool, 0, mesh.points.size() + mesh.tetrahedra.size() + mesh.triangles.size());
  WorkerPool& pool = lease.pool();
  SourceRange range;
  range.file = mesh.source;
  if (!(spec.value > 0.0) || !std::isfinite(spec.value)) {
    diagnostics.error(range, "the density or total mass must be a positive, finite number");
    return {};
  }
  if (!mesh.tetrahedra.empty()
          ? !check_indices(mesh, mesh.tetrahedra, mesh.tetrahedron_lines, "tetrahedron", diagnostics, pool)
          : !check_indices(mesh, mesh.triangles, mesh.triangle_lines, "triangle", diagnostics, pool))
    return {};
  std::vector<double> mass;
  resize_large(mass, mesh.points.size());
  const double density = spec.source == MassSpec::Source::Density ? spec.value : 1.0;
  if (!mesh.tetrahedra.empty()) {
    std::vector<double> share;
    resize_large(share, mesh.tetrahedra.size());
    pool.run(share.size(), [&](std::size_t first, std::size_t last) {
      for (std::size_t e = first; e < last; ++e) {
        const Tetrahedron& t = mesh.tetrahedra[e];
        share[e] = density *
                   std::abs(signed_volume(points[static_cast<std::size_t>(t[0])], points[static_cast<std::size_t>(t[1])],
                                          points[static_cast<std::size_t>(t[2])], points[static_cast<std::size_t>(t[3])])) /
                   4.0;
      }
    });
    gather_shares(mesh.tetrahedra, share, at, mass, pool);
  } else if (!mesh.triangles.empty()) {
    std::vector<double> share(mesh.triangles.size());
    pool.run(share.size(), [&](std::size_t first, std::size_t last) {
      for (std::size_t e = first; e < last; ++e) {
        const Triangle& t = mesh.triangles[e];
        share[e] = density * spec.thickness *
                   triangle_area(points[static_cast<std::size_t>(t[0])], points[static_cast<std::size_t>(t[1])],
                                 points[static_cast<std::size_t>(t[2])]) /
                   3.0;
      }
    });
    gather_shares(mesh.triangles, share, at, mass, pool);
  } else if (spec.source == MassSpec::Source::TotalMass) {
    std::fill(mass.begin(), mass.end(), 1.0);
  }
  if (spec.source == MassSpec::Source::TotalMass) {
    double total = 0.0;  // in vertex order, one thread: the same bits for every thread count
    for (const double m : mass) total += m;
    if (total > 0.0) {
      pool.run(mass.size(), [&](std::size_t first, std::size_t last) {
        for (std::size_t v = first; v < last; ++v) mass[v] *= spec.value / total;
      });
    }
  }
  const std::size_t v = first_where(pool, mass.size(), [&](std::size_t i) { return !(mass[i] > 0.0); });
  if (v < mass.size()) {
    diagnostics.error(range, "vertex " + std::to_string(v) +
                                 " gets no mass (no element uses it or its elements are flat); repair the mesh "
                                 "(repair_mesh removes unreferenced vertices)");
    return {};
  }
  return mass;
}

bool assign_damping(SpringNetwork& network, const std::vector<double>& mass, const DampingSpec& spec,
                    DiagnosticList& diagnostics, WorkerPool* given_pool) {
  PoolLease lease(given_pool, 0, network.size());
  WorkerPool& pool = lease.pool();
  SourceRange range;
  if (network.stiffness.size() != network.size()) {
    diagnostics.error(range, "stiffness is missing; call assign_stiffness first");
    return false;
  }
  if (!(spec.ratio >= 0.0) || !std::isfinite(spec.ratio)) {
    diagnostics.error(range, "the damping ratio must be a finite, non-negative number");
    return false;
  }
  if (spec.rule == DampingSpec::Rule::ThesisNaturalFrequency && !(spec.natural_frequency > 0.0)) {
    diagnostics.error(range, "the thesis damping rule (gamma = 2 zeta k / w) needs a positive natural frequency w");
    return false;
  }
  if (spec.rule == DampingSpec::Rule::Fixed && !(spec.value >= 0.0)) {
    diagnostics.error(range, "a fixed damping coefficient must be non-negative");
    return false;
  }
  const bool undamped = (spec.rule == DampingSpec::Rule::Fixed && spec.value == 0.0) ||
                        (spec.rule != DampingSpec::Rule::Fixed && spec.ratio == 0.0);
  if (undamped) {
    network.damping.clear();  // no dashpots: the backends allocate and read no damping array
    network.damping.shrink_to_fit();
    return true;
  }
  resize_large(network.damping, network.size());
  pool.run(network.size(), [&](std::size_t first, std::size_t last) {
    for (std::size_t s = first; s < last; ++s) {
      const double k = network.stiffness[s];
      switch (spec.rule) {
        case DampingSpec::Rule::DampingRatio: {
          const double ma = mass[static_cast<std::size_t>(network.first[s])];
          const double mb = mass[static_cast<std::size_t>(network.second[s])];
          network.damping[s] = 2.0 * spec.ratio * std::sqrt(k * ma * mb / (ma + mb));
          break;
        }
        case DampingSpec::Rule::ThesisNaturalFrequency:
          network.damping[s] = 2.0 * spec.ratio * k / spec.natural_frequency;
          break;
        case DampingSpec::Rule::Fixed:
          network.damping[s] = spec.value;
          break;
      }
    }
  });
  return true;
}

}  // namespace fmpc::sim
