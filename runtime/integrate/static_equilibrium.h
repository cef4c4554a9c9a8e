#pragma once
// The static equilibrium of a setup under its loads: f_int(x) + f_ext = 0 for the free vertices, with gravity,
// external forces, fixed vertices and a probe applied at its full target (a displacement probe's vertices moved by
// it, a force probe's total shared by its vertices). Newton's method on the model's tangent stiffness
// (model_tangent.h), each step solved by a sparse Cholesky factorisation (Eigen's SimplicialLDLT), with a
// backtracking line search on the residual. What validates the force models against analytic solutions and
// CalculiX (tests/validation), and what a converged reference of the dynamics settles to.
#include <optional>
#include <vector>

#include "diagnostics/diagnostic.h"
#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

struct StaticOptions {
  // |residual| <= tolerance x |applied load| (the largest of gravity, forces, and the first residual of a
  // displacement probe or of initial positions that move held vertices)
  double tolerance = 1e-10;
  int max_iterations = 100;  // Newton steps; reaching it is an error, never a result
  // The linear (small-strain) solution, for comparison with linear FEM codes: the stiffness at rest K0, and
  // K0 u = f_ext with the held axes' displacements (from the initial positions) prescribed. Reactions K0 u - f_ext.
  bool linear = false;
};

struct StaticResult {
  std::vector<Point3> positions;  // m
  int iterations = 0;
  double residual = 0.0;       // N, |f_int + f_ext| over the free degrees of freedom at the end
  ProbeReading probe;          // the probe's displacement and reaction (zeros without a probe)
  std::vector<Point3> reactions;  // N, -f_ext - f_int at every vertex: non-zero at fixed and probe vertices only
};

// nullopt after an error: no support (the stiffness is singular), a non-finite state, or no convergence within
// max_iterations (the error gives the residual reached).
std::optional<StaticResult> static_equilibrium(const SimulationSetup& setup, const StaticOptions& options,
                                               DiagnosticList& diagnostics);

}  // namespace fmpc::sim
