#pragma once
// One implicit Euler step's linear solve on the CPU (implicit_system.h's system), by the method the setup asks for
// (ImplicitSolverOptions): a sparse direct factorisation (Eigen's SimplicialLDLT with AMD ordering, its symbolic
// analysis done once for the fixed pattern, the numeric factorisation every step, refined with further solves while
// the residual is above the tolerance) or a preconditioned conjugate gradient (block Jacobi: each vertex's 3 x 3
// diagonal block inverted), started from the previous step's solution. Automatic takes whichever costs less by an
// estimate and a trial (automatic_method; docs/simulator.md gives the measurements behind the rule and the choice of
// SimplicialLDLT over CHOLMOD). Every vector loop runs over the system's fixed chunks: the same bits for
// any thread count. Internal to runtime/integrate.
#include <cstddef>
#include <memory>
#include <vector>

#include "runtime/integrate/implicit_system.h"
#include "runtime/integrate/simulation.h"
#include "runtime/integrate/worker_pool.h"

namespace fmpc::sim {

// What one solve reached (over its rounds, with a linear part).
struct ImplicitSolve {
  int iterations = 0;              // conjugate-gradient iterations (matrix products), or direct solves, all rounds'
  double relative_residual = 0.0;  // |b - A dv| / |b| (0 when b = 0), the last round's
  bool converged = true;           // false: the last round stopped at max_iterations above the tolerance
  bool direct_failed = false;      // the factorisation failed (a zero pivot) and the step fell back to the CG
  int rounds = 1;                  // solves with the linear part's values (ImplicitLinearPart)
  bool settled = true;             // false: the linear part still changed after the last round allowed
};

// A part of the system that depends on its solution, which a caller adds (cpu_engine.cpp: the tools' contact, an
// active set): per vertex a symmetric 3 x 3 block (6 values, kernels::symmetric_index's order) added to the vertex's
// diagonal block and 3 values added to the right-hand side, on the free axes only. The solver solves with the part,
// asks whether the solution changes it, and if so solves again with its new values from the last solution.
class ImplicitLinearPart {
 public:
  virtual ~ImplicitLinearPart() = default;
  // The part's values for the next solve into `blocks` (6 per vertex) and `rhs` (3 per vertex), both zeroed.
  virtual void linearise(std::vector<double>& blocks, std::vector<double>& rhs) = 0;
  // Whether the solution dv (3 per vertex) changes the part (the next linearise gives the new values).
  virtual bool changed_by(const std::vector<double>& dv) = 0;
};

// How Automatic chose (ImplicitSolver::automatic_method), for the measurements behind it.
struct ImplicitChoice {
  double direct_step = 0.0;   // operations of one direct step (implicit_cost.h)
  double cg_iteration = 0.0;  // operations of one CG iteration
  int budget = 0;             // the CG iterations the trial was allowed: a direct step's cost, at most the cap
  int trial_iterations = 0;   // what the trial took (at the budget: it did not converge within it)
};

// A factorisation's operation against a CG iteration's (the CG's are streaming passes over the blocks, the
// factorisation's scattered updates of the factor's columns): measured in docs/simulator.md ("Choosing the solver").
inline constexpr double kDirectOperationWeight = 2.5;

class ImplicitSolver {
 public:
  // `held`: held_axes(setup); `h`: the run's step (s), for Automatic's trial; `pool`: its workers. Reads the setup for
  // its life.
  ImplicitSolver(const SimulationSetup& setup, const std::vector<unsigned char>& held, double h, WorkerPool& pool);
  ~ImplicitSolver();
  ImplicitSolver(const ImplicitSolver&) = delete;
  ImplicitSolver& operator=(const ImplicitSolver&) = delete;

  // Direct or ConjugateGradient: the setup's, or Automatic's choice.
  ImplicitMethod method() const { return method_; }
  // Automatic's estimates and trial (zeros for a method the setup named).
  const ImplicitChoice& choice() const { return choice_; }

  // Assembles the system at the state (ImplicitSystem::assemble's arguments) and solves it into `dv` (3 per vertex,
  // zero on held axes). With a linear `part`, solves until the part stays (each round from the last round's dv), at
  // most `most_rounds` times. `linearisations`: the elements' linearisations at x, where the force pass kept them.
  ImplicitSolve solve(const std::vector<double>& x, const std::vector<double>& v, const std::vector<double>& a,
                      const std::vector<double>& spring_stiffness, double h, WorkerPool& pool,
                      std::vector<double>& dv, ImplicitLinearPart* part = nullptr, int most_rounds = 1,
                      const ElementLinearisations* linearisations = nullptr);

  // The conjugate gradient's starting point, carried from step to step (a checkpoint saves and restores it).
  const std::vector<double>& warm_start() const { return previous_; }
  void set_warm_start(const std::vector<double>& previous) { previous_ = previous; }

 private:
  struct Factorisation;
  ImplicitMethod automatic_method(double h, WorkerPool& pool);
  // One solve of the assembled system with rhs_; `first`: the step's first round (else dv holds the last round's).
  ImplicitSolve solve_assembled(std::vector<double>& dv, bool first, WorkerPool& pool, bool& at_rest);
  // The assembled diagonal blocks and right-hand side with the part's values added on the free axes.
  void add_part(ImplicitLinearPart& part);
  // From x (the warm start); b2 = |b|^2 (squared_norm), which the caller has already summed.
  ImplicitSolve conjugate_gradient(const std::vector<double>& b, double b2, std::vector<double>& x, WorkerPool& pool);
  bool direct(const std::vector<double>& b, std::vector<double>& x, WorkerPool& pool, ImplicitSolve& solve);
  // |b|^2, summed by chunks.
  double squared_norm(const std::vector<double>& b, WorkerPool& pool);
  // r = b - A x; returns |r|^2, summed by chunks.
  double residual(const std::vector<double>& b, const std::vector<double>& x, std::vector<double>& r,
                  WorkerPool& pool);
  void invert_diagonal_blocks(WorkerPool& pool);

  const SimulationSetup& setup_;
  ImplicitSystem system_;
  ImplicitMethod method_ = ImplicitMethod::ConjugateGradient;
  double tolerance_ = 1e-10;
  int limit_ = 0;
  ImplicitChoice choice_;
  std::unique_ptr<Factorisation> factorisation_;
  std::vector<double> rhs_, r_, p_, q_, inverse_diagonal_, previous_;
  std::vector<double> partial_;  // per chunk, the dot products of one pass
  // With a linear part: the diagonal blocks (9 per vertex) and right-hand side as assembled, and the part's values.
  std::vector<double> assembled_diagonal_, assembled_rhs_, part_blocks_, part_rhs_;
};

}  // namespace fmpc::sim
