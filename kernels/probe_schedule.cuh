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

// Entry e's ramp at the chunk's step `step` (t = (base + step) h): before step `step`, or after step `step` - 1.
__device__ inline kernels::ProbeRamp probe_ramp_at(const ProbeEntry& e, int step) {
  const ProbeScene& p = e.scene;
  const double t = static_cast<double>(e.step_base + static_cast<unsigned long long>(step)) * p.h;
  return kernels::probe_ramp(t, p.ramp_time, p.cycles);
}

// Entry e before or after a step, on that time's `ramp`: a force entry gives its vertex's external force (before the
// step) in `force`; a displacement entry prescribes its vertex's position and velocity into `state` and returns
// true.
template <typename Real>
__device__ bool probe_prescribe_on(const ProbeEntry& e, const kernels::ProbeRamp& ramp, bool before_step,
                                   kernels::VertexState<Real>& state, ProbeForce<Real>& force) {
  const ProbeScene& p = e.scene;
  if (p.force_mode) {
    if (!before_step) return false;
    const double count = static_cast<double>(p.count);
    force = {true, static_cast<Real>(e.base_force_x + ramp.share * p.target_x / count),
             static_cast<Real>(e.base_force_y + ramp.share * p.target_y / count),
             static_cast<Real>(e.base_force_z + ramp.share * p.target_z / count)};
    return false;
  }
  kernels::probe_prescribed_axis(ramp, e.start_x, p.target_x, p.ramp_time, before_step, state.x, state.vx);
  kernels::probe_prescribed_axis(ramp, e.start_y, p.target_y, p.ramp_time, before_step, state.y, state.vy);
  kernels::probe_prescribed_axis(ramp, e.start_z, p.target_z, p.ramp_time, before_step, state.z, state.vz);
  return true;
}

// Entry e before or after the step at `offset` in the chunk (probe_prescribe_on).
template <typename Real>
__device__ bool probe_prescribe(const ProbeEntry& e, int offset, bool before_step, kernels::VertexState<Real>& state,
                                ProbeForce<Real>& force) {
  return probe_prescribe_on(e, probe_ramp_at(e, offset + (before_step ? 0 : 1)), before_step, state, force);
}

// Entry e after the step at `offset`, then at_step_end(x) on the state a chunk ending there holds (a persistent
// kernel's check stores it), then, where `next`, before the following step. Returns whether the entry prescribed x
// (a displacement entry prescribes every value of its vertex's state; a force entry gives its force in `force`).
// Both prescriptions are at one time, so one ramp serves them, and the position the second would write is the
// first's: only the velocity changes (the same bits as two probe_prescribe calls, with a sixth of the ramp's
// double-precision work on the path of the probe vertex's thread).
template <typename Real, typename AtStepEnd>
__device__ bool probe_between_steps(const ProbeEntry& e, int offset, bool next, kernels::VertexState<Real>& x,
                                    ProbeForce<Real>& force, AtStepEnd at_step_end) {
  const kernels::ProbeRamp ramp = probe_ramp_at(e, offset + 1);
  const bool prescribed = probe_prescribe_on(e, ramp, false, x, force);
  at_step_end(x);
  if (!next) return prescribed;
  if (!prescribed) return probe_prescribe_on(e, ramp, true, x, force);
  const ProbeScene& p = e.scene;
  x.vx = kernels::probe_ramp_velocity<Real>(ramp, p.target_x, p.ramp_time, true);
  x.vy = kernels::probe_ramp_velocity<Real>(ramp, p.target_y, p.ramp_time, true);
  x.vz = kernels::probe_ramp_velocity<Real>(ramp, p.target_z, p.ramp_time, true);
  return true;
}

template <typename Real>
__device__ void store_probe_force(const MutableVector3View<Real>& to, int v, const ProbeForce<Real>& force) {
  if (!force.set) return;
  to.x[v] = force.x;
  to.y[v] = force.y;
  to.z[v] = force.z;
}

}  // namespace fmpc::gpu
