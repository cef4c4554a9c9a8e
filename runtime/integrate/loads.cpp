// The probe and the strain stiffness table: their checks, the probe's reading and the table's view, shared by the
// CPU backend (cpu_engine.cpp) and the CUDA backend (runtime/gpu).
#include <cmath>

#include "kernels/integrator_math.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

const Point3& start_position(const SimulationSetup& setup, std::size_t v) {
  return setup.initial_positions.empty() ? setup.rest_positions[v] : setup.initial_positions[v];
}

std::vector<unsigned char> held_axes(const SimulationSetup& setup) {
  const std::size_t n = setup.rest_positions.size();
  std::vector<unsigned char> held(n, 0);
  if (setup.fixed_axes.size() == n)
    for (std::size_t v = 0; v < n; ++v) held[v] = static_cast<unsigned char>(setup.fixed_axes[v] & kernels::kAllAxesFixed);
  for (const auto v : setup.fixed_vertices)
    if (v >= 0 && static_cast<std::size_t>(v) < n) held[static_cast<std::size_t>(v)] = kernels::kAllAxesFixed;
  if (setup.probe && setup.probe->mode == ProbeLoad::Mode::Displacement)
    for (const auto v : setup.probe->vertices)
      if (v >= 0 && static_cast<std::size_t>(v) < n) held[static_cast<std::size_t>(v)] = kernels::kAllAxesFixed;
  return held;
}

int implicit_iteration_limit(const SimulationSetup& setup) {
  return setup.implicit.max_iterations > 0 ? setup.implicit.max_iterations
                                           : static_cast<int>(6 * setup.rest_positions.size());
}

kernels::StrainTableView strain_table_view(const StrainStiffnessTable& table) {
  return {table.strain.data(), table.modulus.data(), static_cast<int>(table.strain.size())};
}

ProbeReading read_probe(const SimulationSetup& setup, double time, const std::vector<Point3>& positions,
                        const std::vector<Point3>& velocities, const std::vector<double>& stiffness,
                        const ElementTermStates* states) {
  ProbeReading reading;
  if (!setup.probe || setup.probe->vertices.empty()) return reading;
  const std::size_t n = setup.rest_positions.size();
  if (positions.size() != n || velocities.size() != n || stiffness.size() != setup.springs.size()) return reading;
  const ProbeLoad& probe = *setup.probe;
  const double count = static_cast<double>(probe.vertices.size());
  for (const auto vertex : probe.vertices) {
    const auto v = static_cast<std::size_t>(vertex);
    const Point3& start = start_position(setup, v);
    for (std::size_t axis = 0; axis < 3; ++axis) reading.displacement[axis] += (positions[v][axis] - start[axis]) / count;
  }
  if (probe.mode == ProbeLoad::Mode::Force) {
    const double share = kernels::probe_ramp_share(time, probe.ramp_time, probe.cycles);
    for (std::size_t axis = 0; axis < 3; ++axis) reading.force[axis] = share * probe.target[axis];
    return reading;
  }
  const std::vector<Point3> forces = internal_forces(setup, positions, velocities, stiffness, probe.vertices, states);
  for (const Point3& f : forces)
    for (std::size_t axis = 0; axis < 3; ++axis) reading.force[axis] -= f[axis];
  return reading;
}

bool validate_loads(const SimulationSetup& setup, DiagnosticList& diagnostics) {
  const std::size_t errors = diagnostics.error_count();
  const std::size_t n = setup.rest_positions.size();
  if (setup.probe) {
    const ProbeLoad& probe = *setup.probe;
    std::vector<unsigned char> fixed(n, 0), seen(n, 0);
    for (const auto v : setup.fixed_vertices)
      if (v >= 0 && static_cast<std::size_t>(v) < n) fixed[static_cast<std::size_t>(v)] = 1;
    if (probe.vertices.empty()) diagnostics.error(SourceRange{}, "the probe has no vertices");
    for (const auto v : probe.vertices) {
      if (v < 0 || static_cast<std::size_t>(v) >= n) {
        diagnostics.error(SourceRange{}, "probe vertex " + std::to_string(v) + " is out of range (the mesh has " +
                                             std::to_string(n) + " vertices)");
        continue;
      }
      if (fixed[static_cast<std::size_t>(v)])
        diagnostics.error(SourceRange{}, "probe vertex " + std::to_string(v) + " is also fixed; unfix it or pick another");
      if (seen[static_cast<std::size_t>(v)])
        diagnostics.error(SourceRange{}, "probe vertex " + std::to_string(v) + " is given twice");
      seen[static_cast<std::size_t>(v)] = 1;
    }
    bool finite = std::isfinite(probe.ramp_time) && probe.ramp_time >= 0.0;
    for (const double value : probe.target) finite = finite && std::isfinite(value);
    if (!finite) diagnostics.error(SourceRange{}, "the probe's target and ramp time must be finite (ramp time >= 0)");
    if (probe.cycles < 0 || (probe.cycles > 0 && !(probe.ramp_time > 0.0)))
      diagnostics.error(SourceRange{}, "a cyclic probe needs a positive ramp time and a non-negative cycle count");
  }
  if (setup.strain_stiffness) {
    const StrainStiffnessTable& table = *setup.strain_stiffness;
    bool valid = table.strain.size() >= 2 && table.modulus.size() == table.strain.size() &&
                 table.stiffness_per_modulus.size() == setup.springs.size();
    for (std::size_t i = 0; valid && i < table.strain.size(); ++i) {
      valid = std::isfinite(table.strain[i]) && std::isfinite(table.modulus[i]) && table.modulus[i] >= 0.0 &&
              (i == 0 || table.strain[i] > table.strain[i - 1]);
    }
    for (const double factor : table.stiffness_per_modulus) valid = valid && std::isfinite(factor) && factor >= 0.0;
    if (!valid)
      diagnostics.error(SourceRange{}, "the strain stiffness table needs at least 2 strictly increasing finite "
                                       "strains, one finite non-negative modulus per strain and one non-negative "
                                       "factor per spring");
  }
  return diagnostics.error_count() == errors;
}

}  // namespace fmpc::sim
