#pragma once
// The probe's schedule on the device, the same for every kernel that applies it (docs/simulator.md, "Probes"):
// before step s of a chunk that starts at step `base` (t = (base + s) h) a displacement entry prescribes its vertex's
// position and the ramp's velocity and a force entry its vertex's external force; after the step (t + h) a
// displacement entry prescribes the position again with zero velocity. A kernel that keeps a vertex across steps
// (the per-step fused kernels' thread of a probe vertex, the persistent and cluster kernels) applies "after step s"
// and "before step s + 1" in one go (probe_between_steps), which is what the CPU loop's order amounts to.
#include "kernels/step_device.cuh"

namespace fmpc::gpu {

// A force entry's force on its vertex, where a prescription set one.
template <typename Real>
struct ProbeForce {
  bool set = false;
  Real x = Real(0), y = Real(0), z = Real(0);
};

// ProbeArguments' entry i, for a chunk starting at step `step_base` (the per-step kernels read it from
// ProbeArguments::step_base, the persistent kernels have it by value).
template <typename Real>
__device__ ProbeEntry probe_entry(const ProbeArguments<Real>& a, int i, unsigned long long step_base) {
  ProbeEntry e;
  e.scene = a.scenes[a.entry_scene[i]];
  e.start_x = a.start_x[i];
  e.start_y = a.start_y[i];
  e.start_z = a.start_z[i];
  const bool based = e.scene.force_mode && e.scene.has_base_force;
  e.base_force_x = based ? a.base_force_x[i] : 0.0;
  e.base_force_y = based ? a.base_force_y[i] : 0.0;
  e.base_force_z = based ? a.base_force_z[i] : 0.0;
  e.step_base = step_base;
  e.vertex = a.vertices[i];
  return e;
}

// Entry e before or after the step at `offset` in the chunk: a force entry gives its vertex's external force (before
// the step) in `force`; a displacement entry prescribes its vertex's position and velocity into `state` and returns
// true.
template <typename Real>
__device__ bool probe_prescribe(const ProbeEntry& e, int offset, bool before_step, kernels::VertexState<Real>& state,
                                ProbeForce<Real>& force) {
  const ProbeScene& p = e.scene;
  const double t =
      static_cast<double>(e.step_base + static_cast<unsigned long long>(offset + (before_step ? 0 : 1))) * p.h;
  if (p.force_mode) {
    if (!before_step) return false;
    const double share = kernels::probe_ramp_share(t, p.ramp_time, p.cycles);
    const double count = static_cast<double>(p.count);
    force = {true, static_cast<Real>(e.base_force_x + share * p.target_x / count),
             static_cast<Real>(e.base_force_y + share * p.target_y / count),
             static_cast<Real>(e.base_force_z + share * p.target_z / count)};
    return false;
  }
  kernels::probe_prescribed_state(e.start_x, p.target_x, t, p.ramp_time, p.cycles, before_step, state.x, state.vx);
  kernels::probe_prescribed_state(e.start_y, p.target_y, t, p.ramp_time, p.cycles, before_step, state.y, state.vy);
  kernels::probe_prescribed_state(e.start_z, p.target_z, t, p.ramp_time, p.cycles, before_step, state.z, state.vz);
  return true;
}

// Entry e after the step at `offset`, then at_step_end(x) on the state a chunk ending there holds (a persistent
// kernel's check stores it), then, where `next`, before the following step. Returns whether the entry prescribed x
// (a displacement entry prescribes every value of its vertex's state; a force entry gives its force in `force`).
template <typename Real, typename AtStepEnd>
__device__ bool probe_between_steps(const ProbeEntry& e, int offset, bool next, kernels::VertexState<Real>& x,
                                    ProbeForce<Real>& force, AtStepEnd at_step_end) {
  bool prescribed = probe_prescribe(e, offset, false, x, force);
  at_step_end(x);
  if (next) prescribed = probe_prescribe(e, offset + 1, true, x, force) || prescribed;
  return prescribed;
}

template <typename Real>
__device__ void store_probe_force(const MutableVector3View<Real>& to, int v, const ProbeForce<Real>& force) {
  if (!force.set) return;
  to.x[v] = force.x;
  to.y[v] = force.y;
  to.z[v] = force.z;
}

}  // namespace fmpc::gpu
