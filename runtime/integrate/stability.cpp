#include <algorithm>
#include <cmath>
#include <sstream>

#include "kernels/element_laws.h"
#include "kernels/integrator_math.h"
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
// Basafa-Farahmand law, whose slope grows with the strain up to Xc and stays constant beyond. The transverse
// stiffness T / l of a stretched spring is below k (T / l = k (l - l0) / l). With a strain table, k is the largest
// value the table can give the spring (the step must stay stable there).
double tangent_stiffness_bound(const SimulationSetup& setup, double table_modulus_max, std::size_t spring) {
  const double k = setup.strain_stiffness ? table_modulus_max * setup.strain_stiffness->stiffness_per_modulus[spring]
                                          : setup.springs.stiffness[spring];
  if (setup.law == kernels::SpringLaw::BasafaFarahmand) {
    return k * (1.0 + 3.0 * setup.basafa_k2_over_k1 * setup.basafa_xc * setup.basafa_xc);
  }
  return k;
}

// How far a vertex may move from rest before the nodal damping gamma1 |x - x0| exceeds what the step was chosen
// for: the largest of the initial displacement and the mesh's extent plus the probe's target (a vertex that moves
// further stops the run with an error naming it; the bound is never silently left).
double assumed_displacement(const SimulationSetup& setup) {
  double initial = 0.0;
  for (std::size_t v = 0; v < setup.initial_positions.size() && v < setup.rest_positions.size(); ++v)
    initial = std::max(initial, distance(setup.initial_positions[v], setup.rest_positions[v]));
  Point3 lo = setup.rest_positions.empty() ? Point3{0.0, 0.0, 0.0} : setup.rest_positions.front(), hi = lo;
  for (const Point3& p : setup.rest_positions)
    for (std::size_t i = 0; i < 3; ++i) {
      lo[i] = std::min(lo[i], p[i]);
      hi[i] = std::max(hi[i], p[i]);
    }
  double probe = 0.0;
  if (setup.probe && setup.probe->mode == ProbeLoad::Mode::Displacement)
    probe =
        std::sqrt(setup.probe->target[0] * setup.probe->target[0] + setup.probe->target[1] * setup.probe->target[1] +
                  setup.probe->target[2] * setup.probe->target[2]);
  return std::max(initial, distance(lo, hi) + probe);
}

}  // namespace

VertexBounds vertex_bounds(const SimulationSetup& setup) {
  const SpringNetwork& net = setup.springs;
  const std::size_t n = setup.mass.size();
  const double table_modulus_max =
      setup.strain_stiffness ? *std::max_element(setup.strain_stiffness->modulus.begin(),
                                                 setup.strain_stiffness->modulus.end())
                             : 0.0;
  VertexBounds bounds;
  bounds.stiffness.assign(n, 0.0);
  bounds.damping.assign(n, 0.0);
  for (std::size_t s = 0; s < net.size(); ++s) {
    const double k = tangent_stiffness_bound(setup, table_modulus_max, s);
    const double c = net.damping.empty() ? 0.0 : net.damping[s];
    for (const auto v : {net.first[s], net.second[s]}) {
      bounds.stiffness[static_cast<std::size_t>(v)] += 2.0 * k;
      bounds.damping[static_cast<std::size_t>(v)] += 2.0 * c;
    }
    if (k > 0.0) bounds.spring_ratio_min = std::min(bounds.spring_ratio_min, c / k);
  }
  // Each element term's bound at the largest modulus the run can give it (a strain table's largest where its law
  // reads one), its damping beta_e times that.
  const kernels::StrainTableView table = setup.strain_stiffness ? strain_table_view(*setup.strain_stiffness)
                                                                : kernels::StrainTableView{nullptr, nullptr, 0};
  for (std::size_t term = 0; term < setup.elements.terms.size(); ++term) {
    const kernels::ElementTermView<double> view = element_term_view(setup.elements, term, &table);
    const ElementGeometry& geometry = setup.elements.geometry;
    kernels::visit_element_term(view.element, view.law, [&](auto kind, auto element_law) {
      using Element = decltype(kind);
      using Law = decltype(element_law);
      constexpr auto N = static_cast<std::size_t>(Element::kNodes);
      for (std::size_t e = 0; e < geometry.size(); ++e) {
        const double bound = Element::template stiffness_bound<Law>(view, static_cast<int>(e));
        const double beta = view.stiffness_damping[e];
        for (std::size_t a = 0; a < N; ++a) {
          const auto v = static_cast<std::size_t>(geometry.nodes[N * e + a]);
          bounds.stiffness[v] += bound;
          bounds.damping[v] += beta * bound;
        }
        bounds.element_ratio_min = std::min(bounds.element_ratio_min, beta);
      }
    });
  }
  return bounds;
}

std::optional<StabilityReport> check_stability(const SimulationSetup& setup, DiagnosticList& diagnostics) {
  if (!validate_setup(setup, diagnostics)) return std::nullopt;
  const std::size_t n = setup.mass.size();
  // Vertices held along every axis take no part in the bounds; a vertex held along some axes still vibrates along
  // the others (its bound is kept, which is conservative).
  const std::vector<unsigned char> held = held_axes(setup);
  StabilityReport report;
  if (setup.nodal_damping_gamma1 > 0.0) report.assumed_displacement_max = assumed_displacement(setup);
  const double nodal_damping =
      setup.nodal_damping_gamma0 +
      (setup.nodal_damping_gamma1 > 0.0 ? setup.nodal_damping_gamma1 * report.assumed_displacement_max : 0.0);
  // Per-vertex stiffness and damping bounds (x^T K x <= sum_i s_i |x_i|^2, the same for C), with the tools' contact
  // stiffness on the vertices they can touch (a diagonal term k_c n n^T <= k_c I).
  VertexBounds bounds = vertex_bounds(setup);
  std::vector<double>& stiffness_sum = bounds.stiffness;
  std::vector<double>& damping_sum = bounds.damping;
  if (!setup.tools.empty()) {
    // And the contact's damping on those vertices (rigid_tools.h's contact_damping, from the same bound).
    const std::vector<unsigned char> surface = surface_vertices(setup);
    for (std::size_t v = 0; v < n; ++v) {
      if (!surface[v]) continue;
      if (setup.contact_damping_ratio > 0.0)
        damping_sum[v] += contact_damping_coefficient(setup.contact_damping_ratio,
                                                      setup.contact_stiffness_ratio * stiffness_sum[v], setup.mass[v]);
      stiffness_sum[v] *= 1.0 + setup.contact_stiffness_ratio;
    }
  }
  const double spring_ratio_min = bounds.spring_ratio_min;
  const double element_ratio_min = bounds.element_ratio_min;
  double omega_squared_max = 0.0, mass_damping_min = std::numeric_limits<double>::infinity();
  for (std::size_t v = 0; v < n; ++v) {
    if (held[v] == kernels::kAllAxesFixed) continue;
    const double omega_squared = stiffness_sum[v] / setup.mass[v];
    if (omega_squared > omega_squared_max) {
      omega_squared_max = omega_squared;
      report.limiting_vertex = static_cast<std::int32_t>(v);
    }
    report.damping_rate_max =
        std::max(report.damping_rate_max, (damping_sum[v] + nodal_damping) / setup.mass[v] + setup.mass_damping);
    mass_damping_min = std::min(mass_damping_min, setup.mass_damping + setup.nodal_damping_gamma0 / setup.mass[v]);
  }
  report.omega_max = std::sqrt(omega_squared_max);
  const double w = report.omega_max;
  const double beta = report.damping_rate_max;
  // rho bounds |lambda| of the test equation's roots lambda = -beta/2 +- sqrt(beta^2/4 - w^2).
  const double rho = beta / 2.0 + std::sqrt(w * w + beta * beta / 4.0);
  const double infinity = std::numeric_limits<double>::infinity();
  double damped_modes_limit = infinity;  // forward Euler, without the undamped modes
  switch (setup.integrator) {
    case Integrator::SemiImplicitEuler:
    case Integrator::VelocityVerlet:
      // Symplectic Euler on x'' + beta x' + w^2 x = 0 is stable iff h <= 2 / (beta/2 + sqrt(w^2 + beta^2/4))
      // (Jury criterion on its 2x2 step matrix: trace 2 - beta h - w^2 h^2, determinant 1 - beta h); velocity
      // Verlet has the same limit h w <= 2 without damping and is given the same bound with it.
      report.critical_time_step = rho > 0.0 ? 2.0 / rho : infinity;
      report.limit = "h <= 2 / (beta/2 + sqrt(w^2 + beta^2/4))";
      break;
    case Integrator::RungeKutta4:
      // |h lambda| <= 2.5 lies inside RK4's stability region for every Re(lambda) <= 0 (checked numerically:
      // max |R(z)| = 0.873 on that half circle); the region reaches 2.83 on the imaginary axis.
      report.critical_time_step = rho > 0.0 ? 2.5 / rho : infinity;
      report.limit = "h <= 2.5 / (beta/2 + sqrt(w^2 + beta^2/4))";
      break;
    case Integrator::ForwardEuler: {
      // A mode with m = x*Mx, c = x*Cx, k = x*Kx (x its eigenvector) has m l^2 + c l + k = 0. Underdamped, forward
      // Euler needs |1 + h l|^2 = 1 - h c/m + h^2 k/m <= 1, i.e. h <= c / k; overdamped, h |l| <= 2 with |l| <= c/m
      // <= beta_max. Mass and nodal damping act on every motion: c >= alpha_min m >= (alpha_min / w_max^2) k for every
      // mode, so h <= alpha_min / w_max^2 is stable whatever the prestress. Dashpots damp only along springs and
      // element damping only the elements' own stiffness: a stretched spring's sideways stiffness (T/l)(I - u u^T) and
      // a loaded element's rotation are undamped by them, so without mass or nodal damping (alpha_min = 0) those
      // modes grow at every step; modes the dashpots do reach need h <= min_s c_s / k_s (or beta_e).
      const double ratio = std::min(spring_ratio_min, element_ratio_min);
      const double overdamped = beta > 0.0 ? 2.0 / beta : infinity;
      damped_modes_limit = std::min(ratio, overdamped);
      report.undamped_modes = omega_squared_max > 0.0 && !(mass_damping_min > 0.0);
      const double mass_term = omega_squared_max > 0.0 ? mass_damping_min / omega_squared_max : infinity;
      report.critical_time_step = report.undamped_modes ? 0.0 : std::min(mass_term, overdamped);
      report.limit = report.undamped_modes ? "h <= min(min_s c_s / k_s, min_e beta_e, 2 / beta) for the damped modes"
                                           : "h <= min(alpha_min / w^2, 2 / beta)";
      break;
    }
    case Integrator::ImplicitEuler:
      report.critical_time_step = infinity;
      report.limit = "unconditionally stable";
      break;
  }
  const SourceRange& dt_range = setup.time_step_range;
  if (!setup.time_step) {
    report.automatic = true;
    double reference = report.critical_time_step;
    if (setup.integrator == Integrator::ImplicitEuler) {
      // Stable at any step; 'auto' takes 10 explicit critical steps, which keeps the numerical damping moderate.
      reference = rho > 0.0 ? 10.0 * 2.0 / rho : infinity;
    }
    if (setup.integrator == Integrator::ForwardEuler && report.undamped_modes) {
      diagnostics.error(dt_range,
                        "dt auto: forward Euler has no stable step here: the sideways vibrations of stretched springs "
                        "and the rotations of loaded elements are damped by neither the dashpots nor the elements' "
                        "stiffness-proportional damping, and forward Euler amplifies an undamped vibration at every "
                        "step; add mass damping (damping: {rayleigh: {mass: ALPHA}}) or nodal damping (law: gamma0), "
                        "or use semi_implicit_euler");
      return std::nullopt;
    }
    if (!std::isfinite(reference) || !(reference > 0.0)) {
      diagnostics.error(dt_range,
                        std::isfinite(reference)
                            ? "dt auto: no stable time step exists for " + std::string(to_string(setup.integrator)) +
                                  " without damping; add damping or use semi-implicit Euler"
                            : "dt auto: no time step can be derived (no spring or element acts on a free vertex); "
                              "give dt explicitly");
      return std::nullopt;
    }
    report.time_step = setup.stability_margin * reference;
    return report;
  }
  report.time_step = *setup.time_step;
  const double limit = setup.integrator == Integrator::ForwardEuler && report.undamped_modes
                           ? damped_modes_limit
                           : report.critical_time_step;
  if (setup.integrator == Integrator::ForwardEuler && omega_squared_max > 0.0 && !(limit > 0.0) &&
      setup.refuse_unstable_time_step) {
    diagnostics.error(dt_range,
                      "forward Euler is unstable at every time step for undamped springs (|1 + i h w| > 1); "
                      "add damping or use semi-implicit Euler");
    return std::nullopt;
  }
  if (report.time_step > limit) {
    const std::string message =
        "dt: time step " + number(report.time_step) + " s exceeds the " + to_string(setup.integrator) +
        " stability limit " + number(limit) + " s (" + report.limit + " with w_max = " + number(w) +
        " rad/s at vertex " + std::to_string(report.limiting_vertex) + ", beta_max = " + number(beta) +
        " 1/s); use dt <= " + number(setup.stability_margin * limit) + " s, dt auto, or implicit Euler";
    if (!setup.refuse_unstable_time_step) {
      diagnostics.warning(dt_range, "unstable-time-step", message);
      return report;
    }
    diagnostics.error(dt_range, message);
    return std::nullopt;
  }
  if (setup.integrator == Integrator::ForwardEuler && report.undamped_modes) {
    diagnostics.warning(dt_range, "undamped-modes",
                        "forward Euler: the sideways vibrations of stretched springs and the rotations of loaded "
                        "elements are undamped here and grow at any step (slowly at small steps; the NaN guard stops "
                        "the run if they blow up); add mass damping (damping: {rayleigh: {mass: ALPHA}}) or nodal "
                        "damping to make the step stable");
  }
  return report;
}

}  // namespace fmpc::sim
