#include "runtime/mesh/mesh_check.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <sstream>

namespace fmpc::sim {

const char* to_string(MeshFindingKind kind) {
  switch (kind) {
    case MeshFindingKind::IndexOutOfRange:
      return "index-out-of-range";
    case MeshFindingKind::DegenerateTetrahedron:
      return "degenerate-tetrahedron";
    case MeshFindingKind::InvertedTetrahedron:
      return "inverted-tetrahedron";
    case MeshFindingKind::DuplicateTetrahedron:
      return "duplicate-tetrahedron";
    case MeshFindingKind::DegenerateTriangle:
      return "degenerate-triangle";
    case MeshFindingKind::DuplicateTriangle:
      return "duplicate-triangle";
    case MeshFindingKind::DuplicateVertex:
      return "duplicate-vertex";
    case MeshFindingKind::UnreferencedVertex:
      return "unreferenced-vertex";
  }
  return "unknown";
}

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

std::string finding_message(const MeshFinding& f) {
  std::ostringstream out;
  const bool is_vertex = f.kind == MeshFindingKind::DuplicateVertex || f.kind == MeshFindingKind::UnreferencedVertex;
  const bool is_triangle =
      f.kind == MeshFindingKind::DegenerateTriangle || f.kind == MeshFindingKind::DuplicateTriangle;
  out << (is_vertex ? "vertex " : is_triangle ? "triangle " : "element ") << f.index;
  if (f.line > 0) out << " (line " << f.line << ")";
  switch (f.kind) {
    case MeshFindingKind::IndexOutOfRange:
      out << " refers to a vertex that does not exist";
      break;
    case MeshFindingKind::DegenerateTetrahedron:
      out << " is degenerate (volume " << f.value << ")";
      break;
    case MeshFindingKind::InvertedTetrahedron:
      out << " is inverted (volume " << f.value << ")";
      break;
    case MeshFindingKind::DuplicateTetrahedron:
    case MeshFindingKind::DuplicateTriangle:
      out << " repeats element " << f.other;
      break;
    case MeshFindingKind::DegenerateTriangle:
      out << " is degenerate (area " << f.value << ")";
      break;
    case MeshFindingKind::DuplicateVertex:
      out << " duplicates vertex " << f.other << " (distance " << f.value << ")";
      break;
    case MeshFindingKind::UnreferencedVertex:
      out << " is used by no element";
      break;
  }
  if (f.repaired) {
    switch (f.kind) {
      case MeshFindingKind::InvertedTetrahedron:
        out << "; repaired: two vertices swapped";
        break;
      case MeshFindingKind::DuplicateVertex:
        out << "; repaired: merged";
        break;
      default:
        out << "; repaired: removed";
        break;
    }
  }
  return out.str();
}

}  // namespace fmpc::sim
