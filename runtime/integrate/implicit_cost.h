#pragma once
// What each of implicit Euler's CPU solvers costs per step on a system's pattern (implicit_system.h), for Automatic's
// choice (implicit_solver.h; docs/simulator.md, "Choosing the solver"). Counts of floating-point operations, from the
// pattern alone: the direct solver's from the fill of an LDL^T factor under an AMD ordering (symbolic, on the vertex
// graph: each 3 x 3 block a vertex, each scalar column of a vertex as long as its block column), the CG's per
// iteration from the blocks and the vectors. Internal to runtime/integrate.
#include <cstddef>

#include "runtime/integrate/implicit_system.h"

namespace fmpc::sim {

struct ImplicitCost {
  double factor_nonzeros = 0.0;    // below the diagonal of L (scalar)
  double direct_step = 0.0;        // one numeric factorisation (sum over L's columns of their squared lengths) and
                                   // one solve (forward and back: 4 per factor non-zero)
  double cg_iteration = 0.0;       // one CG iteration: the product (18 per block) and the vector passes (14 per dof)
};

ImplicitCost implicit_cost(const ImplicitSystem& system);

}  // namespace fmpc::sim
