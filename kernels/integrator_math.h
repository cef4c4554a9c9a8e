#pragma once
// Per-vertex pieces of the integrators, shared by the CPU loops and the CUDA kernels.
#include "kernels/contact_math.h"
#include "kernels/fmpc_hd.h"
#include "kernels/internal_force_math.h"
#include "kernels/spring_math.h"

namespace fmpc::kernels {

// Which axes of a vertex are held (bit a: axis a), as SOFA's FixedConstraint (all three) and
// PartialFixedConstraint (some: a vertex sliding on a plane) do.
constexpr unsigned char kAllAxesFixed = 7;
FMPC_HD bool axis_fixed(unsigned char mask, int axis) { return ((mask >> axis) & 1u) != 0u; }

// Loads that are the same for every vertex (per-vertex external forces are an optional array).
template <typename Real>
struct VertexLoads {
  const Real* mass;
  const unsigned char* fixed;  // held axes per vertex (kAllAxesFixed: the vertex does not move)
  const Real* rest_x;          // reference position x0 for the nodal damping gamma0 + gamma1 |x - x0|
  const Real* rest_y;
  const Real* rest_z;
  const Real* force_x;  // constant external force (N) or null
  const Real* force_y;
  const Real* force_z;
  Real gravity_x, gravity_y, gravity_z;
  Real gamma0, gamma1;  // nodal damping (Basafa-Farahmand), N s/m and N s/m^2
  Real mass_damping;    // Rayleigh's mass-proportional alpha (1/s): force -alpha m v
  ContactView<Real> contact;  // rigid tools (kernels/contact_math.h); tool_count 0: none
};

// A vertex's own load values (VertexLoads' per-vertex arrays at one vertex): what loaded_acceleration reads besides
// the loads common to every vertex. The persistent CUDA kernel keeps them in registers for a launch.
template <typename Real>
struct VertexLoadValues {
  Real mass;
  Real rest_x, rest_y, rest_z;     // read where there is nodal damping
  Real force_x, force_y, force_z;  // zero without external forces
  Real contact_stiffness;          // zero without tools
  Real contact_damping;            // zero without contact damping
};

template <typename Real>
FMPC_HD VertexLoadValues<Real> vertex_load_values(const VertexLoads<Real>& loads, int v) {
  VertexLoadValues<Real> l{loads.mass[v], Real(0), Real(0), Real(0), Real(0), Real(0), Real(0), Real(0), Real(0)};
  if (loads.gamma0 != Real(0) || loads.gamma1 != Real(0)) {
    l.rest_x = loads.rest_x[v];
    l.rest_y = loads.rest_y[v];
    l.rest_z = loads.rest_z[v];
  }
  if (loads.force_x) {
    l.force_x = loads.force_x[v];
    l.force_y = loads.force_y[v];
    l.force_z = loads.force_z[v];
  }
  if (loads.contact.tool_count > 0) l.contact_stiffness = loads.contact.stiffness[v];
  if (loads.contact.damping) l.contact_damping = loads.contact.damping[v];
  return l;
}

// Acceleration of a vertex at (x, v) = `self` with load values `own`, not held on every axis, under the model's
// internal force f: (f + external force + the tools' contact force - (gamma0 + gamma1 |x - x0|) v - alpha m v) / m
// + g; zero along held axes.
template <typename Real>
FMPC_HD void loaded_acceleration(const VertexLoadValues<Real>& own, unsigned char held, const VertexState<Real>& self,
                                 Real fx, Real fy, Real fz, const VertexLoads<Real>& loads, Real& ax, Real& ay,
                                 Real& az) {
  if (loads.force_x) {
    fx += own.force_x;
    fy += own.force_y;
    fz += own.force_z;
  }
  if (own.contact_stiffness > Real(0))
    add_contact_force(loads.contact, own.contact_stiffness, own.contact_damping, self.x, self.y, self.z, self.vx,
                      self.vy, self.vz, fx, fy, fz);
  if (loads.gamma0 != Real(0) || loads.gamma1 != Real(0)) {
    const Real dx = self.x - own.rest_x, dy = self.y - own.rest_y, dz = self.z - own.rest_z;
    const Real gamma = loads.gamma0 + loads.gamma1 * square_root(dx * dx + dy * dy + dz * dz);
    fx -= gamma * self.vx;
    fy -= gamma * self.vy;
    fz -= gamma * self.vz;
  }
  if (loads.mass_damping != Real(0)) {
    const Real drag = loads.mass_damping * own.mass;
    fx -= drag * self.vx;
    fy -= drag * self.vy;
    fz -= drag * self.vz;
  }
  const Real inverse_mass = Real(1) / own.mass;
  ax = axis_fixed(held, 0) ? Real(0) : fx * inverse_mass + loads.gravity_x;
  ay = axis_fixed(held, 1) ? Real(0) : fy * inverse_mass + loads.gravity_y;
  az = axis_fixed(held, 2) ? Real(0) : fz * inverse_mass + loads.gravity_z;
}

// loaded_acceleration of vertex v with its load values read from `loads`.
template <typename Real>
FMPC_HD void loaded_acceleration(int v, unsigned char held, const VertexState<Real>& self, Real fx, Real fy, Real fz,
                                 const VertexLoads<Real>& loads, Real& ax, Real& ay, Real& az) {
  loaded_acceleration(vertex_load_values(loads, v), held, self, fx, fy, fz, loads, ax, ay, az);
}

// Acceleration of vertex v: loaded_acceleration under the internal forces `forces` gathers (one of the structs of
// kernels/internal_force_math.h); zero for a vertex held on every axis.
template <typename Real, typename Forces>
FMPC_HD void vertex_acceleration(int v, const Forces& forces, const StateView<Real>& s, const VertexLoads<Real>& loads,
                                 Real& ax, Real& ay, Real& az) {
  const unsigned char held = loads.fixed[v];
  if (held == kAllAxesFixed) {
    ax = ay = az = Real(0);
    return;
  }
  Real fx, fy, fz;
  forces.gather(v, s, fx, fy, fz);
  loaded_acceleration(v, held, vertex_state(s, v), fx, fy, fz, loads, ax, ay, az);
}

// Forward (explicit) Euler, the thesis's scheme: x1 = x0 + h v0, v1 = v0 + h a(x0, v0).
template <typename Real>
FMPC_HD void forward_euler_update(Real& x, Real& v, Real a, Real h) {
  x += h * v;
  v += h * a;
}

// Semi-implicit (symplectic) Euler: v1 = v0 + h a(x0, v0), x1 = x0 + h v1.
template <typename Real>
FMPC_HD void semi_implicit_euler_update(Real& x, Real& v, Real a, Real h) {
  v += h * a;
  x += h * v;
}

// Velocity Verlet, first half: x1 = x0 + h v0 + h^2/2 a0; the velocity predictor v0 + h a0 feeds a1 = a(x1, .)
// so that velocity-dependent damping keeps the scheme second order.
template <typename Real>
FMPC_HD void verlet_position_update(Real& x, Real v, Real a, Real h, Real& v_predicted) {
  x += h * v + Real(0.5) * h * h * a;
  v_predicted = v + h * a;
}

// Velocity Verlet, second half: v1 = v0 + h/2 (a0 + a1).
template <typename Real>
FMPC_HD void verlet_velocity_update(Real& v, Real a0, Real a1, Real h) {
  v += Real(0.5) * h * (a0 + a1);
}

// A probe's ramp at time t (s): its share of the target, linear from 0 at t = 0 to 1 at the ramp time, then held
// (ramp_time 0: at once), and whether it is still moving (a velocity before a step). Evaluated in double by both
// backends so that the prescribed path is the same bits. Once t reaches the ramp time, t / ramp_time rounds to 1 or
// more, so the division is skipped: on the GPU it is a double-precision sequence on the path of the probe vertex's
// thread, which its neighbours' blocks wait for; for the same reason the ramp is evaluated once for a vertex's three
// axes (and once for the prescriptions after a step and before the next, which share their time) rather than per
// axis. With `cycles` > 0 the share is a triangle wave instead: up to 1 at the ramp time, back to 0 at twice it,
// `cycles` times, then held at 0 (cyclic loading: a viscoelastic material's hysteresis); `falling` in a period's
// second half. The period's index is a truncation (exact), the rest + - * /.
struct ProbeRamp {
  double share;
  bool moving;
  bool falling;
};
FMPC_HD double probe_cycle_phase(double t, double ramp_time) {
  const double u = t / ramp_time;
  const double whole = static_cast<double>(static_cast<long long>(u / 2.0));
  return u - 2.0 * whole;  // in [0, 2): rising below 1, falling above
}
FMPC_HD ProbeRamp probe_ramp(double t, double ramp_time, int cycles) {
  if (cycles > 0 && ramp_time > 0.0) {
    if (!(t < 2.0 * ramp_time * cycles)) return {0.0, false, false};
    const double phase = probe_cycle_phase(t, ramp_time);
    return phase < 1.0 ? ProbeRamp{phase, true, false} : ProbeRamp{2.0 - phase, true, true};
  }
  if (!(ramp_time > 0.0) || !(t < ramp_time)) return {1.0, false, false};
  const double share = t / ramp_time;
  return {share < 1.0 ? share : 1.0, true, false};
}
FMPC_HD double probe_ramp_share(double t, double ramp_time, int cycles) {
  return probe_ramp(t, ramp_time, cycles).share;
}

// One axis of a displacement probe's vertex on `ramp`: position start + share target, and the ramp's velocity
// before a step while it moves (which the dashpots and the implicit step see); zero otherwise.
template <typename Real>
FMPC_HD Real probe_ramp_position(const ProbeRamp& ramp, double start, double target) {
  return static_cast<Real>(start + ramp.share * target);
}
template <typename Real>
FMPC_HD Real probe_ramp_velocity(const ProbeRamp& ramp, double target, double ramp_time, bool before_step) {
  if (!(before_step && ramp.moving)) return static_cast<Real>(0.0);
  return static_cast<Real>(ramp.falling ? -target / ramp_time : target / ramp_time);
}
template <typename Real>
FMPC_HD void probe_prescribed_axis(const ProbeRamp& ramp, double start, double target, double ramp_time,
                                   bool before_step, Real& position, Real& velocity) {
  position = probe_ramp_position<Real>(ramp, start, target);
  velocity = probe_ramp_velocity<Real>(ramp, target, ramp_time, before_step);
}

// Classical Runge-Kutta: y1 = y0 + h/6 (k1 + 2 k2 + 2 k3 + k4).
template <typename Real>
FMPC_HD Real runge_kutta4_combine(Real y0, Real k1, Real k2, Real k3, Real k4, Real h) {
  return y0 + h / Real(6) * (k1 + Real(2) * k2 + Real(2) * k3 + k4);
}

}  // namespace fmpc::kernels
