#pragma once
// The force model's tangent at a state, as sparse matrices over 3 n degrees of freedom (vertex-major, x y z): the
// stiffness K = -df/dx and the damping D = -df/dv of the springs (their blocks of kernels/implicit_math.h: k u u^T
// plus the transverse term, the dashpot c u u^T) and of the tetrahedron field (kernels/tetrahedron_math.h: R K0 R^T or
// the volume term's Gauss-Newton stiffness, and beta_e times it). The nodal and mass damping are per vertex and left
// to the caller. Implicit Euler (cpu_engine.cpp) and the static solver (static_equilibrium.h) both build their
// systems from it, so a new force model adds its blocks here once.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <Eigen/Sparse>
#pragma GCC diagnostic pop
#include <vector>

#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

struct ModelTangent {
  Eigen::SparseMatrix<double> stiffness;
  Eigen::SparseMatrix<double> damping;
};

// At `positions` (double), with the springs' current stiffness `spring_stiffness` (one per spring: a strain table's
// last lookup, or springs.stiffness) and, with a strain table, each element's modulus at its current strain.
ModelTangent model_tangent(const SimulationSetup& setup, const std::vector<Point3>& positions,
                           const std::vector<double>& spring_stiffness);

}  // namespace fmpc::sim
