#pragma once
// One implicit Euler step's linear solve on the CPU (implicit_system.h's system), by the method the setup asks for
// (ImplicitSolverOptions): a sparse direct factorisation (Eigen's SimplicialLDLT with AMD ordering, its symbolic
// analysis done once for the fixed pattern, the numeric factorisation every step, refined with further solves while
// the residual is above the tolerance) or a preconditioned conjugate gradient (block Jacobi: each vertex's 3 x 3
// diagonal block inverted), started from the previous step's solution. Automatic takes the direct solver up to
// kDirectSolverMostUnknowns free unknowns (docs/simulator.md gives the measurements behind the threshold and the
// choice of SimplicialLDLT over CHOLMOD). Every vector loop runs over the system's fixed chunks: the same bits for
// any thread count. Internal to runtime/integrate.
#include <cstddef>
#include <memory>
#include <vector>

#include "runtime/integrate/implicit_system.h"
#include "runtime/integrate/simulation.h"
#include "runtime/integrate/worker_pool.h"

namespace fmpc::sim {

// What one solve reached.
struct ImplicitSolve {
  int iterations = 0;              // conjugate-gradient iterations (matrix products), or direct solves
  double relative_residual = 0.0;  // |b - A dv| / |b| (0 when b = 0)
  bool converged = true;           // false: stopped at max_iterations above the tolerance
  bool direct_failed = false;      // the factorisation failed (a zero pivot) and the step fell back to the CG
};

class ImplicitSolver {
 public:
  // `held`: held_axes(setup). Reads the setup for its life.
  ImplicitSolver(const SimulationSetup& setup, const std::vector<unsigned char>& held);
  ~ImplicitSolver();
  ImplicitSolver(const ImplicitSolver&) = delete;
  ImplicitSolver& operator=(const ImplicitSolver&) = delete;

  // Direct or ConjugateGradient: the setup's, or Automatic's choice.
  ImplicitMethod method() const { return method_; }

  // Assembles the system at the state (ImplicitSystem::assemble's arguments) and solves it into `dv` (3 per vertex,
  // zero on held axes).
  ImplicitSolve solve(const std::vector<double>& x, const std::vector<double>& v, const std::vector<double>& a,
                      const std::vector<double>& spring_stiffness, double h, WorkerPool& pool,
                      std::vector<double>& dv);

  // The conjugate gradient's starting point, carried from step to step (a checkpoint saves and restores it).
  const std::vector<double>& warm_start() const { return previous_; }
  void set_warm_start(const std::vector<double>& previous) { previous_ = previous; }

 private:
  struct Factorisation;
  ImplicitSolve conjugate_gradient(const std::vector<double>& b, std::vector<double>& x, WorkerPool& pool);
  bool direct(const std::vector<double>& b, std::vector<double>& x, WorkerPool& pool, ImplicitSolve& solve);
  // r = b - A x; returns |r|^2, summed by chunks.
  double residual(const std::vector<double>& b, const std::vector<double>& x, std::vector<double>& r,
                  WorkerPool& pool);
  void invert_diagonal_blocks(WorkerPool& pool);

  const SimulationSetup& setup_;
  ImplicitSystem system_;
  ImplicitMethod method_ = ImplicitMethod::ConjugateGradient;
  double tolerance_ = 1e-10;
  int limit_ = 0;
  std::unique_ptr<Factorisation> factorisation_;
  std::vector<double> rhs_, r_, p_, q_, inverse_diagonal_, previous_;
  std::vector<double> partial_;  // per chunk, the dot products of one pass
};

}  // namespace fmpc::sim
