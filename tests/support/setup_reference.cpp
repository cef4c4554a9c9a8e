// The host setup as it was before it was made O(N log N) and multi-threaded (git: runtime/mesh/mesh_check.cpp,
// runtime/mesh/mesh.cpp, runtime/springs/spring_network.cpp and runtime/scene/spring_model_builder.cpp at 62131b7),
// kept verbatim as the reference the equivalence tests compare the new code with, bit for bit. Not used elsewhere.
#include "tests/support/setup_reference.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <string>
#include <utility>

#include "diagnostics/number_format.h"

namespace fmpc::sim::reference {

namespace {

template <std::size_t N>
bool indices_in_range(const std::array<std::int32_t, N>& element, std::size_t vertex_count) {
  return std::all_of(element.begin(), element.end(),
                     [&](std::int32_t v) { return v >= 0 && static_cast<std::size_t>(v) < vertex_count; });
}

template <std::size_t N>
bool has_repeated_vertex(const std::array<std::int32_t, N>& element) {
  for (std::size_t i = 0; i < N; ++i) {
    for (std::size_t j = i + 1; j < N; ++j) {
      if (element[i] == element[j]) return true;
    }
  }
  return false;
}

template <std::size_t N>
double longest_edge(const Mesh& mesh, const std::array<std::int32_t, N>& element) {
  double longest = 0.0;
  for (std::size_t i = 0; i < N; ++i) {
    for (std::size_t j = i + 1; j < N; ++j) {
      longest = std::max(longest, distance(mesh.points[static_cast<std::size_t>(element[i])],
                                           mesh.points[static_cast<std::size_t>(element[j])]));
    }
  }
  return longest;
}

int line_of(const std::vector<int>& lines, std::size_t index) { return index < lines.size() ? lines[index] : 0; }

double duplicate_tolerance(const Mesh& mesh, const MeshCheckOptions& options) {
  if (options.duplicate_distance >= 0.0) return options.duplicate_distance;
  if (mesh.points.empty()) return 0.0;
  Point3 low = mesh.points[0], high = mesh.points[0];
  for (const Point3& p : mesh.points) {
    for (std::size_t a = 0; a < 3; ++a) {
      low[a] = std::min(low[a], p[a]);
      high[a] = std::max(high[a], p[a]);
    }
  }
  return 1e-9 * distance(low, high);
}

// For each vertex, the earliest vertex within `tolerance` (itself when none): a sweep over vertices sorted by x.
std::vector<std::size_t> duplicate_representatives(const Mesh& mesh, double tolerance) {
  const std::size_t n = mesh.points.size();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return mesh.points[a] < mesh.points[b] || (mesh.points[a] == mesh.points[b] && a < b);
  });
  std::vector<std::size_t> representative(n);
  std::iota(representative.begin(), representative.end(), std::size_t{0});
  for (std::size_t s = 0; s < n; ++s) {
    const std::size_t i = order[s];
    for (std::size_t t = s + 1; t < n && mesh.points[order[t]][0] - mesh.points[i][0] <= tolerance; ++t) {
      const std::size_t j = order[t];
      if (distance(mesh.points[i], mesh.points[j]) <= tolerance) {
        const std::size_t first = std::min(representative[i], representative[j]);
        const std::size_t later = std::max(i, j);
        if (first < representative[later]) representative[later] = first;
      }
    }
  }
  // Chains (c near b near a) all point at the earliest member.
  for (std::size_t v = 0; v < n; ++v) representative[v] = representative[representative[v]];
  return representative;
}

template <std::size_t N>
void check_elements(const Mesh& mesh, const std::vector<std::array<std::int32_t, N>>& elements,
                    const std::vector<int>& lines, const MeshCheckOptions& options,
                    std::vector<MeshFinding>& findings) {
  constexpr bool tetrahedra = N == 4;
  std::map<std::array<std::int32_t, N>, std::size_t> first_with_vertices;
  for (std::size_t e = 0; e < elements.size(); ++e) {
    const auto& element = elements[e];
    MeshFinding finding;
    finding.index = e;
    finding.line = line_of(lines, e);
    if (!indices_in_range(element, mesh.points.size())) {
      finding.kind = MeshFindingKind::IndexOutOfRange;
      findings.push_back(finding);
      continue;
    }
    double measure = 0.0;
    double scale = longest_edge(mesh, element);
    if constexpr (tetrahedra) {
      measure = signed_volume(mesh, element);
      scale = scale * scale * scale;
    } else {
      measure = triangle_area(mesh, element);
      scale = scale * scale;
    }
    finding.value = measure;
    if (has_repeated_vertex(element) || std::abs(measure) <= options.shape_tolerance * scale) {
      finding.kind = tetrahedra ? MeshFindingKind::DegenerateTetrahedron : MeshFindingKind::DegenerateTriangle;
      findings.push_back(finding);
      continue;
    }
    if (tetrahedra && measure < 0.0) {
      finding.kind = MeshFindingKind::InvertedTetrahedron;
      findings.push_back(finding);
    }
    auto key = element;
    std::sort(key.begin(), key.end());
    const auto [it, inserted] = first_with_vertices.emplace(key, e);
    if (!inserted) {
      finding.kind = tetrahedra ? MeshFindingKind::DuplicateTetrahedron : MeshFindingKind::DuplicateTriangle;
      finding.other = it->second;
      findings.push_back(finding);
    }
  }
}

}  // namespace

std::vector<MeshFinding> check_mesh(const Mesh& mesh, const MeshCheckOptions& options) {
  std::vector<MeshFinding> element_findings;
  check_elements(mesh, mesh.tetrahedra, mesh.tetrahedron_lines, options, element_findings);
  std::vector<MeshFinding> triangle_findings;
  check_elements(mesh, mesh.triangles, mesh.triangle_lines, options, triangle_findings);
  std::vector<MeshFinding> findings;
  for (const auto& f : element_findings) {
    if (f.kind == MeshFindingKind::IndexOutOfRange) findings.push_back(f);
  }
  for (const auto& f : triangle_findings) {
    if (f.kind == MeshFindingKind::IndexOutOfRange) findings.push_back(f);
  }
  for (const auto& f : element_findings) {
    if (f.kind != MeshFindingKind::IndexOutOfRange) findings.push_back(f);
  }
  for (const auto& f : triangle_findings) {
    if (f.kind != MeshFindingKind::IndexOutOfRange) findings.push_back(f);
  }
  const double tolerance = duplicate_tolerance(mesh, options);
  const std::vector<std::size_t> representative = duplicate_representatives(mesh, tolerance);
  for (std::size_t v = 0; v < representative.size(); ++v) {
    if (representative[v] != v) {
      MeshFinding finding;
      finding.kind = MeshFindingKind::DuplicateVertex;
      finding.index = v;
      finding.other = representative[v];
      finding.value = distance(mesh.points[v], mesh.points[representative[v]]);
      findings.push_back(finding);
    }
  }
  if (!mesh.tetrahedra.empty() || !mesh.triangles.empty()) {
    std::vector<bool> referenced(mesh.points.size(), false);
    const auto mark = [&](std::int32_t v) {
      if (v >= 0 && static_cast<std::size_t>(v) < referenced.size()) referenced[static_cast<std::size_t>(v)] = true;
    };
    for (const auto& t : mesh.tetrahedra) std::for_each(t.begin(), t.end(), mark);
    for (const auto& t : mesh.triangles) std::for_each(t.begin(), t.end(), mark);
    for (std::size_t v = 0; v < referenced.size(); ++v) {
      if (!referenced[v]) {
        MeshFinding finding;
        finding.kind = MeshFindingKind::UnreferencedVertex;
        finding.index = v;
        findings.push_back(finding);
      }
    }
  }
  return findings;
}

namespace {

template <std::size_t N>
void repair_elements(Mesh& mesh, std::vector<std::array<std::int32_t, N>>& elements, std::vector<int>& lines,
                     const std::vector<std::size_t>& representative, const MeshCheckOptions& options,
                     std::vector<MeshFinding>& findings) {
  constexpr bool tetrahedra = N == 4;
  // Check the elements as given (indices of the input mesh), then merge duplicate vertices and check again so that
  // elements made degenerate or duplicate by merging are caught too.
  std::vector<MeshFinding> original;
  check_elements(mesh, elements, lines, options, original);
  std::vector<bool> drop(elements.size(), false);
  for (MeshFinding& f : original) {
    switch (f.kind) {
      case MeshFindingKind::InvertedTetrahedron:
        std::swap(elements[f.index][1], elements[f.index][2]);
        break;
      default:
        drop[f.index] = true;
        break;
    }
    f.repaired = true;
    findings.push_back(f);
  }
  for (std::size_t e = 0; e < elements.size(); ++e) {
    if (drop[e]) continue;
    for (auto& v : elements[e]) v = static_cast<std::int32_t>(representative[static_cast<std::size_t>(v)]);
  }
  std::vector<MeshFinding> after_merge;
  check_elements(mesh, elements, lines, options, after_merge);
  for (MeshFinding& f : after_merge) {
    if (drop[f.index]) continue;
    if (f.kind == MeshFindingKind::InvertedTetrahedron) {
      std::swap(elements[f.index][1], elements[f.index][2]);  // merging moved no point, so this cannot happen
    } else {
      drop[f.index] = true;
    }
    f.repaired = true;
    findings.push_back(f);
  }
  std::size_t kept = 0;
  for (std::size_t e = 0; e < elements.size(); ++e) {
    if (drop[e]) continue;
    elements[kept] = elements[e];
    if (e < lines.size()) lines[kept] = lines[e];
    ++kept;
  }
  elements.resize(kept);
  if (lines.size() > kept) lines.resize(kept);
  (void)tetrahedra;
}

}  // namespace

MeshRepairResult repair_mesh(Mesh& mesh, const MeshCheckOptions& options) {
  MeshRepairResult result;
  const double tolerance = duplicate_tolerance(mesh, options);
  const std::vector<std::size_t> representative = duplicate_representatives(mesh, tolerance);
  repair_elements(mesh, mesh.tetrahedra, mesh.tetrahedron_lines, representative, options, result.findings);
  repair_elements(mesh, mesh.triangles, mesh.triangle_lines, representative, options, result.findings);
  const std::size_t n = mesh.points.size();
  std::vector<bool> keep(n, true);
  for (std::size_t v = 0; v < n; ++v) {
    if (representative[v] != v) {
      MeshFinding finding;
      finding.kind = MeshFindingKind::DuplicateVertex;
      finding.index = v;
      finding.other = representative[v];
      finding.value = distance(mesh.points[v], mesh.points[representative[v]]);
      finding.repaired = true;
      result.findings.push_back(finding);
      keep[v] = false;
    }
  }
  if (!mesh.tetrahedra.empty() || !mesh.triangles.empty()) {
    std::vector<bool> referenced(n, false);
    for (const auto& t : mesh.tetrahedra) {
      for (const auto v : t) referenced[static_cast<std::size_t>(v)] = true;
    }
    for (const auto& t : mesh.triangles) {
      for (const auto v : t) referenced[static_cast<std::size_t>(v)] = true;
    }
    for (std::size_t v = 0; v < n; ++v) {
      if (keep[v] && !referenced[v]) {
        MeshFinding finding;
        finding.kind = MeshFindingKind::UnreferencedVertex;
        finding.index = v;
        finding.repaired = true;
        result.findings.push_back(finding);
        keep[v] = false;
      }
    }
  }
  result.new_vertex_index.assign(n, -1);
  std::size_t next = 0;
  for (std::size_t v = 0; v < n; ++v) {
    if (keep[v]) {
      result.new_vertex_index[v] = static_cast<std::int32_t>(next);
      mesh.points[next] = mesh.points[v];
      ++next;
    }
  }
  for (std::size_t v = 0; v < n; ++v) {
    if (!keep[v] && representative[v] != v) result.new_vertex_index[v] = result.new_vertex_index[representative[v]];
  }
  mesh.points.resize(next);
  for (auto& t : mesh.tetrahedra) {
    for (auto& v : t) v = result.new_vertex_index[static_cast<std::size_t>(v)];
  }
  for (auto& t : mesh.triangles) {
    for (auto& v : t) v = result.new_vertex_index[static_cast<std::size_t>(v)];
  }
  return result;
}


namespace {

using Edge = std::pair<std::int32_t, std::int32_t>;

Edge make_edge(std::int32_t a, std::int32_t b) { return a < b ? Edge{a, b} : Edge{b, a}; }

SourceRange mesh_range(const Mesh& mesh, int line) {
  SourceRange range;
  range.file = mesh.source;
  range.line = line;
  range.column = line > 0 ? 1 : 0;
  return range;
}

template <std::size_t N>
bool check_indices(const Mesh& mesh, const std::vector<std::array<std::int32_t, N>>& elements,
                   const std::vector<int>& lines, const char* what, DiagnosticList& diagnostics) {
  for (std::size_t e = 0; e < elements.size(); ++e) {
    for (const std::int32_t v : elements[e]) {
      if (v < 0 || static_cast<std::size_t>(v) >= mesh.points.size()) {
        diagnostics.error(mesh_range(mesh, e < lines.size() ? lines[e] : 0),
                          std::string(what) + " " + std::to_string(e) + " refers to vertex " + std::to_string(v) +
                              " of " + std::to_string(mesh.points.size()) + "; repair the mesh first (repair_mesh)");
        return false;
      }
    }
  }
  return true;
}

void append_springs(SpringNetwork& network, const std::map<Edge, double>& edges, SpringKind kind) {
  for (const auto& [edge, measure] : edges) {
    network.first.push_back(edge.first);
    network.second.push_back(edge.second);
    network.kind.push_back(kind);
    network.element_measure.push_back(measure);
  }
}

// The bending links of springs_from_triangles: for every vertex j and structural neighbour i, the neighbour k of j
// with the most negative cos(i-j-k), kept when the angle reaches min_angle_degrees and no structural or flexion
// spring joins i and k. Ties go to the smaller k (neighbours are visited in increasing order), so the result does
// not depend on the order of the triangles.
std::map<Edge, double> bending_links(const Mesh& mesh, const std::map<Edge, double>& structural,
                                     const std::map<Edge, std::vector<std::int32_t>>& opposite,
                                     double min_angle_degrees) {
  std::vector<std::vector<std::int32_t>> neighbours(mesh.points.size());
  for (const auto& [edge, measure] : structural) {
    neighbours[static_cast<std::size_t>(edge.first)].push_back(edge.second);
    neighbours[static_cast<std::size_t>(edge.second)].push_back(edge.first);
  }
  std::map<Edge, bool> flexion;
  for (const auto& [edge, across] : opposite) {
    for (std::size_t i = 0; i < across.size(); ++i)
      for (std::size_t j = i + 1; j < across.size(); ++j) flexion[make_edge(across[i], across[j])] = true;
  }
  const double pi = std::acos(-1.0);
  const double max_cosine = std::cos(min_angle_degrees * pi / 180.0);
  std::map<Edge, double> links;
  for (std::size_t j = 0; j < neighbours.size(); ++j) {
    std::vector<std::int32_t>& around = neighbours[j];
    std::sort(around.begin(), around.end());
    const Point3& centre = mesh.points[j];
    for (const std::int32_t i : around) {
      const Point3& a = mesh.points[static_cast<std::size_t>(i)];
      std::int32_t best = -1;
      double best_cosine = 2.0;
      for (const std::int32_t k : around) {
        if (k == i) continue;
        const Point3& b = mesh.points[static_cast<std::size_t>(k)];
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
      if (structural.count(link) == 0 && flexion.count(link) == 0) links.emplace(link, 0.0);
    }
  }
  return links;
}

}  // namespace


SpringNetwork springs_from_tetrahedra(const Mesh& mesh, DiagnosticList& diagnostics) {
  SpringNetwork network;
  network.vertex_count = mesh.points.size();
  if (!check_indices(mesh, mesh.tetrahedra, mesh.tetrahedron_lines, "tetrahedron", diagnostics)) return network;
  std::map<Edge, double> edges;
  for (const Tetrahedron& t : mesh.tetrahedra) {
    const double volume = std::abs(signed_volume(mesh, t));
    for (std::size_t i = 0; i < 4; ++i) {
      for (std::size_t j = i + 1; j < 4; ++j) {
        if (t[i] != t[j]) edges[make_edge(t[i], t[j])] += volume;
      }
    }
  }
  append_springs(network, edges, SpringKind::TetrahedronEdge);
  reference::build_adjacency(network);
  return network;
}

SpringNetwork springs_from_triangles(const Mesh& mesh, const TriangleSpringOptions& options,
                                     DiagnosticList& diagnostics) {
  SpringNetwork network;
  network.vertex_count = mesh.points.size();
  if (!check_indices(mesh, mesh.triangles, mesh.triangle_lines, "triangle", diagnostics)) return network;
  std::map<Edge, double> structural;
  // For each edge, the vertices opposite it in the triangles that contain it.
  std::map<Edge, std::vector<std::int32_t>> opposite;
  for (const Triangle& t : mesh.triangles) {
    const double area = triangle_area(mesh, t);
    for (std::size_t i = 0; i < 3; ++i) {
      const std::int32_t a = t[i], b = t[(i + 1) % 3], c = t[(i + 2) % 3];
      if (a == b) continue;
      structural[make_edge(a, b)] += area;
      opposite[make_edge(a, b)].push_back(c);
    }
  }
  if (options.structural) append_springs(network, structural, SpringKind::Structural);
  if (options.flexion) {
    std::map<Edge, double> flexion;
    for (const auto& [edge, across] : opposite) {
      for (std::size_t i = 0; i < across.size(); ++i) {
        for (std::size_t j = i + 1; j < across.size(); ++j) {
          if (across[i] == across[j]) continue;
          const Edge link = make_edge(across[i], across[j]);
          if (structural.count(link) == 0) flexion.emplace(link, 0.0);
        }
      }
    }
    append_springs(network, flexion, SpringKind::Flexion);
  }
  if (options.bending) {
    append_springs(network, bending_links(mesh, structural, opposite, options.bending_min_angle_degrees),
                   SpringKind::Bending);
  }
  reference::build_adjacency(network);
  return network;
}

bool compute_rest_lengths(SpringNetwork& network, const std::vector<Point3>& points, DiagnosticList& diagnostics,
                          double min_relative_length) {
  network.rest_length.resize(network.size());
  double total = 0.0;
  for (std::size_t s = 0; s < network.size(); ++s) {
    network.rest_length[s] = distance(points[static_cast<std::size_t>(network.first[s])],
                                      points[static_cast<std::size_t>(network.second[s])]);
    total += network.rest_length[s];
  }
  if (network.size() == 0) return true;
  const double mean = total / static_cast<double>(network.size());
  for (std::size_t s = 0; s < network.size(); ++s) {
    const double length = network.rest_length[s];
    if (!(length > min_relative_length * mean) || !std::isfinite(length)) {
      SourceRange range;
      diagnostics.error(range, "spring " + std::to_string(s) + " between vertices " + std::to_string(network.first[s]) +
                                   " and " + std::to_string(network.second[s]) + " has rest length " +
                                   std::to_string(length) + " (mean " + std::to_string(mean) +
                                   "); its direction is undefined: merge the duplicate vertices (repair_mesh)");
      return false;
    }
  }
  return true;
}

void build_adjacency(SpringNetwork& network) {
  const std::size_t n = network.vertex_count;
  std::vector<std::int32_t> count(n + 1, 0);
  for (std::size_t s = 0; s < network.size(); ++s) {
    ++count[static_cast<std::size_t>(network.first[s]) + 1];
    ++count[static_cast<std::size_t>(network.second[s]) + 1];
  }
  for (std::size_t v = 0; v < n; ++v) count[v + 1] += count[v];
  network.adjacency_offset = count;
  network.adjacency_spring.assign(2 * network.size(), 0);
  std::vector<std::int32_t> next(count.begin(), count.end() - 1);
  for (std::size_t s = 0; s < network.size(); ++s) {
    const auto a = static_cast<std::size_t>(network.first[s]);
    const auto b = static_cast<std::size_t>(network.second[s]);
    network.adjacency_spring[static_cast<std::size_t>(next[a])] = static_cast<std::int32_t>(s);
    ++next[a];
    network.adjacency_spring[static_cast<std::size_t>(next[b])] = static_cast<std::int32_t>(s);
    ++next[b];
  }
}

bool assign_stiffness(SpringNetwork& network, const StiffnessSpec& spec, DiagnosticList& diagnostics) {
  SourceRange range;
  if (!spec.per_spring.empty() && spec.per_spring.size() != network.size()) {
    diagnostics.error(range, "per-spring stiffness values: " + std::to_string(spec.per_spring.size()) + " given for " +
                                 std::to_string(network.size()) + " springs; give one per spring");
    return false;
  }
  if (network.rest_length.size() != network.size()) {
    diagnostics.error(range, "rest lengths are missing; call compute_rest_lengths first");
    return false;
  }
  const bool modulus = is_modulus_mapping(spec.mapping);
  if (modulus && !(spec.thickness > 0.0 && std::isfinite(spec.thickness))) {
    diagnostics.error(range, std::string("the membrane thickness must be a positive number for the ") +
                                 mapping_citation(spec.mapping) + " mapping");
    return false;
  }
  const auto spring_name = [&](std::size_t s) {
    return "spring " + std::to_string(s) + " (vertices " + std::to_string(network.first[s]) + " and " +
           std::to_string(network.second[s]) + ")";
  };
  network.stiffness.assign(network.size(), 0.0);
  for (std::size_t s = 0; s < network.size(); ++s) {
    const double value = spec.per_spring.empty() ? spec.value : spec.per_spring[s];
    if (modulus && !(value > 0.0 && std::isfinite(value))) {
      // A zero modulus leaves the network without stiffness (every vertex free), NaN would reach the integrator.
      diagnostics.error(range, spring_name(s) + ": Young's modulus " + format_number(value) + " Pa (" +
                                   mapping_citation(spec.mapping) +
                                   " mapping) is not a positive, finite number; fix the material value");
      return false;
    }
    if (!(value >= 0.0) || !std::isfinite(value)) {
      diagnostics.error(range, spring_name(s) + ": stiffness parameter " + std::to_string(value) +
                                   " is not a finite, non-negative number; fix the material value");
      return false;
    }
    const double length = network.rest_length[s];
    const SpringKind kind = network.kind[s];
    const bool element_spring = kind == SpringKind::TetrahedronEdge || kind == SpringKind::Structural;
    if (modulus && element_spring && !(network.element_measure[s] > 0.0)) {
      diagnostics.error(range, spring_name(s) + " belongs only to elements of zero " +
                                   (kind == SpringKind::Structural ? "area" : "volume") +
                                   ", so the mapping gives it no stiffness; repair the mesh (repair_mesh drops "
                                   "degenerate elements)");
      return false;
    }
    const double measure =
        kind == SpringKind::Structural ? spec.thickness * network.element_measure[s] : network.element_measure[s];
    switch (spec.mapping) {
      case StiffnessMapping::Uniform:
        network.stiffness[s] = value;
        break;
      case StiffnessMapping::StiffnessOverLength:
        network.stiffness[s] = value / length;
        break;
      case StiffnessMapping::VanGelder1998:
        network.stiffness[s] = value * measure / (length * length);
        break;
      case StiffnessMapping::LloydSzekelyHarders2007: {
        // Lloyd et al. 2007: k = (2 sqrt 2 / 25) E l on a regular tetrahedron = (24/25) E V / l^2; the equilateral
        // triangle's k = (sqrt 3 / 4) E h = E h A / l^2 (see StiffnessMapping).
        const double factor = kind == SpringKind::TetrahedronEdge ? 24.0 / 25.0 : 1.0;
        network.stiffness[s] = factor * value * measure / (length * length);
        break;
      }
    }
  }
  if (modulus) {
    // Flexion and bending springs: a fraction of the mean structural stiffness at their two endpoints.
    for (std::size_t s = 0; s < network.size(); ++s) {
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
  }
  return true;
}

std::vector<double> lumped_masses(const Mesh& mesh, const MassSpec& spec, DiagnosticList& diagnostics) {
  SourceRange range;
  range.file = mesh.source;
  std::vector<double> mass(mesh.points.size(), 0.0);
  if (!(spec.value > 0.0) || !std::isfinite(spec.value)) {
    diagnostics.error(range, "the density or total mass must be a positive, finite number");
    return {};
  }
  const double density = spec.source == MassSpec::Source::Density ? spec.value : 1.0;
  if (!mesh.tetrahedra.empty()) {
    for (const Tetrahedron& t : mesh.tetrahedra) {
      const double share = density * std::abs(signed_volume(mesh, t)) / 4.0;
      for (const std::int32_t v : t) mass[static_cast<std::size_t>(v)] += share;
    }
  } else if (!mesh.triangles.empty()) {
    for (const Triangle& t : mesh.triangles) {
      const double share = density * spec.thickness * triangle_area(mesh, t) / 3.0;
      for (const std::int32_t v : t) mass[static_cast<std::size_t>(v)] += share;
    }
  } else if (spec.source == MassSpec::Source::TotalMass) {
    std::fill(mass.begin(), mass.end(), 1.0);
  }
  if (spec.source == MassSpec::Source::TotalMass) {
    double total = 0.0;
    for (const double m : mass) total += m;
    if (total > 0.0) {
      for (double& m : mass) m *= spec.value / total;
    }
  }
  for (std::size_t v = 0; v < mass.size(); ++v) {
    if (!(mass[v] > 0.0)) {
      diagnostics.error(range, "vertex " + std::to_string(v) +
                                   " gets no mass (no element uses it or its elements are flat); repair the mesh "
                                   "(repair_mesh removes unreferenced vertices)");
      return {};
    }
  }
  return mass;
}

bool assign_damping(SpringNetwork& network, const std::vector<double>& mass, const DampingSpec& spec,
                    DiagnosticList& diagnostics) {
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
    return true;
  }
  network.damping.assign(network.size(), 0.0);
  for (std::size_t s = 0; s < network.size(); ++s) {
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
  return true;
}


std::vector<Triangle> boundary_triangles(const Mesh& mesh) {
  // Faces of a positively oriented tetrahedron (a,b,c,d) with outward normals.
  std::map<std::array<std::int32_t, 3>, std::pair<Triangle, int>> faces;
  for (const Tetrahedron& t : mesh.tetrahedra) {
    const Triangle oriented[4] = {{t[0], t[2], t[1]}, {t[0], t[1], t[3]}, {t[1], t[2], t[3]}, {t[0], t[3], t[2]}};
    for (const Triangle& face : oriented) {
      std::array<std::int32_t, 3> key = face;
      std::sort(key.begin(), key.end());
      auto [it, inserted] = faces.try_emplace(key, face, 0);
      ++it->second.second;
      (void)inserted;
    }
  }
  std::vector<Triangle> boundary;
  for (const auto& entry : faces) {
    if (entry.second.second == 1) boundary.push_back(entry.second.first);
  }
  return boundary;
}


std::optional<SimulationSetup> build_spring_model(const Mesh& mesh, const SpringModelSpec& spec,
                                                  DiagnosticList& diagnostics) {
  SourceRange range;
  range.file = mesh.source;
  if (!(spec.length_unit > 0.0) || !std::isfinite(spec.length_unit)) {
    diagnostics.error(range, "the length unit must be a positive number of metres per mesh unit");
    return std::nullopt;
  }
  if (mesh.tetrahedra.empty() && mesh.triangles.empty()) {
    diagnostics.error(range, "the mesh has no tetrahedra or triangles to build springs from");
    return std::nullopt;
  }
  if (is_modulus_mapping(spec.stiffness.mapping)) {
    // Young's modulus mappings weigh every spring by the volumes (areas) of its elements: a degenerate element has
    // none to give, and a network built over it would be silently soft there.
    const bool volume = !mesh.tetrahedra.empty();
    const std::size_t errors = diagnostics.error_count();
    for (const MeshFinding& finding : reference::check_mesh(mesh)) {
      const bool degenerate = volume ? finding.kind == MeshFindingKind::DegenerateTetrahedron
                                     : finding.kind == MeshFindingKind::DegenerateTriangle;
      if (!degenerate) continue;
      SourceRange at = range;
      at.line = finding.line;
      at.column = finding.line > 0 ? 1 : 0;
      diagnostics.error(at, finding_message(finding) + ": the " + mapping_citation(spec.stiffness.mapping) +
                                " mapping needs every element's " + (volume ? "volume" : "area") +
                                "; repair the mesh first (repair_mesh drops degenerate elements)");
    }
    if (diagnostics.error_count() > errors) return std::nullopt;
  }
  Mesh scaled = mesh;
  for (Point3& p : scaled.points) {
    for (double& coordinate : p) coordinate *= spec.length_unit;
  }
  SimulationSetup setup;
  setup.rest_positions = scaled.points;
  setup.springs = scaled.tetrahedra.empty() ? reference::springs_from_triangles(scaled, spec.triangle_springs, diagnostics)
                                            : reference::springs_from_tetrahedra(scaled, diagnostics);
  if (diagnostics.has_errors()) return std::nullopt;
  if (!reference::compute_rest_lengths(setup.springs, scaled.points, diagnostics)) return std::nullopt;
  if (!reference::assign_stiffness(setup.springs, spec.stiffness, diagnostics)) return std::nullopt;
  setup.mass = reference::lumped_masses(scaled, spec.mass, diagnostics);
  if (setup.mass.empty() && !scaled.points.empty()) return std::nullopt;
  if (!reference::assign_damping(setup.springs, setup.mass, spec.damping, diagnostics)) return std::nullopt;
  return setup;
}


}  // namespace fmpc::sim::reference
