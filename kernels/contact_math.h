#pragma once
// Frictionless penalty contact between rigid tools and the tissue's surface vertices (docs/simulator.md, "Rigid
// tools"), shared by the CPU loop, the CUDA kernels (through kernels::loaded_acceleration) and the host's reaction
// readings: one implementation for both backends.
//
// A tool is a capsule: the points within `radius` of the segment [a, b]; a sphere is the capsule with b = a. A surface
// vertex at x, with q the closest point of the segment, r = |x - q| and depth d = radius - r > 0, is pushed out along
// n = (x - q) / r by f = max(k d - c (v . n), 0) n, k the vertex's contact stiffness (zero for interior vertices, which
// never touch a tool) and c its contact damping (zero unless the scene asks: contact.damping_ratio), acting on the
// vertex's normal velocity v . n (the tool taken at rest between its poses); the damper pushes, it never pulls the
// surface onto the tool.
// A vertex exactly on the axis (r = 0) has no direction and gets no force; it can only get there by passing through
// the tool. The tool feels -f at x.
#include "kernels/fmpc_hd.h"
#include "kernels/spring_math.h"

namespace fmpc::kernels {

// The most tools one scene may hold (their shapes are an argument of every step's kernels).
constexpr int kMostTools = 8;

template <typename Real>
struct ToolShape {
  Real ax, ay, az;  // the segment's first end (the tool's origin: a sphere's centre, a capsule's tip end)
  Real bx, by, bz;  // its second end (= a for a sphere)
  Real radius;
};

// What the step reads of the tools: their shapes (null or count 0: no tool), each vertex's contact stiffness and
// damping.
template <typename Real>
struct ContactView {
  const ToolShape<Real>* tools;
  int tool_count;
  const Real* stiffness;  // N/m per vertex; zero for a vertex that cannot touch a tool
  const Real* damping;    // N s/m per vertex; null: no contact damping
};

// The offset of (x, y, z) from the closest point of the tool's segment: (rx, ry, rz).
template <typename Real>
FMPC_HD void tool_axis_offset(const ToolShape<Real>& tool, Real x, Real y, Real z, Real& rx, Real& ry, Real& rz) {
  const Real dx = tool.bx - tool.ax, dy = tool.by - tool.ay, dz = tool.bz - tool.az;
  const Real px = x - tool.ax, py = y - tool.ay, pz = z - tool.az;
  const Real length_squared = dx * dx + dy * dy + dz * dz;
  Real t = Real(0);
  if (length_squared > Real(0)) {
    t = (px * dx + py * dy + pz * dz) / length_squared;
    t = t < Real(0) ? Real(0) : (t > Real(1) ? Real(1) : t);
  }
  rx = px - t * dx;
  ry = py - t * dy;
  rz = pz - t * dz;
}

// One vertex against one tool: true where the vertex lies inside (depth > 0 and a direction), with the outward unit
// normal n and the depth d (m).
template <typename Real>
FMPC_HD bool tool_penetration(const ToolShape<Real>& tool, Real x, Real y, Real z, Real& nx, Real& ny, Real& nz,
                              Real& depth) {
  Real rx, ry, rz;
  tool_axis_offset(tool, x, y, z, rx, ry, rz);
  const Real distance_squared = rx * rx + ry * ry + rz * rz;
  // Outside the radius: no square root (every surface vertex is tested against every tool every step).
  if (!(distance_squared < tool.radius * tool.radius)) return false;
  const Real r = square_root(distance_squared);
  if (!(r > Real(0))) return false;
  nx = rx / r;
  ny = ry / r;
  nz = rz / r;
  depth = tool.radius - r;
  return true;
}

// The contact force of every tool, in list order, on a vertex at (x, y, z) moving at (vx, vy, vz) with contact
// stiffness k and damping c, added to (fx, fy, fz).
template <typename Real>
FMPC_HD void add_contact_force(const ContactView<Real>& contact, Real k, Real c, Real x, Real y, Real z, Real vx,
                               Real vy, Real vz, Real& fx, Real& fy, Real& fz) {
  for (int t = 0; t < contact.tool_count; ++t) {
    Real nx, ny, nz, depth;
    if (!tool_penetration(contact.tools[t], x, y, z, nx, ny, nz, depth)) continue;
    Real magnitude = k * depth;
    if (c > Real(0)) {
      magnitude -= c * (vx * nx + vy * ny + vz * nz);
      if (!(magnitude > Real(0))) magnitude = Real(0);
    }
    fx += magnitude * nx;
    fy += magnitude * ny;
    fz += magnitude * nz;
  }
}

// ---- implicit Euler's model of the contact (both backends' assembly, kernels/implicit_math.h's block layout) ----
// A step linearises each vertex's contact with each tool at the step's start x0: depth d(x) ~ d0 - n . (x - x0), with
// d0 = radius - r (negative outside) and n from the axis. The penalty is one-sided, so which (vertex, tool) pairs
// push is decided like an active set: the pairs inside at x0 first, then, after each solve, those the solution
// predicts inside (d0 - n . dx > 0), solved again until the set stays (runtime/integrate/cpu_engine.cpp,
// runtime/gpu/gpu_engine_implicit.cpp). Without that a vertex the tool slid off in one step feels no contact and
// relaxes through the tool, to be thrown out the next step: a period-2 chatter at large steps.

// One vertex's linearisation against one tool at (x, y, z), in double: false where it lies on the axis (no normal).
template <typename Real>
FMPC_HD bool tool_gap(const ToolShape<Real>& shape, double x, double y, double z, double* n, double& depth) {
  const ToolShape<double> tool{static_cast<double>(shape.ax), static_cast<double>(shape.ay),
                               static_cast<double>(shape.az), static_cast<double>(shape.bx),
                               static_cast<double>(shape.by), static_cast<double>(shape.bz),
                               static_cast<double>(shape.radius)};
  double rx, ry, rz;
  tool_axis_offset(tool, x, y, z, rx, ry, rz);
  const double r = square_root(rx * rx + ry * ry + rz * rz);
  if (!(r > 0.0)) return false;
  n[0] = rx / r;
  n[1] = ry / r;
  n[2] = rz / r;
  depth = tool.radius - r;
  return true;
}

// The tools (bit t for tool t) a vertex at x0 = (x, y, z) is inside after moving by dx (null: not moving) in the
// linearised model.
template <typename Real>
FMPC_HD unsigned contact_set(const ContactView<Real>& contact, double x, double y, double z, const double* dx) {
  unsigned set = 0u;
  for (int t = 0; t < contact.tool_count; ++t) {
    double n[3], depth;
    if (!tool_gap(contact.tools[t], x, y, z, n, depth)) continue;
    if (dx != nullptr) depth -= n[0] * dx[0] + n[1] * dx[1] + n[2] * dx[2];  // n points out of the tool
    if (depth > 0.0) set |= 1u << t;
  }
  return set;
}

// The linear model of one vertex's contact with the tools in `active`, at x0: its stiffness -df/dx, the symmetric
// block k sum n n^T (xx xy xz yy yz zz), and `change`, the model's force at x0 (k sum d0 n over the active tools)
// minus the force the step's f0 holds (k sum max(d0, 0) n over every tool, kernels::add_contact_force's). The exact
// tangent also has the softening term -k (d / r) (I - n n^T) (minus its axial part for a capsule), left out so that
// the system stays positive definite, as the springs' transverse term is clamped under compression.
template <typename Real>
FMPC_HD void contact_linear_model(const ContactView<Real>& contact, unsigned active, double k, double x, double y,
                                  double z, double* block, double* change) {
  for (int i = 0; i < 6; ++i) block[i] = 0.0;
  for (int i = 0; i < 3; ++i) change[i] = 0.0;
  for (int t = 0; t < contact.tool_count; ++t) {
    double n[3], depth;
    if (!tool_gap(contact.tools[t], x, y, z, n, depth)) continue;
    const bool pushing = ((active >> t) & 1u) != 0u;
    const double model = pushing ? depth : 0.0;
    const double held = depth > 0.0 ? depth : 0.0;
    for (int i = 0; i < 3; ++i) change[i] += k * (model - held) * n[i];
    if (!pushing) continue;
    block[0] += k * n[0] * n[0];
    block[1] += k * n[0] * n[1];
    block[2] += k * n[0] * n[2];
    block[3] += k * n[1] * n[1];
    block[4] += k * n[1] * n[2];
    block[5] += k * n[2] * n[2];
  }
}

// Active-set rounds per implicit step before the step goes on with the last set (with a warning).
constexpr int kMostContactRounds = 8;

}  // namespace fmpc::kernels
