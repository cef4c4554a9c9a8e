#include "runtime/springs/spring_network.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>

#include "diagnostics/number_format.h"

namespace fmpc::sim {

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
  build_adjacency(network);
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
  build_adjacency(network);
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
  network.adjacency_neighbour.assign(2 * network.size(), 0);
  std::vector<std::int32_t> next(count.begin(), count.end() - 1);
  for (std::size_t s = 0; s < network.size(); ++s) {
    const auto a = static_cast<std::size_t>(network.first[s]);
    const auto b = static_cast<std::size_t>(network.second[s]);
    network.adjacency_spring[static_cast<std::size_t>(next[a])] = static_cast<std::int32_t>(s);
    network.adjacency_neighbour[static_cast<std::size_t>(next[a]++)] = network.second[s];
    network.adjacency_spring[static_cast<std::size_t>(next[b])] = static_cast<std::int32_t>(s);
    network.adjacency_neighbour[static_cast<std::size_t>(next[b]++)] = network.first[s];
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

}  // namespace fmpc::sim
