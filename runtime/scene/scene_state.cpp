#include "runtime/scene/scene_state.h"

#include <algorithm>

namespace fmpc::sim {

double largest_displacement(const std::vector<Point3>& positions, const std::vector<Point3>& start) {
  double largest = 0.0;
  for (std::size_t v = 0; v < positions.size() && v < start.size(); ++v)
    largest = std::max(largest, distance(positions[v], start[v]));
  return largest;
}

bool SceneState::read_stiffness(DiagnosticList& diagnostics) {
  const SimulationSetup& setup = simulation_.setup(scene_);
  if (setup.strain_stiffness) return true;
  stiffness_ = simulation_.current_stiffness(scene_, diagnostics);
  stiffness_read_ = true;
  return stiffness_.size() == setup.springs.size();
}

std::vector<Point3> SceneState::positions(DiagnosticList& diagnostics) const {
  if (positions_ != nullptr) return *positions_;
  return simulation_.positions(scene_, diagnostics);
}

std::vector<Point3> SceneState::velocities(DiagnosticList& diagnostics) const {
  if (positions_ != nullptr) return velocities_ != nullptr ? *velocities_ : std::vector<Point3>{};
  return simulation_.velocities(scene_, diagnostics);
}

ProbeReading SceneState::probe_reading(DiagnosticList& diagnostics) const {
  if (positions_ == nullptr) return simulation_.probe_reading(scene_, diagnostics);
  const SimulationSetup& setup = simulation_.setup(scene_);
  if (!setup.probe || velocities_ == nullptr) return {};
  return read_probe(setup, time(), *positions_, *velocities_, current_stiffness(diagnostics));
}

std::vector<ToolReading> SceneState::tool_readings(DiagnosticList& diagnostics) const {
  if (positions_ == nullptr) return simulation_.tool_readings(scene_, diagnostics);
  return read_tools(simulation_.setup(scene_).tools, simulation_.tool_poses(scene_),
                    simulation_.contact_stiffness(scene_), *positions_, simulation_.contact_damping(scene_),
                    velocities_ != nullptr ? *velocities_ : std::vector<Point3>{});
}

std::vector<double> SceneState::current_stiffness(DiagnosticList& diagnostics) const {
  if (stiffness_read_) return stiffness_;
  return simulation_.current_stiffness(scene_, diagnostics);
}

std::optional<double> SceneState::largest_displacement(const std::vector<Point3>& start,
                                                       DiagnosticList& diagnostics) const {
  if (reduces_in_place()) return simulation_.largest_displacement(scene_, diagnostics);
  const std::vector<Point3> now = positions(diagnostics);
  if (now.size() != start.size()) return std::nullopt;  // a device error, already reported
  return sim::largest_displacement(now, start);
}

std::optional<std::pair<double, double>> SceneState::energies(const SimulationSetup& setup,
                                                              const std::vector<Point3>& positions,
                                                              const std::vector<Point3>& velocities,
                                                              DiagnosticList& diagnostics) const {
  if (!reduces_in_place()) return std::make_pair(kinetic_energy(setup, velocities), elastic_energy(setup, positions));
  const auto kinetic = simulation_.kinetic_energy(scene_, diagnostics);
  const auto elastic = simulation_.elastic_energy(scene_, diagnostics);
  if (!kinetic || !elastic) return std::nullopt;
  return std::make_pair(*kinetic, *elastic);
}

}  // namespace fmpc::sim
