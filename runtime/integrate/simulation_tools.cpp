// The Simulation's rigid tools (poses along paths or set by the caller, readings) and its material replacement
// between two steps: what a session (runtime/session/) drives every tick, on both backends through the engine.
#include <algorithm>
#include <cstring>

#include "runtime/integrate/stepping_engine.h"

namespace fmpc::sim {

namespace {

bool same_pose(const ToolPose& a, const ToolPose& b) {
  return std::memcmp(a.position.data(), b.position.data(), sizeof a.position) == 0 &&
         std::memcmp(a.orientation.data(), b.orientation.data(), sizeof a.orientation) == 0;
}

std::vector<kernels::ToolShape<double>> tool_shapes(const std::vector<RigidTool>& tools,
                                                    const std::vector<ToolPose>& poses) {
  std::vector<kernels::ToolShape<double>> shapes;
  for (std::size_t t = 0; t < tools.size(); ++t) shapes.push_back(tool_shape(tools[t], poses[t]));
  return shapes;
}

// Copies `from` into `to` without reallocating `to` (the engines' views point into it); the sizes are equal.
template <typename T>
void overwrite(std::vector<T>& to, const std::vector<T>& from) {
  std::copy(from.begin(), from.end(), to.begin());
}

// Why `material` cannot replace `current`'s material, or empty.
std::string material_mismatch(const SimulationSetup& current, const SimulationSetup& material) {
  const auto count = [](const char* what, std::size_t had, std::size_t given) {
    return std::string("it has ") + std::to_string(given) + " " + what + " where the simulation has " +
           std::to_string(had);
  };
  if (material.rest_positions.size() != current.rest_positions.size())
    return count("vertices", current.rest_positions.size(), material.rest_positions.size());
  if (material.springs.first != current.springs.first || material.springs.second != current.springs.second)
    return material.springs.size() != current.springs.size()
               ? count("springs", current.springs.size(), material.springs.size())
               : "its springs join other vertices";
  if (material.springs.stiffness.size() != current.springs.stiffness.size() ||
      material.springs.damping.size() != current.springs.damping.size())
    return "its springs' stiffness or damping arrays have other sizes (dashpots where there were none, or none where "
           "there were)";
  if (material.tetrahedra != current.tetrahedra)
    return material.tetrahedra.size() != current.tetrahedra.size()
               ? count("tetrahedra", current.tetrahedra.size(), material.tetrahedra.size())
               : "its tetrahedra have other corners";
  if (material.elements.terms.size() != current.elements.terms.size())
    return count("element terms", current.elements.terms.size(), material.elements.terms.size());
  for (std::size_t t = 0; t < current.elements.terms.size(); ++t) {
    const ElementTerm& a = current.elements.terms[t];
    const ElementTerm& b = material.elements.terms[t];
    if (a.law != b.law) return "its element term " + std::to_string(t) + " has another law";
    for (int p = 0; p < kernels::kMostLawParameters; ++p)
      if (a.parameter[p].size() != b.parameter[p].size())
        return "its element term " + std::to_string(t) + " has another number of values of parameter " +
               std::to_string(p);
    if (a.stiffness_damping.size() != b.stiffness_damping.size())
      return "its element term " + std::to_string(t) + " has damping values where there were none, or the reverse";
    if (a.prony.size() != b.prony.size())
      return "its element term " + std::to_string(t) + " has " + std::to_string(b.prony.size()) +
             " Prony terms where the simulation has " + std::to_string(a.prony.size()) +
             " (the series' length sets the state each point keeps)";
  }
  if (material.strain_stiffness.has_value() != current.strain_stiffness.has_value())
    return material.strain_stiffness ? "it has a strain-dependent modulus where the simulation has a fixed one"
                                     : "it has a fixed modulus where the simulation has a strain-dependent one";
  if (current.strain_stiffness) {
    const StrainStiffnessTable& a = *current.strain_stiffness;
    const StrainStiffnessTable& b = *material.strain_stiffness;
    if (a.strain.size() != b.strain.size() || a.stiffness_per_modulus.size() != b.stiffness_per_modulus.size())
      return count("strain table points", a.strain.size(), b.strain.size());
  }
  return {};
}

}  // namespace

bool Simulation::tools_move() const {
  for (std::size_t s = 0; s < scenes_.size(); ++s)
    for (const RigidTool& tool : scenes_[s].tools)
      if (tool.path.size() > 1 && time(s) < tool.path.back().time) return true;
  return false;
}

bool Simulation::pose_tools(std::size_t step, DiagnosticList& diagnostics) {
  for (std::size_t s = 0; s < scenes_.size(); ++s) {
    const std::vector<RigidTool>& tools = scenes_[s].tools;
    if (tools.empty()) continue;
    const double t = static_cast<double>(step) * stability_[s].time_step;
    bool changed = false;
    for (std::size_t k = 0; k < tools.size(); ++k) {
      const ToolPose pose = tool_pose_at(tools[k], t);
      if (same_pose(pose, tool_poses_[s][k])) continue;
      tool_poses_[s][k] = pose;
      changed = true;
    }
    if (changed && !engine_->set_tool_shapes(s, tool_shapes(tools, tool_poses_[s]), diagnostics)) return false;
  }
  return true;
}

bool Simulation::start_tools(DiagnosticList& diagnostics) {
  tool_poses_.assign(scenes_.size(), {});
  contact_stiffness_.assign(scenes_.size(), {});
  contact_damping_.assign(scenes_.size(), {});
  for (std::size_t s = 0; s < scenes_.size(); ++s) {
    const std::vector<RigidTool>& tools = scenes_[s].tools;
    if (tools.empty()) continue;
    for (const RigidTool& tool : tools) tool_poses_[s].push_back(tool_pose_at(tool, 0.0));
    contact_stiffness_[s] = sim::contact_stiffness(scenes_[s]);
    contact_damping_[s] = sim::contact_damping(scenes_[s], contact_stiffness_[s]);
    if (!engine_->set_contact(s, contact_stiffness_[s], contact_damping_[s], diagnostics) ||
        !engine_->set_tool_shapes(s, tool_shapes(tools, tool_poses_[s]), diagnostics))
      return false;
  }
  return true;
}

bool Simulation::run_engine(const std::vector<std::size_t>& ends, DiagnosticList& diagnostics) {
  if (!tools_move()) return pose_tools(engine_->steps_taken(), diagnostics) && engine_->run(ends, diagnostics);
  for (std::size_t step = engine_->steps_taken(); step < ends.back(); ++step)
    if (!pose_tools(step, diagnostics) || !engine_->run({step + 1}, diagnostics)) return false;
  return true;
}

bool Simulation::set_tool_pose(std::size_t scene, std::size_t tool, ToolPose pose, DiagnosticList& diagnostics) {
  const SourceRange argument{"argument 'pose'", 0, 0, 0, 0};
  if (!scene_exists(scene, scenes_.size(), diagnostics)) return false;
  std::vector<RigidTool>& tools = scenes_[scene].tools;
  if (tool >= tools.size()) {
    diagnostics.error(SourceRange{"argument 'tool'", 0, 0, 0, 0},
                      "tool " + std::to_string(tool) + " does not exist; the scene has " +
                          std::to_string(tools.size()) + (tools.empty() ? " (add one under tools:)" : ""));
    return false;
  }
  const std::string name = "tool " + std::to_string(tool) + (tools[tool].name.empty() ? "" : " '" + tools[tool].name + "'");
  if (failed_) {
    diagnostics.error(argument, name + ": the simulation stopped at an earlier error; create it again");
    return false;
  }
  if (!validate_pose(pose, name, argument, diagnostics)) return false;
  tools[tool].path = {ToolKeyframe{time(scene), pose}};
  tool_poses_[scene][tool] = pose;
  if (!engine_->set_tool_shapes(scene, tool_shapes(tools, tool_poses_[scene]), diagnostics)) return fail();
  return true;
}

std::optional<DevicePositions> Simulation::device_positions(std::size_t scene, DiagnosticList& diagnostics) const {
  if (!scene_exists(scene, scenes_.size(), diagnostics)) return std::nullopt;
  if (backend_ != Backend::Cuda) {
    diagnostics.error(SourceRange{}, "the positions live on the host with the CPU backend; read positions() instead "
                                     "of a device pointer");
    return std::nullopt;
  }
  return engine_->device_positions(scene, diagnostics);
}

const std::vector<ToolPose>& Simulation::tool_poses(std::size_t scene) const { return tool_poses_.at(scene); }

const std::vector<double>& Simulation::contact_stiffness(std::size_t scene) const {
  return contact_stiffness_.at(scene);
}

const std::vector<double>& Simulation::contact_damping(std::size_t scene) const { return contact_damping_.at(scene); }

std::vector<ToolReading> Simulation::tool_readings(std::size_t scene, DiagnosticList& diagnostics) const {
  const std::vector<Point3> now = positions(scene, diagnostics);
  if (now.size() != scenes_.at(scene).rest_positions.size()) return {};
  if (contact_damping_[scene].empty())
    return read_tools(scenes_[scene].tools, tool_poses_[scene], contact_stiffness_[scene], now);
  const std::vector<Point3> moving = velocities(scene, diagnostics);
  if (moving.size() != now.size()) return {};
  return read_tools(scenes_[scene].tools, tool_poses_[scene], contact_stiffness_[scene], now, contact_damping_[scene],
                    moving);
}

bool Simulation::replace_material(std::size_t scene, const SimulationSetup& material, DiagnosticList& diagnostics) {
  const SourceRange argument{"argument 'material'", 0, 0, 0, 0};
  if (!scene_exists(scene, scenes_.size(), diagnostics)) return false;
  if (failed_) {
    diagnostics.error(argument, "the simulation stopped at an earlier error; the material was not replaced");
    return false;
  }
  SimulationSetup& current = scenes_[scene];
  const std::string mismatch = material_mismatch(current, material);
  if (!mismatch.empty()) {
    diagnostics.error(argument, "the new material does not fit this simulation: " + mismatch +
                                    "; build it from the same mesh and model");
    return false;
  }
  // The candidate: the current setup with the new material, checked (values, stability) at the step in use.
  SimulationSetup candidate = current;
  candidate.springs.stiffness = material.springs.stiffness;
  candidate.springs.damping = material.springs.damping;
  for (std::size_t t = 0; t < candidate.elements.terms.size(); ++t) {
    for (int p = 0; p < kernels::kMostLawParameters; ++p)
      candidate.elements.terms[t].parameter[p] = material.elements.terms[t].parameter[p];
    candidate.elements.terms[t].stiffness_damping = material.elements.terms[t].stiffness_damping;
    candidate.elements.terms[t].prony = material.elements.terms[t].prony;
  }
  candidate.strain_stiffness = material.strain_stiffness;
  candidate.time_step = stability_[scene].time_step;
  DiagnosticList checks;
  const std::optional<StabilityReport> report = check_stability(candidate, checks);
  if (!report) {
    for (Diagnostic diagnostic : checks.items()) {
      diagnostic.message = "the new material: " + diagnostic.message;
      diagnostics.add(std::move(diagnostic));
    }
    diagnostics.error(argument, "the material was not replaced; the simulation goes on with the old one");
    return false;
  }
  overwrite(current.springs.stiffness, candidate.springs.stiffness);
  overwrite(current.springs.damping, candidate.springs.damping);
  for (std::size_t t = 0; t < current.elements.terms.size(); ++t) {
    for (int p = 0; p < kernels::kMostLawParameters; ++p)
      overwrite(current.elements.terms[t].parameter[p], candidate.elements.terms[t].parameter[p]);
    overwrite(current.elements.terms[t].stiffness_damping, candidate.elements.terms[t].stiffness_damping);
    overwrite(current.elements.terms[t].prony, candidate.elements.terms[t].prony);
  }
  if (current.strain_stiffness) {
    overwrite(current.strain_stiffness->strain, candidate.strain_stiffness->strain);
    overwrite(current.strain_stiffness->modulus, candidate.strain_stiffness->modulus);
    overwrite(current.strain_stiffness->stiffness_per_modulus, candidate.strain_stiffness->stiffness_per_modulus);
  }
  StabilityReport kept = *report;
  kept.automatic = stability_[scene].automatic;
  stability_[scene] = kept;
  if (!engine_->refresh_material(scene, diagnostics)) return fail();
  if (!current.tools.empty()) {
    contact_stiffness_[scene] = sim::contact_stiffness(current);
    contact_damping_[scene] = sim::contact_damping(current, contact_stiffness_[scene]);
    if (!engine_->set_contact(scene, contact_stiffness_[scene], contact_damping_[scene], diagnostics)) return fail();
  }
  return true;
}

}  // namespace fmpc::sim
