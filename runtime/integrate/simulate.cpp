// The host's sums over a state (double), which both backends' readers and the run summaries share, and simulate(),
// the driver of a setup's step_count with samples.
#include <algorithm>
#include <cmath>

#include "kernels/strain_table_math.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

double elastic_energy(const SimulationSetup& setup, const std::vector<Point3>& positions) {
  const SpringNetwork& net = setup.springs;
  const kernels::SpringLawParameters<double> law{setup.law, setup.basafa_k2_over_k1, setup.basafa_xc};
  double energy = 0.0;
  for (std::size_t s = 0; s < net.size(); ++s) {
    const Point3& a = positions[static_cast<std::size_t>(net.first[s])];
    const Point3& b = positions[static_cast<std::size_t>(net.second[s])];
    const double length = distance(a, b);
    const double rest = net.rest_length[s];
    const double k = setup.strain_stiffness
                         ? kernels::strain_table_stiffness(strain_table_view(*setup.strain_stiffness), b[0] - a[0],
                                                           b[1] - a[1], b[2] - a[2], rest,
                                                           setup.strain_stiffness->stiffness_per_modulus[s])
                         : net.stiffness[s];
    energy += kernels::spring_potential_energy(length, rest, k, law);
  }
  if (!setup.elements.empty()) energy += element_elastic_energy(setup, positions);
  return energy;
}

double kinetic_energy(const SimulationSetup& setup, const std::vector<Point3>& velocities) {
  double energy = 0.0;
  for (std::size_t v = 0; v < velocities.size(); ++v) {
    const Point3& u = velocities[v];
    energy += 0.5 * setup.mass[v] * (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
  }
  return energy;
}

double steps_covering(double span, double dt) { return std::ceil(span / dt * (1.0 - 1e-12)); }

SimulationResult simulate(const SimulationSetup& setup, DiagnosticList& diagnostics) {
  SimulationResult result;
  const auto simulation = Simulation::create(setup, diagnostics);
  if (!simulation) return result;
  DiagnosticList reads;  // the CPU's reads cannot fail
  result.stability = simulation->stability();
  const auto record = [&] {
    Sample sample;
    sample.step = simulation->steps_taken();
    sample.time = simulation->time();
    const std::vector<Point3> positions = simulation->positions(reads);
    for (const auto v : setup.recorded_vertices) sample.positions.push_back(positions[static_cast<std::size_t>(v)]);
    sample.kinetic_energy = *simulation->kinetic_energy(reads);
    sample.potential_energy = *simulation->potential_energy(reads);
    result.samples.push_back(std::move(sample));
  };
  if (setup.record_every > 0) record();
  bool ok = true;
  std::size_t remaining = setup.step_count;
  while (ok && remaining > 0) {
    const std::size_t chunk = setup.record_every > 0 ? std::min(setup.record_every, remaining) : remaining;
    ok = simulation->advance(chunk, diagnostics);
    remaining -= chunk;
    if (ok && setup.record_every > 0) record();
  }
  result.completed = ok;
  result.steps_taken = simulation->steps_taken();
  result.positions = simulation->positions(reads);
  result.velocities = simulation->velocities(reads);
  result.non_finite = simulation->non_finite();
  result.inversions = simulation->inversions();
  result.implicit_max_iterations_used = simulation->implicit_max_iterations_used();
  result.implicit_solver = simulation->implicit_solver();
  return result;
}

}  // namespace fmpc::sim
