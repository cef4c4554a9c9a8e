// GCC 12 at -O2 reports a null dereference inside Eigen's SparseCompressedBase after inlining (Eigen's code, not
// ours); the warning is silenced for Eigen's headers only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <Eigen/SparseCholesky>
#pragma GCC diagnostic pop

#include "runtime/integrate/implicit_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "kernels/implicit_math.h"
#include "runtime/integrate/implicit_cost.h"

namespace fmpc::sim {

// The system permuted once by an AMD ordering (P A P^T) and stored as its upper triangle in Eigen's compressed
// columns, with where each entry's value lives among the system's blocks, and its LDL^T factorisation (symbolic
// analysis once, at the first step). Permuting here rather than through SimplicialLDLT's own ordering lets Eigen
// factorise the stored matrix in place: with an ordering it copies the permuted matrix at every factorisation.
struct ImplicitSolver::Factorisation {
  Eigen::SparseMatrix<double> upper;
  std::vector<std::size_t> source;  // per stored entry: its index in the system's block values
  std::vector<int> permuted;        // per unknown i: P(i), its row in the permuted system
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Upper, Eigen::NaturalOrdering<int>> ldlt;
  Eigen::VectorXd b, x;  // in the permuted order
  bool analysed = false;
};

namespace {

// The sum of the chunks' partial values in chunk order (`stride` values per chunk, `which` of them).
double sum_partials(const std::vector<double>& partial, std::size_t chunks, std::size_t stride, std::size_t which) {
  double sum = 0.0;
  for (std::size_t c = 0; c < chunks; ++c) sum += partial[stride * c + which];
  return sum;
}

}  // namespace

ImplicitSolver::ImplicitSolver(const SimulationSetup& setup, const std::vector<unsigned char>& held, double h,
                               WorkerPool& pool)
    : setup_(setup), system_(setup, held) {
  tolerance_ = setup.implicit.tolerance;
  limit_ = implicit_iteration_limit(setup);
  method_ = setup.implicit.method;
  const std::size_t dofs = system_.dofs();
  rhs_.assign(dofs, 0.0);
  r_.assign(dofs, 0.0);
  p_.assign(dofs, 0.0);
  q_.assign(dofs, 0.0);
  previous_.assign(dofs, 0.0);
  inverse_diagonal_.assign(3 * dofs, 0.0);
  partial_.assign(3 * system_.chunks(), 0.0);
  if (method_ == ImplicitMethod::Automatic) method_ = automatic_method(h, pool);
  if (method_ == ImplicitMethod::Direct) {
    factorisation_ = std::make_unique<Factorisation>();
    Factorisation& f = *factorisation_;
    const auto size = static_cast<Eigen::Index>(dofs);
    // Every entry of the pattern (both triangles); its value is its source index + 1 until it is read.
    std::vector<Eigen::Triplet<double>> entries;
    for (std::size_t i = 0; i < system_.vertices(); ++i)
      for (std::size_t k = system_.row_offset(i); k < system_.row_offset(i + 1); ++k) {
        const auto j = static_cast<std::size_t>(system_.column(k));
        for (std::size_t r = 0; r < 3; ++r)
          for (std::size_t c = 0; c < 3; ++c)
            entries.emplace_back(static_cast<int>(3 * i + r), static_cast<int>(3 * j + c),
                                 static_cast<double>(9 * k + 3 * r + c + 1));
      }
    Eigen::SparseMatrix<double> full(size, size);
    full.setFromTriplets(entries.begin(), entries.end());
    // Eigen's orderings give the inverse permutation (SimplicialCholeskyBase::ordering does the same).
    Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> inverse;
    Eigen::AMDOrdering<int>()(full, inverse);
    const Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> permutation = inverse.inverse();
    f.permuted.assign(permutation.indices().data(), permutation.indices().data() + dofs);
    std::vector<Eigen::Triplet<double>> upper;
    for (const Eigen::Triplet<double>& entry : entries) {
      const int row = f.permuted[static_cast<std::size_t>(entry.row())];
      const int column = f.permuted[static_cast<std::size_t>(entry.col())];
      if (row <= column) upper.emplace_back(row, column, entry.value());
    }
    f.upper.resize(size, size);
    f.upper.setFromTriplets(upper.begin(), upper.end());
    f.upper.makeCompressed();
    f.source.resize(static_cast<std::size_t>(f.upper.nonZeros()));
    for (std::size_t k = 0; k < f.source.size(); ++k)
      f.source[k] = static_cast<std::size_t>(f.upper.valuePtr()[k]) - 1;
    f.b.resize(size);
    f.x.resize(size);
  }
}

ImplicitSolver::~ImplicitSolver() = default;

// Automatic's choice (docs/simulator.md, "Choosing the solver"): the CG where it reaches the tolerance, from zero, on
// the run's own matrix at its start within the iterations that cost what one direct step costs (implicit_cost.h:
// the factorisation's and one solve's operations, weighted by kDirectOperationWeight against the CG's); else the
// direct solver. The trial's right-hand side is a uniform acceleration along gravity (or z without it) on the free
// axes, h M a: the smooth load that CG converges on slowest. It depends on the setup and the step alone (the same
// choice for any thread count and on a replay), and costs at most about one direct step.
ImplicitMethod ImplicitSolver::automatic_method(double h, WorkerPool& pool) {
  const ImplicitCost cost = implicit_cost(system_);
  choice_.direct_step = cost.direct_step;
  choice_.cg_iteration = cost.cg_iteration;
  const double budget = kDirectOperationWeight * cost.direct_step / cost.cg_iteration;
  choice_.budget = static_cast<int>(std::min<double>(limit_, std::ceil(budget)));
  const std::size_t n = system_.vertices();
  std::vector<double> x(3 * n), v(3 * n, 0.0), a(3 * n, 0.0);
  const double g = std::sqrt(setup_.gravity[0] * setup_.gravity[0] + setup_.gravity[1] * setup_.gravity[1] +
                             setup_.gravity[2] * setup_.gravity[2]);
  const Point3 along = g > 0.0 ? Point3{setup_.gravity[0] / g, setup_.gravity[1] / g, setup_.gravity[2] / g}
                               : Point3{0.0, 0.0, 1.0};
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t axis = 0; axis < 3; ++axis) {
      x[3 * i + axis] = start_position(setup_, i)[axis];
      if (!system_.dof_held(3 * i + axis)) a[3 * i + axis] = along[axis];
    }
  system_.assemble(x, v, a, setup_.springs.stiffness, h, pool, rhs_);
  std::vector<double> dv(system_.dofs(), 0.0);
  const int limit = limit_;
  limit_ = choice_.budget;
  const ImplicitSolve trial = conjugate_gradient(rhs_, squared_norm(rhs_, pool), dv, pool);
  limit_ = limit;
  choice_.trial_iterations = trial.iterations;
  return trial.converged ? ImplicitMethod::ConjugateGradient : ImplicitMethod::Direct;
}

ImplicitSolve ImplicitSolver::solve(const std::vector<double>& x, const std::vector<double>& v,
                                    const std::vector<double>& a, const std::vector<double>& spring_stiffness,
                                    double h, WorkerPool& pool, std::vector<double>& dv, ImplicitLinearPart* part,
                                    int most_rounds, const ElementLinearisations* linearisations) {
  system_.assemble(x, v, a, spring_stiffness, h, pool, rhs_, linearisations);
  dv.assign(system_.dofs(), 0.0);
  if (part != nullptr) {
    assembled_rhs_ = rhs_;
    assembled_diagonal_.resize(9 * system_.vertices());
    for (std::size_t i = 0; i < system_.vertices(); ++i) {
      const double* block = system_.value(system_.diagonal_block(i));
      std::copy(block, block + 9, &assembled_diagonal_[9 * i]);
    }
  }
  ImplicitSolve total;
  for (int round = 1;; ++round) {
    if (part != nullptr) add_part(*part);
    bool at_rest = false;
    const ImplicitSolve solve = solve_assembled(dv, round == 1, pool, at_rest);
    total.iterations += solve.iterations;
    total.relative_residual = solve.relative_residual;
    total.converged = solve.converged;
    total.direct_failed = total.direct_failed || solve.direct_failed;
    total.rounds = round;
    if (at_rest || part == nullptr || !part->changed_by(dv)) break;
    if (round >= most_rounds) {
      total.settled = false;
      break;
    }
  }
  return total;
}

void ImplicitSolver::add_part(ImplicitLinearPart& part) {
  const std::size_t n = system_.vertices();
  part_blocks_.assign(6 * n, 0.0);
  part_rhs_.assign(3 * n, 0.0);
  part.linearise(part_blocks_, part_rhs_);
  rhs_ = assembled_rhs_;
  for (std::size_t i = 0; i < n; ++i) {
    double* block = system_.mutable_value(system_.diagonal_block(i));
    std::copy(&assembled_diagonal_[9 * i], &assembled_diagonal_[9 * i] + 9, block);
    for (int r = 0; r < 3; ++r) {
      if (system_.dof_held(3 * i + static_cast<std::size_t>(r))) continue;
      rhs_[3 * i + static_cast<std::size_t>(r)] += part_rhs_[3 * i + static_cast<std::size_t>(r)];
      for (int c = 0; c < 3; ++c)
        if (!system_.dof_held(3 * i + static_cast<std::size_t>(c)))
          block[3 * r + c] += part_blocks_[6 * i + static_cast<std::size_t>(kernels::symmetric_index(r, c))];
    }
  }
}

ImplicitSolve ImplicitSolver::solve_assembled(std::vector<double>& dv, bool first, WorkerPool& pool, bool& at_rest) {
  const double b2 = squared_norm(rhs_, pool);
  ImplicitSolve solve;
  // A right-hand side this small means the system is at rest to double precision: a solver on denormals would only
  // report a spurious failure.
  at_rest = std::sqrt(b2) < 1e-150;
  if (at_rest) {
    std::fill(dv.begin(), dv.end(), 0.0);
    std::fill(previous_.begin(), previous_.end(), 0.0);
    return solve;
  }
  if (method_ == ImplicitMethod::Direct && direct(rhs_, dv, pool, solve)) return solve;
  const bool fell_back = method_ == ImplicitMethod::Direct;
  // A later round starts from the last round's dv.
  if (first) dv = setup_.implicit.warm_start && !fell_back ? previous_ : std::vector<double>(system_.dofs(), 0.0);
  solve = conjugate_gradient(rhs_, b2, dv, pool);
  solve.direct_failed = fell_back;
  previous_ = dv;
  return solve;
}

double ImplicitSolver::squared_norm(const std::vector<double>& b, WorkerPool& pool) {
  pool.run(
      system_.chunks(),
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t chunk = begin; chunk < end; ++chunk) {
          double sum = 0.0;
          const std::size_t last = std::min(system_.dofs(), 3 * (chunk + 1) * kSystemChunkVertices);
          for (std::size_t d = 3 * chunk * kSystemChunkVertices; d < last; ++d) sum += b[d] * b[d];
          partial_[chunk] = sum;
        }
      },
      kSystemChunksPerThread);
  return sum_partials(partial_, system_.chunks(), 1, 0);
}

double ImplicitSolver::residual(const std::vector<double>& b, const std::vector<double>& x, std::vector<double>& r,
                                WorkerPool& pool) {
  pool.run(
      system_.chunks(),
      [&](std::size_t begin, std::size_t end) {
        system_.multiply_chunks(x.data(), r.data(), begin, end);
        for (std::size_t chunk = begin; chunk < end; ++chunk) {
          double rr = 0.0;
          const std::size_t first = 3 * chunk * kSystemChunkVertices;
          const std::size_t last = std::min(system_.dofs(), 3 * (chunk + 1) * kSystemChunkVertices);
          for (std::size_t d = first; d < last; ++d) {
            r[d] = b[d] - r[d];
            rr += r[d] * r[d];
          }
          partial_[chunk] = rr;
        }
      },
      kSystemChunksPerThread);
  return sum_partials(partial_, system_.chunks(), 1, 0);
}

bool ImplicitSolver::direct(const std::vector<double>& b, std::vector<double>& x, WorkerPool& pool,
                            ImplicitSolve& solve) {
  Factorisation& f = *factorisation_;
  double* values = f.upper.valuePtr();
  const double* blocks = system_.value(0);
  for (std::size_t k = 0; k < f.source.size(); ++k) values[k] = blocks[f.source[k]];
  if (!f.analysed) {
    f.ldlt.analyzePattern(f.upper);
    f.analysed = true;
  }
  f.ldlt.factorize(f.upper);
  if (f.ldlt.info() != Eigen::Success) return false;
  const std::size_t dofs = system_.dofs();
  const double b2 = squared_norm(b, pool);
  const double threshold = std::max(tolerance_ * tolerance_ * b2, std::numeric_limits<double>::min());
  // x += A^-1 r through the permuted factorisation (x = 0 at the start, r = b).
  const auto correct = [&](const std::vector<double>& r, bool first) {
    for (std::size_t d = 0; d < dofs; ++d) f.b[f.permuted[d]] = r[d];
    f.x = f.ldlt.solve(f.b);
    for (std::size_t d = 0; d < dofs; ++d) x[d] = (first ? 0.0 : x[d]) + f.x[f.permuted[d]];
  };
  correct(b, true);
  solve.iterations = 1;
  double r2 = residual(b, x, r_, pool);
  // Iterative refinement: each further solve corrects by the factorisation's answer to the residual.
  while (!(r2 < threshold) && solve.iterations < limit_) {
    correct(r_, false);
    ++solve.iterations;
    r2 = residual(b, x, r_, pool);
  }
  for (std::size_t d = 0; d < dofs; ++d)
    if (system_.dof_held(d)) x[d] = 0.0;
  solve.relative_residual = std::sqrt(r2 / b2);
  solve.converged = r2 < threshold;
  return true;
}

void ImplicitSolver::invert_diagonal_blocks(WorkerPool& pool) {
  pool.run(
      system_.chunks(),
      [&](std::size_t begin, std::size_t end) {
        const std::size_t last = std::min(system_.vertices(), end * kSystemChunkVertices);
        for (std::size_t i = begin * kSystemChunkVertices; i < last; ++i) {
          const double* m = system_.value(system_.diagonal_block(i));
          double* inverse = &inverse_diagonal_[9 * i];
          // The adjugate over the determinant; the block is symmetric positive definite (a mass plus tangents).
          const double c00 = m[4] * m[8] - m[5] * m[7], c01 = m[5] * m[6] - m[3] * m[8], c02 = m[3] * m[7] - m[4] * m[6];
          const double determinant = m[0] * c00 + m[1] * c01 + m[2] * c02;
          const double s = 1.0 / determinant;
          inverse[0] = s * c00;
          inverse[1] = s * (m[2] * m[7] - m[1] * m[8]);
          inverse[2] = s * (m[1] * m[5] - m[2] * m[4]);
          inverse[3] = s * c01;
          inverse[4] = s * (m[0] * m[8] - m[2] * m[6]);
          inverse[5] = s * (m[2] * m[3] - m[0] * m[5]);
          inverse[6] = s * c02;
          inverse[7] = s * (m[1] * m[6] - m[0] * m[7]);
          inverse[8] = s * (m[0] * m[4] - m[1] * m[3]);
        }
      },
      kSystemChunksPerThread);
}

// Eigen's ConjugateGradient with its stopping rule (|r|^2 < tol^2 |b|^2, r = b - A x the true residual's recurrence),
// preconditioned by the inverse diagonal blocks, from x as given (the warm start; restarted from zero where that
// starts further from b than zero does). Three chunked passes per iteration: q = A p with p.q; x, r and the dot
// products |r|^2 and r.z (z = P r, not stored); p = P r + beta p.
ImplicitSolve ImplicitSolver::conjugate_gradient(const std::vector<double>& b, double b2, std::vector<double>& x,
                                                 WorkerPool& pool) {
  const std::size_t chunks = system_.chunks(), dofs = system_.dofs();
  const auto dof_range = [&](std::size_t chunk) {
    return std::pair<std::size_t, std::size_t>{3 * chunk * kSystemChunkVertices,
                                               std::min(dofs, 3 * (chunk + 1) * kSystemChunkVertices)};
  };
  const double threshold = std::max(tolerance_ * tolerance_ * b2, std::numeric_limits<double>::min());
  invert_diagonal_blocks(pool);
  double r2 = residual(b, x, r_, pool);
  if (r2 > b2) {
    std::fill(x.begin(), x.end(), 0.0);
    r_ = b;
    r2 = b2;
  }
  ImplicitSolve solve;
  const auto precondition = [&](std::size_t vertex, double z[3]) {
    const double* inverse = &inverse_diagonal_[9 * vertex];
    const double* r = &r_[3 * vertex];
    for (std::size_t i = 0; i < 3; ++i) z[i] = inverse[3 * i] * r[0] + inverse[3 * i + 1] * r[1] + inverse[3 * i + 2] * r[2];
  };
  double rz = 0.0;
  if (!(r2 < threshold)) {
    pool.run(
        chunks,
        [&](std::size_t begin, std::size_t end) {
          for (std::size_t chunk = begin; chunk < end; ++chunk) {
            const auto [first, last] = dof_range(chunk);
            double sum = 0.0;
            for (std::size_t i = first / 3; i < last / 3; ++i) {
              double z[3];
              precondition(i, z);
              for (std::size_t axis = 0; axis < 3; ++axis) {
                p_[3 * i + axis] = z[axis];
                sum += r_[3 * i + axis] * z[axis];
              }
            }
            partial_[chunk] = sum;
          }
        },
        kSystemChunksPerThread);
    rz = sum_partials(partial_, chunks, 1, 0);
  }
  while (!(r2 < threshold) && solve.iterations < limit_) {
    pool.run(
        chunks,
        [&](std::size_t begin, std::size_t end) {
          system_.multiply_chunks(p_.data(), q_.data(), begin, end);
          for (std::size_t chunk = begin; chunk < end; ++chunk) {
            const auto [first, last] = dof_range(chunk);
            double sum = 0.0;
            for (std::size_t d = first; d < last; ++d) sum += p_[d] * q_[d];
            partial_[chunk] = sum;
          }
        },
        kSystemChunksPerThread);
    const double alpha = rz / sum_partials(partial_, chunks, 1, 0);
    pool.run(
        chunks,
        [&](std::size_t begin, std::size_t end) {
          for (std::size_t chunk = begin; chunk < end; ++chunk) {
            const auto [first, last] = dof_range(chunk);
            double rr = 0.0, sum = 0.0;
            for (std::size_t d = first; d < last; ++d) {
              x[d] += alpha * p_[d];
              r_[d] -= alpha * q_[d];
              rr += r_[d] * r_[d];
            }
            for (std::size_t i = first / 3; i < last / 3; ++i) {
              double z[3];
              precondition(i, z);
              sum += r_[3 * i] * z[0] + r_[3 * i + 1] * z[1] + r_[3 * i + 2] * z[2];
            }
            partial_[2 * chunk] = rr;
            partial_[2 * chunk + 1] = sum;
          }
        },
        kSystemChunksPerThread);
    ++solve.iterations;
    r2 = sum_partials(partial_, chunks, 2, 0);
    if (r2 < threshold) break;
    const double rz_next = sum_partials(partial_, chunks, 2, 1);
    const double beta = rz_next / rz;
    rz = rz_next;
    pool.run(
        chunks,
        [&](std::size_t begin, std::size_t end) {
          for (std::size_t chunk = begin; chunk < end; ++chunk) {
            const auto [first, last] = dof_range(chunk);
            for (std::size_t i = first / 3; i < last / 3; ++i) {
              double z[3];
              precondition(i, z);
              for (std::size_t axis = 0; axis < 3; ++axis) p_[3 * i + axis] = z[axis] + beta * p_[3 * i + axis];
            }
          }
        },
        kSystemChunksPerThread);
  }
  solve.relative_residual = std::sqrt(r2 / b2);
  solve.converged = r2 < threshold;
  return solve;
}

}  // namespace fmpc::sim
