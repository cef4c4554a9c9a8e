#pragma once
// The internal forces of a force model at one vertex, for the integrators (kernels/integrator_math.h): each model is
// a plain struct with an FMPC_HD `gather`, and the integrators, the CPU loops and the CUDA kernels are templates over
// it (static dispatch: no virtual call per vertex or element). As SOFA keeps ForceField apart from the ODE solver, a
// new force model is a new struct here and plugs into every integrator on both backends.
//
// - SpringForces: springs gathered over the CSR adjacency (kernels/spring_math.h);
// - ElementForces: per-tetrahedron forces computed beforehand, one pass over the elements (kernels/
//   tetrahedron_math.h, co-rotational FEM), then gathered per vertex over the corner CSR;
// - SpringAndElementForces: both (springs with the volume term of Teschner et al. 2004).
// Each vertex adds its terms in one fixed order (springs first, then corners), so the sums do not depend on threads
// or scheduling and the CUDA kernels add the same terms in the same order as the CPU loop.
#include "kernels/fmpc_hd.h"
#include "kernels/spring_math.h"
#include "kernels/tetrahedron_math.h"

namespace fmpc::kernels {

// `row`: the thread's sliced row on the GPU (kernels/spring_math.h, SlicedSpringsView), loaded with its vertex;
// count -1 (the default) reads the CSR order (the CPU, the lane kernels).
template <typename Real>
struct SpringForces {
  SpringNetworkView<Real> springs;
  SlicedRow row{0, -1};
  FMPC_HD void gather(int v, const StateView<Real>& s, Real& fx, Real& fy, Real& fz) const {
    gather_spring_force(v, row, springs, s, fx, fy, fz);
  }
};

template <typename Real>
struct ElementForces {
  CornerForceView<Real> corners;
  FMPC_HD void gather(int v, const StateView<Real>&, Real& fx, Real& fy, Real& fz) const {
    gather_corner_force(v, corners, fx, fy, fz);
  }
};

template <typename Real>
struct SpringAndElementForces {
  SpringNetworkView<Real> springs;
  CornerForceView<Real> corners;
  SlicedRow row{0, -1};
  FMPC_HD void gather(int v, const StateView<Real>& s, Real& fx, Real& fy, Real& fz) const {
    gather_spring_force(v, row, springs, s, fx, fy, fz);
    Real cx, cy, cz;
    gather_corner_force(v, corners, cx, cy, cz);
    fx += cx;
    fy += cy;
    fz += cz;
  }
};

// The per-tetrahedron data of a force model as raw arrays, element-major, for the element pass.
template <typename Real>
struct TetrahedronFieldView {
  TetrahedronLaw law;
  int count;
  const int* corners;          // 4 per element
  const int* corner_slot;      // 4 per element: where each corner's force goes (CornerForceView's order)
  const Real* rest_inverse;    // 9 per element
  const Real* rest_volume;
  const Real* youngs_modulus;  // CorotationalLinear (Pa)
  const Real* poisson_ratio;   // CorotationalLinear
  const Real* bulk_modulus;    // VolumePreservation (Pa)
  const Real* stiffness_damping;  // null: none
  StrainTableView strain_table;   // strain null: none
};

template <typename Real>
FMPC_HD TetrahedronMaterial<Real> tetrahedron_material(const TetrahedronFieldView<Real>& f, int e) {
  TetrahedronMaterial<Real> m;
  m.law = f.law;
  m.rest_inverse = f.rest_inverse + 9 * e;
  m.rest_volume = f.rest_volume[e];
  m.youngs_modulus = f.youngs_modulus ? f.youngs_modulus[e] : Real(0);
  m.poisson_ratio = f.poisson_ratio ? f.poisson_ratio[e] : Real(0);
  m.bulk_modulus = f.bulk_modulus ? f.bulk_modulus[e] : Real(0);
  m.stiffness_damping = f.stiffness_damping ? f.stiffness_damping[e] : Real(0);
  m.strain_table = f.strain_table.strain ? &f.strain_table : nullptr;
  return m;
}

// The element pass: element e's four corner forces into force[corner_slot[4 e + a]] (the vertex-major layout
// CornerForceView reads). Velocities are read only where a stiffness damping array exists: tetrahedron_forces
// reads them for nothing else, and they are half the pass's gathered bytes.
template <typename Real>
FMPC_HD void tetrahedron_corner_forces(int e, const TetrahedronFieldView<Real>& f, const StateView<Real>& s,
                                       CornerForce<Real>* force) {
  Real x[4][3], v[4][3] = {}, out[4][3];
  const bool damped = f.stiffness_damping != nullptr;
  for (int a = 0; a < 4; ++a) {
    const int vertex = f.corners[4 * e + a];
    x[a][0] = s.x[vertex];
    x[a][1] = s.y[vertex];
    x[a][2] = s.z[vertex];
    if (damped) {
      v[a][0] = s.vx[vertex];
      v[a][1] = s.vy[vertex];
      v[a][2] = s.vz[vertex];
    }
  }
  const TetrahedronMaterial<Real> m = tetrahedron_material(f, e);
  tetrahedron_forces(m, x, v, out);
  for (int a = 0; a < 4; ++a) force[f.corner_slot[4 * e + a]] = {out[a][0], out[a][1], out[a][2], Real(0)};
}

// Whether element e of `corners` is inverted or flat at positions s (signed volume <= 0), for the inversion count.
template <typename Real>
FMPC_HD bool tetrahedron_inverted(int e, const int* corners, const Real* x, const Real* y, const Real* z) {
  Real p[4][3];
  for (int a = 0; a < 4; ++a) {
    const int vertex = corners[4 * e + a];
    p[a][0] = x[vertex];
    p[a][1] = y[vertex];
    p[a][2] = z[vertex];
  }
  return !(tetrahedron_volume(p) > Real(0));
}

}  // namespace fmpc::kernels
