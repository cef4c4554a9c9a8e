#include "runtime/integrate/static_equilibrium.h"

#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <Eigen/SparseCholesky>
#pragma GCC diagnostic pop
#include <cmath>
#include <sstream>

#include "kernels/integrator_math.h"
#include "runtime/integrate/model_tangent.h"

namespace fmpc::sim {

namespace {

struct Loads {
  std::vector<Point3> applied;  // N per vertex: m g + external + a force probe's share
  double scale = 0.0;           // N, the largest |applied| component sum, for the relative tolerance
};

Loads applied_loads(const SimulationSetup& setup) {
  const std::size_t n = setup.rest_positions.size();
  Loads loads;
  loads.applied.assign(n, Point3{0.0, 0.0, 0.0});
  for (std::size_t v = 0; v < n; ++v)
    for (std::size_t i = 0; i < 3; ++i) {
      loads.applied[v][i] = setup.mass[v] * setup.gravity[i];
      if (!setup.external_forces.empty()) loads.applied[v][i] += setup.external_forces[v][i];
    }
  if (setup.probe && setup.probe->mode == ProbeLoad::Mode::Force) {
    const double count = static_cast<double>(setup.probe->vertices.size());
    for (const auto v : setup.probe->vertices)
      for (std::size_t i = 0; i < 3; ++i) loads.applied[static_cast<std::size_t>(v)][i] += setup.probe->target[i] / count;
  }
  double total = 0.0;
  for (const Point3& f : loads.applied) total += std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
  loads.scale = total;
  return loads;
}

// K0 restricted to the free rows, and the full K0 for the right-hand side and the reactions.
Eigen::SparseMatrix<double> free_block(const Eigen::SparseMatrix<double>& K, const std::vector<int>& free_index,
                                       int free_count) {
  std::vector<Eigen::Triplet<double>> entries;
  for (int column = 0; column < K.outerSize(); ++column) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, column); it; ++it) {
      const int row = free_index[static_cast<std::size_t>(it.row())], col = free_index[static_cast<std::size_t>(it.col())];
      if (row >= 0 && col >= 0) entries.emplace_back(row, col, it.value());
    }
  }
  Eigen::SparseMatrix<double> block(free_count, free_count);
  block.setFromTriplets(entries.begin(), entries.end());
  return block;
}

// The linear solution (StaticOptions::linear): K0 u = f_ext at rest, the held axes' u given.
std::optional<StaticResult> linear_solution(const SimulationSetup& setup, const std::vector<unsigned char>& held,
                                            const std::vector<int>& free_index, int free_count, const Loads& loads,
                                            std::vector<Point3> start, DiagnosticList& diagnostics) {
  const std::size_t n = setup.rest_positions.size();
  const Eigen::SparseMatrix<double> K = model_tangent(setup, setup.rest_positions, setup.springs.stiffness).stiffness;
  Eigen::VectorXd u(static_cast<Eigen::Index>(3 * n)), f(static_cast<Eigen::Index>(3 * n));
  for (std::size_t v = 0; v < n; ++v)
    for (std::size_t i = 0; i < 3; ++i) {
      const auto dof = static_cast<Eigen::Index>(3 * v + i);
      u[dof] = kernels::axis_fixed(held[v], static_cast<int>(i)) ? start[v][i] - setup.rest_positions[v][i] : 0.0;
      f[dof] = loads.applied[v][i];
    }
  const Eigen::VectorXd load = f - K * u;
  Eigen::VectorXd rhs(free_count);
  for (std::size_t d = 0; d < 3 * n; ++d)
    if (free_index[d] >= 0) rhs[free_index[d]] = load[static_cast<Eigen::Index>(d)];
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(free_block(K, free_index, free_count));
  const bool singular = solver.info() != Eigen::Success || free_count == 0 ||
                        !(solver.vectorD().cwiseAbs().minCoeff() > 1e-12 * solver.vectorD().cwiseAbs().maxCoeff());
  if (singular) {
    diagnostics.error(setup.source_range, "static equilibrium: the stiffness at rest cannot be factorised (a body "
                                          "without enough held vertices can move freely); fix vertices to hold it");
    return std::nullopt;
  }
  const Eigen::VectorXd solution = solver.solve(rhs);
  for (std::size_t d = 0; d < 3 * n; ++d)
    if (free_index[d] >= 0) u[static_cast<Eigen::Index>(d)] = solution[free_index[d]];
  const Eigen::VectorXd reaction = K * u - f;
  StaticResult result;
  result.iterations = 1;
  result.positions.resize(n);
  result.reactions.assign(n, Point3{0.0, 0.0, 0.0});
  double residual = 0.0;
  for (std::size_t v = 0; v < n; ++v)
    for (std::size_t i = 0; i < 3; ++i) {
      const auto dof = static_cast<Eigen::Index>(3 * v + i);
      result.positions[v][i] = setup.rest_positions[v][i] + u[dof];
      if (free_index[3 * v + i] < 0) result.reactions[v][i] = reaction[dof];
      else residual += reaction[dof] * reaction[dof];
    }
  result.residual = std::sqrt(residual);
  const std::vector<Point3> zero(n, Point3{0.0, 0.0, 0.0});
  result.probe = read_probe(setup, setup.probe ? setup.probe->ramp_time : 0.0, result.positions, zero,
                            setup.springs.stiffness);
  return result;
}

}  // namespace

std::optional<StaticResult> static_equilibrium(const SimulationSetup& setup, const StaticOptions& options,
                                               DiagnosticList& diagnostics) {
  if (!validate_setup(setup, diagnostics)) return std::nullopt;
  const std::size_t n = setup.rest_positions.size();
  const std::vector<unsigned char> held = held_axes(setup);
  std::vector<Point3> x = setup.initial_positions.empty() ? setup.rest_positions : setup.initial_positions;
  double probe_scale = 0.0;
  if (setup.probe && setup.probe->mode == ProbeLoad::Mode::Displacement) {
    for (const auto v : setup.probe->vertices)
      for (std::size_t i = 0; i < 3; ++i) x[static_cast<std::size_t>(v)][i] += setup.probe->target[i];
  }
  // Free degrees of freedom, numbered in vertex order.
  std::vector<int> free_index(3 * n, -1);
  int free_count = 0;
  for (std::size_t v = 0; v < n; ++v)
    for (std::size_t i = 0; i < 3; ++i)
      if (!kernels::axis_fixed(held[v], static_cast<int>(i))) free_index[3 * v + i] = free_count++;
  // Every axis must be held somewhere, or the body translates freely along it (rotations are the factorisation's
  // to find: a tiny pivot below).
  unsigned char held_somewhere = 0;
  for (const unsigned char mask : held) held_somewhere = static_cast<unsigned char>(held_somewhere | mask);
  if (held_somewhere != kernels::kAllAxesFixed && free_count > 0) {
    diagnostics.error(setup.source_range, "static equilibrium: nothing holds the body along every axis, so it has no "
                                          "resting state; fix or hold vertices (fixed, hold) so that x, y and z are "
                                          "each held somewhere");
    return std::nullopt;
  }
  const Loads loads = applied_loads(setup);
  const std::vector<Point3> zero(n, Point3{0.0, 0.0, 0.0});
  std::vector<std::int32_t> all(n);
  for (std::size_t v = 0; v < n; ++v) all[v] = static_cast<std::int32_t>(v);
  const std::vector<double> stiffness =
      setup.strain_stiffness ? std::vector<double>(setup.springs.size(), 0.0) : setup.springs.stiffness;
  // With a strain table the springs' k follows their strain; evaluated at each state (kernels/strain_table_math.h).
  const auto spring_stiffness = [&](const std::vector<Point3>& at) {
    if (!setup.strain_stiffness) return setup.springs.stiffness;
    std::vector<double> k(setup.springs.size());
    const kernels::StrainTableView view = strain_table_view(*setup.strain_stiffness);
    for (std::size_t s = 0; s < k.size(); ++s) {
      const Point3& a = at[static_cast<std::size_t>(setup.springs.first[s])];
      const Point3& b = at[static_cast<std::size_t>(setup.springs.second[s])];
      k[s] = kernels::strain_table_stiffness(view, b[0] - a[0], b[1] - a[1], b[2] - a[2], setup.springs.rest_length[s],
                                             setup.strain_stiffness->stiffness_per_modulus[s]);
    }
    return k;
  };
  const auto residual_of = [&](const std::vector<Point3>& at, Eigen::VectorXd& r) {
    const std::vector<Point3> f = internal_forces(setup, at, zero, spring_stiffness(at), all);
    r.setZero(free_count);
    for (std::size_t v = 0; v < n; ++v)
      for (std::size_t i = 0; i < 3; ++i)
        if (free_index[3 * v + i] >= 0) r[free_index[3 * v + i]] = f[v][i] + loads.applied[v][i];
    return r.allFinite();
  };
  if ((setup.probe && setup.probe->mode == ProbeLoad::Mode::Displacement) || !setup.initial_positions.empty()) {
    // A displacement probe, or held vertices moved from rest (the initial positions), load the tissue through the
    // first residual: its scale is that force.
    Eigen::VectorXd r;
    residual_of(x, r);
    probe_scale = r.norm();
  }
  const double scale = std::max(loads.scale, probe_scale);
  if (options.linear) return linear_solution(setup, held, free_index, free_count, loads, std::move(x), diagnostics);
  StaticResult result;
  Eigen::VectorXd r;
  if (!residual_of(x, r)) {
    diagnostics.error(setup.source_range, "static equilibrium: the starting state gives non-finite forces");
    return std::nullopt;
  }
  for (int iteration = 0; iteration < options.max_iterations && !(r.norm() <= options.tolerance * scale); ++iteration) {
    const ModelTangent tangent = model_tangent(setup, x, spring_stiffness(x));
    Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(free_block(tangent.stiffness, free_index, free_count));
    // A pivot 1e-12 below the largest: a rigid motion left free (e.g. a rotation about a single fixed vertex).
    const bool singular = solver.info() != Eigen::Success || free_count == 0 ||
                          !(solver.vectorD().cwiseAbs().minCoeff() > 1e-12 * solver.vectorD().cwiseAbs().maxCoeff());
    const Eigen::VectorXd step = singular ? Eigen::VectorXd() : Eigen::VectorXd(solver.solve(r));
    if (singular || !step.allFinite()) {
      diagnostics.error(setup.source_range,
                        "static equilibrium: the stiffness cannot be factorised at Newton step " +
                            std::to_string(iteration + 1) +
                            " (a body without enough fixed vertices can move freely); fix vertices to hold it");
      return std::nullopt;
    }
    // x += alpha K^-1 r, halving alpha until the residual decreases (up to 20 times).
    const double before = r.norm();
    double alpha = 1.0;
    std::vector<Point3> trial;
    Eigen::VectorXd trial_r;
    for (int halving = 0; halving < 20; ++halving, alpha /= 2.0) {
      trial = x;
      for (std::size_t v = 0; v < n; ++v)
        for (std::size_t i = 0; i < 3; ++i)
          if (free_index[3 * v + i] >= 0) trial[v][i] += alpha * step[free_index[3 * v + i]];
      if (residual_of(trial, trial_r) && trial_r.norm() < before) break;
    }
    x = std::move(trial);
    r = std::move(trial_r);
    result.iterations = iteration + 1;
  }
  result.residual = r.norm();
  if (!std::isfinite(result.residual)) {
    diagnostics.error(setup.source_range, "static equilibrium: the state became non-finite");
    return std::nullopt;
  }
  if (!(result.residual <= options.tolerance * scale)) {
    std::ostringstream message;
    message << "static equilibrium: Newton's method stopped after " << result.iterations << " iterations with residual "
            << result.residual << " N, above " << options.tolerance << " x the load (" << scale
            << " N); the load may exceed what the model can carry (buckling, inversion)";
    diagnostics.error(setup.source_range, message.str());
    return std::nullopt;
  }
  const std::vector<Point3> f = internal_forces(setup, x, zero, spring_stiffness(x), all);
  result.reactions.assign(n, Point3{0.0, 0.0, 0.0});
  for (std::size_t v = 0; v < n; ++v)
    for (std::size_t i = 0; i < 3; ++i)
      if (free_index[3 * v + i] < 0) result.reactions[v][i] = -(f[v][i] + loads.applied[v][i]);
  result.probe = read_probe(setup, setup.probe ? setup.probe->ramp_time : 0.0, x, zero, spring_stiffness(x));
  result.positions = std::move(x);
  return result;
}

}  // namespace fmpc::sim
