#include "runtime/gpu/batch_concatenation.h"

#include <string>

#include "kernels/integrator_math.h"
#include "runtime/gpu/gpu_simulation.h"

namespace fmpc::gpu {

bool force_probe(const sim::SimulationSetup& setup) {
  return setup.probe && setup.probe->mode == sim::ProbeLoad::Mode::Force;
}

ConcatenatedScenes concatenate(const std::vector<sim::SimulationSetup>& scenes) {
  ConcatenatedScenes c;
  std::size_t vertices = 0, entries = 0, springs = 0, elements = 0, corners = 0;
  for (const auto& setup : scenes) {
    c.has_forces = c.has_forces || !setup.external_forces.empty() || force_probe(setup);
    c.has_damping = c.has_damping || !setup.springs.damping.empty();
    c.has_elements = c.has_elements || !setup.elements.empty();
    vertices += setup.rest_positions.size();
    entries += setup.springs.adjacency_spring.size();
    springs += setup.springs.size();
    elements += setup.tetrahedra.size();
    if (!setup.elements.empty()) corners += setup.elements.geometry.corner_index.size();
  }
  c.offset.reserve(vertices + 1);  // and the end offset, pushed last
  for (auto* array : {&c.offset, &c.vertex_scene}) array->resize(vertices);
  for (auto* array : {&c.spring, &c.neighbour}) array->resize(entries);
  for (auto* array : {&c.first, &c.second}) array->resize(springs);
  for (auto* array : {&c.rest_length, &c.stiffness}) array->resize(springs);
  if (c.has_damping) c.damping.resize(springs);
  c.mass.resize(vertices);
  c.fixed.resize(vertices);
  for (std::size_t axis = 0; axis < 3; ++axis) {
    for (auto* array : {&c.rest[axis], &c.position[axis], &c.velocity[axis]}) array->resize(vertices);
    if (c.has_forces) c.force[axis].resize(vertices);
  }
  c.corners.resize(4 * elements);
  c.element_scene.resize(elements);
  if (c.has_elements) {
    c.element_kind = scenes.front().elements.geometry.kind;
    c.nodes_per_element = scenes.front().elements.geometry.nodes_per_element;
    c.nodes.resize(static_cast<std::size_t>(c.nodes_per_element) * elements);
    c.corner_offset.reserve(vertices + 1);
    c.corner_offset.resize(vertices);
    c.corner_index.resize(corners);
    c.corner_slot.resize(corners);
    c.rest_inverse.resize(9 * elements);
    c.rest_volume.resize(elements);
    const std::vector<sim::ElementTerm>& first = scenes.front().elements.terms;
    c.terms.resize(first.size());
    for (std::size_t t = 0; t < first.size(); ++t) {
      ConcatenatedScenes::Term& term = c.terms[t];
      term.law = first[t].law;
      term.prony = first[t].prony;
      for (int p = 0; p < kernels::kMostLawParameters; ++p)
        if (!first[t].parameter[p].empty()) term.parameter[p].resize(elements);
      bool damped = false;
      for (const auto& setup : scenes) damped = damped || !setup.elements.terms[t].stiffness_damping.empty();
      if (damped) term.stiffness_damping.resize(elements);
    }
  }
  c.pool = std::make_unique<sim::WorkerPool>(sim::resolve_thread_count(0, entries + 4 * elements + vertices));
  sim::WorkerPool& pool = *c.pool;
  int entry_base = 0, corner_base = 0;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    const sim::SimulationSetup& setup = scenes[s];
    const sim::SpringNetwork& net = setup.springs;
    const int vertex_base = c.vertex_begin.back(), spring_base = c.spring_begin.back();
    const int element_base = c.element_begin.back();
    const auto scene = static_cast<int>(s);
    const auto vb = static_cast<std::size_t>(vertex_base), sb = static_cast<std::size_t>(spring_base);
    const auto eb = static_cast<std::size_t>(element_base);
    const std::size_t n = setup.rest_positions.size(), m = setup.tetrahedra.size();
    fill_on_pool(pool, c.corners, 4 * eb, 4 * m,
                 [&](std::size_t i) { return vertex_base + setup.tetrahedra[i / 4][i % 4]; });
    fill_on_pool(pool, c.element_scene, eb, m, [&](std::size_t) { return scene; });
    if (!setup.elements.empty()) {
      const sim::ElementGeometry& field = setup.elements.geometry;
      const int corners_before = corner_base;
      const auto cbase = static_cast<std::size_t>(corner_base);
      fill_on_pool(pool, c.corner_offset, vb, n,
                   [&](std::size_t v) { return corners_before + field.corner_offset[v]; });
      const int N = c.nodes_per_element;
      fill_on_pool(pool, c.nodes, static_cast<std::size_t>(N) * eb, field.nodes.size(),
                   [&](std::size_t k) { return vertex_base + field.nodes[k]; });
      fill_on_pool(pool, c.corner_index, cbase, field.corner_index.size(),
                   [&](std::size_t k) { return N * element_base + field.corner_index[k]; });
      fill_on_pool(pool, c.corner_slot, cbase, field.corner_slot.size(),
                   [&](std::size_t k) { return corners_before + field.corner_slot[k]; });
      corner_base += static_cast<int>(field.corner_index.size());
      fill_on_pool(pool, c.rest_inverse, 9 * eb, 9 * m, [&](std::size_t i) { return field.rest_inverse[i]; });
      fill_on_pool(pool, c.rest_volume, eb, m, [&](std::size_t e) { return field.rest_volume[e]; });
      const auto copy_or_zero = [&](HostArray<double>& to, const std::vector<double>& from) {
        fill_on_pool(pool, to, eb, m, [&](std::size_t e) { return from.empty() ? 0.0 : from[e]; });
      };
      for (std::size_t term = 0; term < c.terms.size(); ++term) {
        const sim::ElementTerm& own = setup.elements.terms[term];
        for (int p = 0; p < kernels::kMostLawParameters; ++p)
          if (!c.terms[term].parameter[p].empty()) copy_or_zero(c.terms[term].parameter[p], own.parameter[p]);
        if (!c.terms[term].stiffness_damping.empty())
          copy_or_zero(c.terms[term].stiffness_damping, own.stiffness_damping);
      }
    }
    const int entries_before = entry_base;
    const auto entry_at = static_cast<std::size_t>(entry_base);
    fill_on_pool(pool, c.offset, vb, n, [&](std::size_t v) { return entries_before + net.adjacency_offset[v]; });
    fill_on_pool(pool, c.spring, entry_at, net.adjacency_spring.size(),
                 [&](std::size_t e) { return spring_base + net.adjacency_spring[e]; });
    sim::write_adjacency_neighbours(net, vertex_base, c.neighbour.data() + entry_at, pool);
    entry_base += static_cast<int>(net.adjacency_spring.size());
    fill_on_pool(pool, c.first, sb, net.size(), [&](std::size_t k) { return vertex_base + net.first[k]; });
    fill_on_pool(pool, c.second, sb, net.size(), [&](std::size_t k) { return vertex_base + net.second[k]; });
    fill_on_pool(pool, c.rest_length, sb, net.size(), [&](std::size_t k) { return net.rest_length[k]; });
    fill_on_pool(pool, c.stiffness, sb, net.size(), [&](std::size_t k) { return net.stiffness[k]; });
    if (c.has_damping)
      fill_on_pool(pool, c.damping, sb, net.size(),
                   [&](std::size_t k) { return net.damping.empty() ? 0.0 : net.damping[k]; });
    fill_on_pool(pool, c.mass, vb, n, [&](std::size_t v) { return setup.mass[v]; });
    // Held axes at the start (a displacement probe's vertices are held only after the initial velocities are taken,
    // as in the CPU backend), then the full mask.
    std::vector<unsigned char> fixed(n, 0);
    for (std::size_t v = 0; v < n && setup.fixed_axes.size() == n; ++v) fixed[v] = setup.fixed_axes[v];
    for (const auto v : setup.fixed_vertices) fixed[static_cast<std::size_t>(v)] = kernels::kAllAxesFixed;
    const std::vector<unsigned char> held = sim::held_axes(setup);
    fill_on_pool(pool, c.fixed, vb, n, [&](std::size_t v) { return held[v]; });
    const std::vector<sim::Point3>& start =
        setup.initial_positions.empty() ? setup.rest_positions : setup.initial_positions;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      fill_on_pool(pool, c.rest[axis], vb, n, [&](std::size_t v) { return setup.rest_positions[v][axis]; });
      fill_on_pool(pool, c.position[axis], vb, n, [&](std::size_t v) { return start[v][axis]; });
      // As the CPU backend: held axes start at rest.
      fill_on_pool(pool, c.velocity[axis], vb, n, [&](std::size_t v) {
        return setup.initial_velocities.empty() || kernels::axis_fixed(fixed[v], static_cast<int>(axis))
                   ? 0.0
                   : setup.initial_velocities[v][axis];
      });
      if (c.has_forces)
        fill_on_pool(pool, c.force[axis], vb, n, [&](std::size_t v) {
          return setup.external_forces.empty() ? 0.0 : setup.external_forces[v][axis];
        });
    }
    fill_on_pool(pool, c.vertex_scene, vb, n, [&](std::size_t) { return scene; });

    c.vertex_begin.push_back(vertex_base + static_cast<int>(n));
    c.spring_begin.push_back(spring_base + static_cast<int>(net.size()));
    c.element_begin.push_back(element_base + static_cast<int>(m));
  }
  c.offset.push_back(entry_base);
  if (c.has_elements) c.corner_offset.push_back(corner_base);
  return c;
}

HostArray<unsigned char> corner_ranks(const ConcatenatedScenes& c) {
  HostArray<unsigned char> ranks(c.nodes.size());
  for (std::size_t k = 0; k < c.nodes.size(); ++k) {
    const int rank = c.corner_slot[k] - c.corner_offset[static_cast<std::size_t>(c.nodes[k])];
    if (rank < 0 || rank > 255) return {};
    ranks[k] = static_cast<unsigned char>(rank);
  }
  return ranks;
}

GatherKind gather_kind(const sim::SimulationSetup& setup) {
  if (setup.elements.empty()) return GatherKind::Springs;
  return setup.springs.size() > 0 ? GatherKind::SpringsAndElements : GatherKind::Elements;
}

bool same_element_laws(const sim::SimulationSetup& a, const sim::SimulationSetup& b) {
  if (a.elements.terms.size() != b.elements.terms.size()) return false;
  if (!a.elements.empty() && a.elements.geometry.kind != b.elements.geometry.kind) return false;
  for (std::size_t t = 0; t < a.elements.terms.size(); ++t)
    if (a.elements.terms[t].law != b.elements.terms[t].law) return false;
  return true;
}

const char* shared_field_mismatch(const sim::SimulationSetup& scene, const sim::SimulationSetup& reference) {
  const bool springs = scene.springs.size() > 0, reference_springs = reference.springs.size() > 0;
  if (springs != reference_springs || (!springs && !same_element_laws(scene, reference))) return "force model";
  if (gather_kind(scene) != gather_kind(reference)) return "volume term (on in one scene, off in the other)";
  if (!same_element_laws(scene, reference)) return "element terms";
  if (scene.integrator != reference.integrator) return "integrator";
  if (scene.precision != reference.precision) return "precision";
  if (scene.law != reference.law) return "spring law";
  if (scene.law == kernels::SpringLaw::BasafaFarahmand &&
      (scene.basafa_k2_over_k1 != reference.basafa_k2_over_k1 || scene.basafa_xc != reference.basafa_xc)) {
    return "Basafa-Farahmand parameters";
  }
  if (scene.gravity != reference.gravity) return "gravity";
  if (scene.nodal_damping_gamma0 != reference.nodal_damping_gamma0 ||
      scene.nodal_damping_gamma1 != reference.nodal_damping_gamma1) {
    return "nodal damping";
  }
  if (scene.mass_damping != reference.mass_damping) return "mass damping (Rayleigh alpha)";
  if (scene.on_inversion != reference.on_inversion) return "on_inversion policy";
  return nullptr;
}

const char* single_scene_feature(const sim::SimulationSetup& setup) {
  if (setup.integrator == sim::Integrator::ImplicitEuler) {
    return "implicit Euler runs one scene at a time on the GPU (its conjugate gradient solves one system); run the "
           "scene as a simulation of its own";
  }
  if (setup.strain_stiffness) {
    return "a scene with table-driven stiffness k(strain) runs on its own on the GPU; run it as a simulation of its "
           "own";
  }
  if (!setup.tools.empty()) {
    return "a scene with rigid tools runs on its own on the GPU (its tools' poses are the launch's); run it as a "
           "simulation of its own";
  }
  if (sim::has_point_state(setup.elements)) {
    return "a viscoelastic scene runs on its own on the GPU (its Prony constants depend on the scene's time step); "
           "run it as a simulation of its own";
  }
  return nullptr;
}

bool batch_accepts(const std::vector<sim::SimulationSetup>& scenes, std::size_t s, DiagnosticList& diagnostics) {
  const char* feature = scenes.size() > 1 ? single_scene_feature(scenes[s]) : nullptr;
  if (feature != nullptr) {
    diagnostics.error(SourceRange{}, "scene " + std::to_string(s) + ": " + feature);
    return false;
  }
  if (const char* field = shared_field_mismatch(scenes[s], scenes.front())) {
    diagnostics.error(SourceRange{}, "scene " + std::to_string(s) + " differs from scene 0 in its " + field +
                                         "; the scenes of one GPU batch share it: run it in another batch");
    return false;
  }
  return true;
}

}  // namespace fmpc::gpu
