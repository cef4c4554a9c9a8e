#include <algorithm>
#include <cmath>
#include <sstream>

#include "runtime/integrate/simulation.h"

namespace fmpc::sim {

const char* to_string(Integrator integrator) {
  switch (integrator) {
    case Integrator::ForwardEuler:
      return "forward Euler";
    case Integrator::SemiImplicitEuler:
      return "semi-implicit Euler";
    case Integrator::VelocityVerlet:
      return "velocity Verlet";
    case Integrator::RungeKutta4:
      return "RK4";
    case Integrator::ImplicitEuler:
      return "implicit Euler";
  }
  return "unknown";
}

namespace {

std::string number(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

// The largest tangent stiffness a spring can have: k for the linear law, K1 + 3 K2 Xc^2 (per unit length) for the
// Basafa-Farahmand law, whose slope grows with the strain up to Xc and stays constant beyond.
// With a strain table, k is the largest value the table can give the spring (the step must stay stable there).
double tangent_stiffness_bound(const SimulationSetup& setup, double table_modulus_max, std::size_t spring) {
  const double k = setup.strain_stiffness ? table_modulus_max * setup.strain_stiffness->stiffness_per_modulus[spring]
                                          : setup.springs.stiffness[spring];
  if (setup.law == kernels::SpringLaw::BasafaFarahmand) {
    return k * (1.0 + 3.0 * setup.basafa_k2_over_k1 * setup.basafa_xc * setup.basafa_xc);
  }
  return k;
}

}  // namespace

std::optional<StabilityReport> check_stability(const SimulationSetup& setup, DiagnosticList& diagnostics) {
  if (!validate_setup(setup, diagnostics)) return std::nullopt;
  const SpringNetwork& net = setup.springs;
  const std::size_t n = setup.mass.size();
  std::vector<bool> fixed(n, false);
  for (const auto v : setup.fixed_vertices) fixed[static_cast<std::size_t>(v)] = true;
  StabilityReport report;
  // Rayleigh quotient argument: x^T K x = sum_s k_s (u_s . (x_a - x_b))^2 <= sum_i |x_i|^2 2 sum_j k_ij, so
  // w^2 = x^T K x / x^T M x <= max_i 2 sum_j k_ij / m_i (the bound in DESIGN section 7).
  // The nodal damping gamma0 + gamma1 |x - x0| is bounded with the largest initial displacement; a run that moves
  // further can exceed it, and the NaN/Inf check then stops it.
  double largest_displacement = 0.0;
  for (std::size_t v = 0; v < setup.initial_positions.size() && v < setup.rest_positions.size(); ++v) {
    largest_displacement =
        std::max(largest_displacement, distance(setup.initial_positions[v], setup.rest_positions[v]));
  }
  const double nodal_damping = setup.nodal_damping_gamma0 + setup.nodal_damping_gamma1 * largest_displacement;
  const double table_modulus_max =
      setup.strain_stiffness ? *std::max_element(setup.strain_stiffness->modulus.begin(),
                                                 setup.strain_stiffness->modulus.end())
                             : 0.0;
  double omega_squared_max = 0.0;
  double euler_limit = std::numeric_limits<double>::infinity();
  for (std::size_t v = 0; v < n; ++v) {
    if (fixed[v]) continue;
    double stiffness_sum = 0.0, damping_sum = 0.0;
    for (auto e = net.adjacency_offset[v]; e < net.adjacency_offset[v + 1]; ++e) {
      const auto s = static_cast<std::size_t>(net.adjacency_spring[static_cast<std::size_t>(e)]);
      stiffness_sum += tangent_stiffness_bound(setup, table_modulus_max, s);
      if (!net.damping.empty()) damping_sum += net.damping[s];
    }
    const double omega_squared = 2.0 * stiffness_sum / setup.mass[v];
    if (omega_squared > omega_squared_max) {
      omega_squared_max = omega_squared;
      report.limiting_vertex = static_cast<std::int32_t>(v);
    }
    report.damping_rate_max = std::max(report.damping_rate_max, (2.0 * damping_sum + nodal_damping) / setup.mass[v]);
    // Forward Euler is stable on an underdamped mode only while h <= beta / w^2; use the lowest damping a vertex
    // can see (sum c / m, no factor 2) over the highest frequency bound.
    if (omega_squared > 0.0) {
      euler_limit = std::min(euler_limit, (damping_sum + setup.nodal_damping_gamma0) / setup.mass[v] / omega_squared);
    }
  }
  report.omega_max = std::sqrt(omega_squared_max);
  const double w = report.omega_max;
  const double beta = report.damping_rate_max;
  // rho bounds |lambda| of the test equation's roots lambda = -beta/2 +- sqrt(beta^2/4 - w^2).
  const double rho = beta / 2.0 + std::sqrt(w * w + beta * beta / 4.0);
  SourceRange range;
  switch (setup.integrator) {
    case Integrator::SemiImplicitEuler:
    case Integrator::VelocityVerlet:
      // Symplectic Euler on x'' + beta x' + w^2 x = 0 is stable iff h <= 2 / (beta/2 + sqrt(w^2 + beta^2/4))
      // (Jury criterion on its 2x2 step matrix: trace 2 - beta h - w^2 h^2, determinant 1 - beta h); velocity
      // Verlet has the same limit h w <= 2 without damping and is given the same bound with it.
      report.critical_time_step = rho > 0.0 ? 2.0 / rho : std::numeric_limits<double>::infinity();
      report.limit = "h <= 2 / (beta/2 + sqrt(w^2 + beta^2/4))";
      break;
    case Integrator::RungeKutta4:
      // |h lambda| <= 2.5 lies inside RK4's stability region for every Re(lambda) <= 0 (checked numerically:
      // max |R(z)| = 0.873 on that half circle); the region reaches 2.83 on the imaginary axis.
      report.critical_time_step = rho > 0.0 ? 2.5 / rho : std::numeric_limits<double>::infinity();
      report.limit = "h <= 2.5 / (beta/2 + sqrt(w^2 + beta^2/4))";
      break;
    case Integrator::ForwardEuler:
      // |1 + h lambda| <= 1 for lambda = -beta/2 +- i sqrt(w^2 - beta^2/4) gives h <= beta / w^2 per mode. The
      // per-vertex estimate of beta / w^2 is not a bound for the coupled, prestressed network: a 0.1 m box hanging
      // under gravity (tests/gpu, bench/sim) diverged after about 600 steps at 0.8 x the estimate, on the CPU and
      // the GPU alike, and stayed bounded for 10,000 steps at 0.5 x and below. The stated critical step is
      // therefore half the estimate.
      report.critical_time_step = 0.5 * euler_limit;
      report.limit = "h <= min_i (sum_j c_ij / m_i) / (2 sum_j k_ij / m_i) / 2";
      if (omega_squared_max > 0.0 && !(euler_limit > 0.0) && setup.refuse_unstable_time_step) {
        diagnostics.error(range,
                          "forward Euler is unstable at every time step for undamped springs (|1 + i h w| > 1); "
                          "add damping or use semi-implicit Euler");
        return std::nullopt;
      }
      break;
    case Integrator::ImplicitEuler:
      report.critical_time_step = std::numeric_limits<double>::infinity();
      report.limit = "unconditionally stable";
      break;
  }
  if (!setup.time_step) {
    report.automatic = true;
    double reference = report.critical_time_step;
    if (setup.integrator == Integrator::ImplicitEuler) {
      // Stable at any step; 'auto' takes 10 explicit critical steps, which keeps the numerical damping moderate.
      reference = rho > 0.0 ? 10.0 * 2.0 / rho : std::numeric_limits<double>::infinity();
    }
    if (!std::isfinite(reference) || !(reference > 0.0)) {
      diagnostics.error(range,
                        std::isfinite(reference)
                            ? "no stable time step exists for " + std::string(to_string(setup.integrator)) +
                                  " without damping; add damping or use semi-implicit Euler"
                            : "no time step can be derived (no spring acts on a free vertex); give dt explicitly");
      return std::nullopt;
    }
    report.time_step = setup.stability_margin * reference;
    return report;
  }
  report.time_step = *setup.time_step;
  if (report.time_step > report.critical_time_step) {
    const std::string message = "time step " + number(report.time_step) + " s exceeds the " +
                                to_string(setup.integrator) + " stability limit " + number(report.critical_time_step) +
                                " s (" + report.limit + " with w_max = " + number(w) + " rad/s at vertex " +
                                std::to_string(report.limiting_vertex) + ", beta_max = " + number(beta) +
                                " 1/s); use dt <= " + number(setup.stability_margin * report.critical_time_step) +
                                " s, dt auto, or implicit Euler";
    if (!setup.refuse_unstable_time_step) {
      diagnostics.warning(range, "unstable-time-step", message);
      return report;
    }
    diagnostics.error(range, message);
    return std::nullopt;
  }
  return report;
}

}  // namespace fmpc::sim
