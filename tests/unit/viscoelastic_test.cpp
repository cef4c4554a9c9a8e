// Prony-series viscoelasticity on every law (kernels/prony_viscoelasticity.h) against the closed-form relaxation and
// creep of the same series in homogeneous deformation, and the per-point state's checkpoint on the CPU engine: a
// restore and the same steps again give the same bits (the run supervisor's replay relies on it).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <vector>

#include "kernels/element_laws.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/fem/fem_model_builder.h"
#include "runtime/integrate/stepping_engine.h"
#include "runtime/mesh/generated_mesh.h"
#include "runtime/scene/scene_builder.h"
#include "runtime/scene/scene_file.h"
#include "tests/support/viscoelastic_box.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

// G(t) = g_inf + sum_i g_i exp(-t / tau_i), g_inf = 1 - sum_i g_i (Abaqus's convention: G(0) = 1).
double relaxation(const std::vector<PronyTerm>& prony, double t) {
  double g = 1.0;
  for (const PronyTerm& term : prony) g += term.weight * (std::exp(-t / term.time) - 1.0);
  return g;
}

// The creep compliance J(t) of G for at most two terms (J(0) = 1, J(inf) = 1 / g_inf), in closed form: the Laplace
// transform J^(s) = D(s) / (s N(s)) with D(s) = prod_i (1 + s tau_i) and N(s) = s G^(s) D(s) = g_inf D(s) +
// sum_i g_i s tau_i prod_(j != i) (1 + s tau_j), so J(t) = 1 / g_inf + sum_k D(r_k) / (r_k N'(r_k)) exp(r_k t) over
// the roots r_k of N (real, negative).
double creep(const std::vector<PronyTerm>& prony, double t) {
  double g_inf = 1.0;
  for (const PronyTerm& term : prony) g_inf -= term.weight;
  // Polynomials in s, lowest power first.
  std::vector<double> D = {1.0};
  const auto times = [](const std::vector<double>& a, const std::vector<double>& b) {
    std::vector<double> out(a.size() + b.size() - 1, 0.0);
    for (std::size_t i = 0; i < a.size(); ++i)
      for (std::size_t j = 0; j < b.size(); ++j) out[i + j] += a[i] * b[j];
    return out;
  };
  for (const PronyTerm& term : prony) D = times(D, {1.0, term.time});
  std::vector<double> N(D.size(), 0.0);
  for (std::size_t k = 0; k < D.size(); ++k) N[k] = g_inf * D[k];
  for (std::size_t i = 0; i < prony.size(); ++i) {
    std::vector<double> part = {0.0, prony[i].weight * prony[i].time};
    for (std::size_t j = 0; j < prony.size(); ++j)
      if (j != i) part = times(part, {1.0, prony[j].time});
    for (std::size_t k = 0; k < part.size(); ++k) N[k] += part[k];
  }
  std::vector<double> roots;
  if (N.size() == 2) {
    roots = {-N[0] / N[1]};
  } else {
    REQUIRE(N.size() == 3);
    const double discriminant = N[1] * N[1] - 4.0 * N[2] * N[0];
    REQUIRE(discriminant > 0.0);
    roots = {(-N[1] + std::sqrt(discriminant)) / (2.0 * N[2]), (-N[1] - std::sqrt(discriminant)) / (2.0 * N[2])};
  }
  const auto value = [](const std::vector<double>& p, double s) {
    double out = 0.0;
    for (std::size_t k = p.size(); k-- > 0;) out = out * s + p[k];
    return out;
  };
  std::vector<double> dN(N.size() - 1);
  for (std::size_t k = 1; k < N.size(); ++k) dN[k - 1] = static_cast<double>(k) * N[k];
  double j = 1.0 / g_inf;
  for (const double r : roots) j += value(D, r) / (r * value(dN, r)) * std::exp(r * t);
  return j;
}

// One linear tetrahedron (a right corner of 1 cm) with a law's parameters for E = 5 kPa, nu = 0.3 (its registry
// builder) and a Prony series, its per-point state held here.
struct ViscoelasticElement {
  double rest[4][3] = {{0, 0, 0}, {0.01, 0, 0}, {0, 0.01, 0}, {0, 0, 0.01}};
  double rest_inverse[9] = {100, 0, 0, 0, 100, 0, 0, 0, 100};
  double volume = 1e-6 / 6.0;
  std::int32_t nodes[4] = {0, 1, 2, 3};
  std::int32_t slots[4] = {0, 1, 2, 3};
  ElementTerm term;
  std::vector<double> state;
  kernels::ElementTermView<double> view{};

  ViscoelasticElement(const ElementLawRow& row, const std::vector<PronyTerm>& prony) {
    ElementMaterial material;
    material.youngs_modulus = {5000.0};
    material.poisson_ratio = {0.3};
    DiagnosticList diagnostics;
    const auto build = row.build(material, diagnostics);
    REQUIRE(build);
    term = build->term;
    term.prony = prony;
    state.assign(static_cast<std::size_t>(point_state_width(term)), 0.0);
    view.law = row.law;
    view.element = kernels::element_kind_index<kernels::LinearTetrahedron>;
    view.count = 1;
    view.corners = nodes;
    view.corner_slot = slots;
    view.rest_inverse = rest_inverse;
    view.rest_volume = &volume;
    for (int p = 0; p < kernels::kMostLawParameters; ++p)
      view.parameter[p] = term.parameter[p].empty() ? nullptr : term.parameter[p].data();
    view.state = {state.data(), point_state_width(term), 1};
  }

  // P at F with the state held (the element's only point).
  void stress(const double* F, double* P) const {
    kernels::visit_element_law(view.law, [&](auto element_law) {
      kernels::point_first_piola<decltype(element_law)>(view, 0, 0, F, static_cast<const double*>(nullptr), P);
    });
  }

  // The state update at the nodes F X (the step's end), with the constants at time step dt (0: a jump).
  void update(const double* F, double dt) {
    double x[4], y[4], z[4], zero[4] = {0, 0, 0, 0};
    for (int a = 0; a < 4; ++a) {
      const double* X = rest[a];
      x[a] = F[0] * X[0] + F[1] * X[1] + F[2] * X[2];
      y[a] = F[3] * X[0] + F[4] * X[1] + F[5] * X[2];
      z[a] = F[6] * X[0] + F[7] * X[1] + F[8] * X[2];
    }
    kernels::ElementTermView<double> at = view;
    at.prony = prony_constants(term.prony, dt, false);
    const kernels::StateView<double> positions{x, y, z, zero, zero, zero};
    kernels::visit_element_term(view.element, view.law, [&](auto kind, auto element_law) {
      kernels::element_state_update<decltype(kind), decltype(element_law)>(0, at, positions);
    });
  }

  // The stress constants of a run at time step dt: at the step's end (implicit Euler) or start (the others).
  void use_time_step(double dt, bool step_end) { view.prony = prony_constants(term.prony, dt, step_end); }
};

const std::vector<PronyTerm> kTwoTerms = {{0.3, 0.05}, {0.25, 0.8}};

}  // namespace

TEST_CASE("prony constants: a jump at dt = 0, decay and gain at a step, the stress's at the step's start or end",
          "[fem][visco]") {
  const kernels::PronyConstants<double> jump = prony_constants(kTwoTerms, 0.0, false);
  CHECK(jump.count == 2);
  CHECK(jump.decay[0] == 1.0);
  CHECK(jump.gain[1] == 0.25);
  CHECK(jump.stress_scale == 1.0);
  const kernels::PronyConstants<double> c = prony_constants(kTwoTerms, 0.01, true);
  CHECK(c.decay[0] == Approx(std::exp(-0.2)).epsilon(1e-15));
  CHECK(c.gain[0] == Approx(0.3 * (1.0 - std::exp(-0.2)) / 0.2).epsilon(1e-15));
  CHECK(c.stress_scale == Approx(0.45 + c.gain[0] + c.gain[1]).epsilon(1e-15));
  CHECK(c.stress_decay[1] == c.decay[1]);
  CHECK(c.stress_gain[1] == c.gain[1]);
  const kernels::PronyConstants<double> start = prony_constants(kTwoTerms, 0.01, false);
  CHECK(start.decay[0] == c.decay[0]);
  CHECK(start.stress_scale == 1.0);
  CHECK(start.stress_decay[0] == 1.0);
  CHECK(start.stress_gain[0] == 0.3);
  CHECK(prony_constants({}, 0.01, false).count == 0);
  // A step far below tau keeps the gain's precision (expm1): c -> g (1 - r / 2).
  const kernels::PronyConstants<double> tiny = prony_constants({{0.5, 1.0}}, 1e-12, true);
  CHECK(tiny.gain[0] == Approx(0.5 * (1.0 - 0.5e-12)).epsilon(1e-15));
}

TEST_CASE("every law with a Prony series relaxes as G(t) after a step strain, at small and large strain",
          "[fem][visco]") {
  for (const ElementLawRow& row : element_law_rows()) {
    for (const double strain : {1e-4, 0.3})
    for (const bool step_end : {false, true}) {
      INFO("law " << row.keyword << ", strain " << strain << (step_end ? ", stress at the step's end" : ""));
      ViscoelasticElement element(row, kTwoTerms);
      // A stretch along x with some shear: a homogeneous deformation held from t = 0.
      const double F[9] = {1.0 + strain, 0.2 * strain, 0.0, 0.0, 1.0, 0.1 * strain, 0.0, 0.0, 1.0 - 0.3 * strain};
      double instantaneous[9];
      element.stress(F, instantaneous);  // the state is zero: the law's own stress
      element.update(F, 0.0);
      const double dt = 1e-3;
      element.use_time_step(dt, step_end);
      double worst = 0.0, largest = 0.0;
      for (const double p : instantaneous) largest = std::max(largest, std::abs(p));
      REQUIRE(largest > 0.0);
      for (int n = 0; n <= 3000; ++n) {
        double P[9];
        element.stress(F, P);
        // After n updates the state is at t_n: the stress at the step's start is G(t_n) S0, at its end G(t_(n+1)) S0.
        const double g = relaxation(kTwoTerms, (step_end ? n + 1 : n) * dt);
        for (int k = 0; k < 9; ++k) worst = std::max(worst, std::abs(P[k] - g * instantaneous[k]) / largest);
        element.update(F, dt);
      }
      // Simo's recursion is exact for a strain held (h_i = g_i S0 a_i^n): rounding only.
      CHECK(worst < 1e-12);
    }
  }
}

TEST_CASE("every element kind with every law: each material point keeps its own Prony history (point kPoints e + q), "
          "and each element relaxes by its own weights where they vary per element",
          "[fem][visco]") {
  // Two elements of each kind on separate nodes, each held at its own non-uniform deformation from t = 0: every
  // point's stress is G(t) times its elastic one, so the node forces are G(t) times the elastic forces exactly, but
  // only where each point reads and updates its own state (a point reading another element's or another point's
  // history would see a different S0). With per-element weights (the first term's 0.3 on element 0, 0.05 on element
  // 1; kernels::prony_weighted) each element's G is its own series', at the step's start and end constants alike.
  const std::vector<std::vector<PronyTerm>> element_series = {kTwoTerms, {{0.05, 0.05}, {0.25, 0.8}}};
  for (int kind = 0; kind < kernels::ElementKinds::count; ++kind)
    for (const ElementLawRow& row : element_law_rows())
    for (const bool per_element : {false, true})
    for (const bool step_end : {false, true}) {
      if (!per_element && step_end) continue;  // the relaxation test above holds the step's end constants
      kernels::visit_element_term(kind, row.law, [&](auto element_kind, auto element_law) {
        using Kind = decltype(element_kind);
        using Law = decltype(element_law);
        constexpr int N = Kind::kNodes;
        INFO("element kind " << element_kind_row(kind).keyword << ", law " << row.keyword
                             << (per_element ? ", weights per element" : "")
                             << (step_end ? ", stress at the step's end" : ""));
        ElementMaterial material;
        material.youngs_modulus = {5000.0, 7000.0};
        material.poisson_ratio = {0.3, 0.3};
        DiagnosticList diagnostics;
        auto build = row.build(material, diagnostics);
        REQUIRE(build);
        ElementTerm term = build->term;
        term.prony = kTwoTerms;
        if (per_element) term.prony[0].element_weight = {0.3, 0.05};
        const double corners[4][3] = {{0, 0, 0}, {0.01, 0, 0}, {0, 0.01, 0}, {0, 0, 0.01}};
        double rest[N][3];
        kernels::element_rest_nodes<Kind>(corners, rest);
        const double rest_inverse[18] = {100, 0, 0, 0, 100, 0, 0, 0, 100, 100, 0, 0, 0, 100, 0, 0, 0, 100};
        const double volume[2] = {1e-6 / 6.0, 1e-6 / 6.0};
        std::vector<std::int32_t> nodes(2 * N);
        for (int a = 0; a < 2 * N; ++a) nodes[static_cast<std::size_t>(a)] = a;
        const int points = 2 * Kind::kPoints;
        std::vector<double> state(static_cast<std::size_t>(point_state_width(term) * points), 0.0);
        kernels::ElementTermView<double> view{};
        view.law = row.law;
        view.element = kind;
        view.count = 2;
        view.corners = nodes.data();
        view.corner_slot = nodes.data();
        view.rest_inverse = rest_inverse;
        view.rest_volume = volume;
        for (int p = 0; p < kernels::kMostLawParameters; ++p)
          view.parameter[p] = term.parameter[p].empty() ? nullptr : term.parameter[p].data();
        view.prony_weight[0] = per_element ? term.prony[0].element_weight.data() : nullptr;
        view.state = {state.data(), point_state_width(term), points};
        // A kind with a nodal pass: its nodal pressure held at zero, so that its forces are the shear part's, which
        // carries the Prony series (the volumetric part is elastic).
        const std::vector<double> no_pressure(2 * N, 0.0);
        view.nodal_pressure = view.nodal_dilatation = no_pressure.data();
        // x = X + u(X), u quadratic in X (so that a quadratic element's points see different F), larger on element 1.
        std::vector<double> x(2 * N), y(2 * N), z(2 * N), zero(2 * N, 0.0);
        double at[2][N][3];
        for (int e = 0; e < 2; ++e)
          for (int a = 0; a < N; ++a) {
            const double* X = rest[a];
            const double s = e == 0 ? 0.05 : 0.2;
            at[e][a][0] = X[0] + s * (X[0] + 60.0 * X[1] * X[1]);
            at[e][a][1] = X[1] + s * (0.3 * X[2] - 50.0 * X[0] * X[2]);
            at[e][a][2] = X[2] - s * (0.2 * X[2] + 40.0 * X[0] * X[0]);
            x[static_cast<std::size_t>(N * e + a)] = at[e][a][0];
            y[static_cast<std::size_t>(N * e + a)] = at[e][a][1];
            z[static_cast<std::size_t>(N * e + a)] = at[e][a][2];
          }
        const kernels::StateView<double> positions{x.data(), y.data(), z.data(), zero.data(), zero.data(), zero.data()};
        const auto forces = [&](int e, double out[N][3]) {
          Kind::template forces<Law>(view, e, at[e], static_cast<const double(*)[3]>(nullptr), out);
        };
        double elastic[2][N][3];
        for (int e = 0; e < 2; ++e) forces(e, elastic[e]);  // the state is zero: the law's own stress
        // A purely volumetric law (the volume term) has no shear part on a kind with a nodal pass: nothing to relax.
        if (Kind::kNodalPressure) {
          bool moves = false;
          for (int a = 0; a < N; ++a)
            for (int i = 0; i < 3; ++i) moves = moves || elastic[1][a][i] != 0.0;
          if (!moves) return;
        }
        const auto update = [&](double dt) {
          kernels::ElementTermView<double> constants = view;
          constants.prony = prony_constants(term.prony, dt, false);
          for (int e = 0; e < 2; ++e) kernels::element_state_update<Kind, Law>(e, constants, positions);
        };
        update(0.0);
        const double dt = 0.01;
        view.prony = prony_constants(term.prony, dt, step_end);
        double worst = 0.0;
        for (int n = 0; n <= 100; ++n) {
          for (int e = 0; e < 2; ++e) {
            // After n updates the state is at t_n: the stress at the step's start is G(t_n) S0, at its end G(t_(n+1)).
            const double g = relaxation(per_element ? element_series[static_cast<std::size_t>(e)] : kTwoTerms,
                                        (step_end ? n + 1 : n) * dt);
            double out[N][3], largest = 0.0, difference = 0.0;
            forces(e, out);
            for (int a = 0; a < N; ++a)
              for (int i = 0; i < 3; ++i) {
                largest = std::max(largest, std::abs(elastic[e][a][i]));
                difference = std::max(difference, std::abs(out[a][i] - g * elastic[e][a][i]));
              }
            REQUIRE(largest > 0.0);
            worst = std::max(worst, difference / largest);
          }
          update(dt);
        }
        CHECK(worst < 1e-12);
      });
    }
}

TEST_CASE("every law with a Prony series creeps as the series' closed-form compliance under a constant stress",
          "[fem][visco]") {
  for (const std::vector<PronyTerm>& prony : {std::vector<PronyTerm>{{0.4, 0.2}}, kTwoTerms}) {
    for (const ElementLawRow& row : element_law_rows()) {
      INFO("law " << row.keyword << ", " << prony.size() << " Prony terms");
      ViscoelasticElement element(row, prony);
      // Uniaxial strain F = diag(1 + eps, 1, 1) under a constant P11 = sigma from t = 0: each step solves P11(eps) =
      // sigma at the step's end with the state held (Newton, the tangent by central differences; the stress
      // constants implicit Euler uses), then updates the state: Simo's algorithm, quasi-static.
      const auto p11 = [&](double eps) {
        const double F[9] = {1.0 + eps, 0, 0, 0, 1, 0, 0, 0, 1};
        double P[9];
        element.stress(F, P);
        return P[0];
      };
      const double modulus = (p11(1e-7) - p11(-1e-7)) / 2e-7;  // the instantaneous modulus at rest (state zero)
      REQUIRE(modulus > 0.0);
      const double sigma = modulus * 1e-6;  // a strain of about 1e-6 at first: small strain
      const auto solve = [&](double eps) {
        for (int iteration = 0; iteration < 30; ++iteration) {
          const double step = 1e-9;
          const double slope = (p11(eps + step) - p11(eps - step)) / (2.0 * step);
          const double change = (sigma - p11(eps)) / slope;
          eps += change;
          if (std::abs(change) < 1e-18) break;
        }
        return eps;
      };
      double eps = solve(0.0);
      const auto F_of = [](double e) { return std::vector<double>{1.0 + e, 0, 0, 0, 1, 0, 0, 0, 1}; };
      element.update(F_of(eps).data(), 0.0);
      const double dt = 1e-3;
      element.use_time_step(dt, true);
      double worst = 0.0;
      for (int n = 1; n <= 2000; ++n) {
        eps = solve(eps);
        element.update(F_of(eps).data(), dt);
        const double expected = sigma / modulus * creep(prony, n * dt);
        worst = std::max(worst, std::abs(eps - expected) / expected);
      }
      INFO("largest relative error of the creep strain over 2 s: " << worst);
      CHECK(worst < 1e-4);
    }
  }
}

TEST_CASE("a viscoelastic FEM's per-point state is saved and restored with the CPU engine's checkpoint",
          "[fem][visco]") {
  for (const ElementKindRow& kind : element_kind_rows()) {
    DiagnosticList diagnostics;
    // Fewer cells for the kinds after the first (CI's time: the quadratic kind's 3 x 3 x 2 box took 10 s here, most
    // of it implicit Euler's factorisations).
    const bool first_kind = kind.kind == 0;
    auto setup =
        viscoelastic_box(first_kind ? 3 : 2, first_kind ? 3 : 2, first_kind ? 2 : 1, kTwoTerms, diagnostics, kind.kind);
    REQUIRE(setup);
    // The first term's weight per element (0.3 and 0.1 alternating): the weights are the run's constants, the state
    // the checkpoint's, whichever way the weights are held.
    std::vector<double>& weights = setup->elements.terms.front().prony.front().element_weight;
    for (std::size_t e = 0; e < setup->tetrahedra.size(); ++e) weights.push_back(e % 2 == 0 ? 0.3 : 0.1);
    for (const Precision precision : {Precision::Float, Precision::Double}) {
      for (const Integrator integrator : {Integrator::SemiImplicitEuler, Integrator::VelocityVerlet,
                                          Integrator::RungeKutta4, Integrator::ImplicitEuler}) {
        INFO(kind.keyword << " elements, " << static_cast<int>(integrator) << ", "
                          << (precision == Precision::Float ? "float" : "double"));
        SimulationSetup scene = *setup;
        scene.precision = precision;
        scene.integrator = integrator;
        const auto stability = check_stability(scene, diagnostics);
        REQUIRE(stability);
        const std::vector<SimulationSetup> scenes = {scene};
        const auto engine = create_cpu_engine(scenes, {*stability}, 1);
        REQUIRE(engine->run({20}, diagnostics));
        REQUIRE(engine->save_checkpoint(diagnostics));
        REQUIRE(engine->run({40}, diagnostics));
        const std::vector<Point3> first = engine->positions(0, diagnostics);
        REQUIRE(engine->restore_checkpoint(diagnostics));
        CHECK(engine->steps_taken() == 20);
        REQUIRE(engine->run({40}, diagnostics));
        const std::vector<Point3> again = engine->positions(0, diagnostics);
        CHECK(first == again);
        // The history matters: the same steps from the restored positions with the state left as it was after step
        // 40 (no restore of the state) would differ. An elastic run's positions differ from the viscoelastic one's.
        SimulationSetup elastic = scene;
        elastic.elements.terms.front().prony.clear();
        const std::vector<SimulationSetup> elastic_scenes = {elastic};
        const auto elastic_engine = create_cpu_engine(elastic_scenes, {*stability}, 1);
        REQUIRE(elastic_engine->run({40}, diagnostics));
        CHECK(elastic_engine->positions(0, diagnostics) != first);
      }
    }
  }
}

TEST_CASE("a Prony series with weights summing to 1 or more, or too many terms, is refused naming the term",
          "[fem][visco]") {
  DiagnosticList diagnostics;
  auto setup = viscoelastic_box(1, 1, 1, {{0.6, 1.0}, {0.4, 2.0}}, diagnostics);
  REQUIRE(setup);
  DiagnosticList refused;
  CHECK_FALSE(validate_setup(*setup, refused));
  CHECK(refused.items().front().message ==
        "element term 0: the Prony weights sum to 1; they must sum below 1 (the long-term modulus is 1 - sum g_i of "
        "the law's)");
  setup->elements.terms.front().prony = {{0.1, 1.0}, {0.1, 1.0}, {0.1, 1.0}, {0.1, 1.0}, {0.1, 1.0}};
  DiagnosticList many;
  CHECK_FALSE(validate_setup(*setup, many));
  CHECK(many.items().front().message == "element term 0 has 5 Prony terms; at most 4 are allowed");
  setup->elements.terms.front().prony = {{0.1, 0.0}};
  DiagnosticList zero_time;
  CHECK_FALSE(validate_setup(*setup, zero_time));
  CHECK(zero_time.items().front().message ==
        "element term 0: Prony term 0 has weight 0.1 and time 0 s; a weight is in (0, 1) and a time positive and "
        "finite");
  // Weights per element: one per element, each in [0, 1) (0 allowed: the term does not relax there), the sum below 1
  // at every element.
  const std::size_t count = setup->tetrahedra.size();
  REQUIRE(count >= 2);
  const auto refusal = [&](std::vector<double> first, double second) {
    setup->elements.terms.front().prony = {{0.0, 1.0, std::move(first)}, {second, 2.0}};
    DiagnosticList found;
    const bool valid = validate_setup(*setup, found);
    return valid ? std::string() : found.items().front().message;
  };
  std::vector<double> weights(count, 0.4);
  weights.front() = 0.0;
  CHECK(refusal(weights, 0.5).empty());
  CHECK(refusal(std::vector<double>(count - 1, 0.4), 0.5) ==
        "element term 0: Prony term 0 has " + std::to_string(count - 1) + " weights for " + std::to_string(count) +
            " elements; give one per element or none");
  weights.back() = -0.1;
  CHECK(refusal(weights, 0.5) == "element term 0: Prony term 0 has weight -0.1 at element " +
                                     std::to_string(count - 1) + "; a weight per element is in [0, 1)");
  weights.back() = std::nan("");
  CHECK(refusal(weights, 0.5) == "element term 0: Prony term 0 has weight nan at element " +
                                     std::to_string(count - 1) + "; a weight per element is in [0, 1)");
  weights.back() = 0.6;
  CHECK(refusal(weights, 0.5) == "element term 0: the Prony weights sum to 1.1 at element " +
                                     std::to_string(count - 1) +
                                     "; they must sum below 1 (the long-term modulus is 1 - sum g_i of the law's)");
}

namespace {

// The errors of parsing (and, where it parses, building) a scene, as "LINE:COL: message".
std::vector<std::string> scene_errors(const std::string& text) {
  DiagnosticList diagnostics;
  const auto scene = parse_scene("/scenes/s.yaml", text, diagnostics);
  if (scene) build_scene(*scene, diagnostics);
  std::vector<std::string> out;
  for (const Diagnostic& d : diagnostics.items())
    if (d.severity == Severity::Error)
      out.push_back(std::to_string(d.range.line) + ":" + std::to_string(d.range.column) + ": " + d.message);
  return out;
}

const std::string kFemScene =
    "model: corotational_fem\nmesh: {box: {size: [0.02, 0.02, 0.02], cells: [1, 1, 1]}}\nmass: {density: 1000}\n";

}  // namespace

TEST_CASE("material.viscoelastic: the scene's Prony series reaches the element term; errors are located",
          "[fem][visco][scene]") {
  {
    DiagnosticList diagnostics;
    const auto scene = parse_scene(
        "/scenes/s.yaml",
        kFemScene + "material:\n  youngs_modulus: 5\n  viscoelastic: {prony: [{weight: 0.3, time: 1.86}, "
                    "{weight: 0.2, time: 51.3}]}\n",
        diagnostics);
    REQUIRE(scene);
    const auto built = build_scene(*scene, diagnostics);
    REQUIRE(built);
    const std::vector<PronyTerm>& prony = built->setup.elements.terms.at(0).prony;
    REQUIRE(prony.size() == 2);
    CHECK(prony[0].weight == 0.3);
    CHECK(prony[1].time == 51.3);
  }
  CHECK(scene_errors(kFemScene + "material:\n  youngs_modulus: 5\n  viscoelastic: {prony: [{weight: 0.6, time: 1}, "
                                 "{weight: 0.5, time: 2}]}\n") ==
        std::vector<std::string>{"6:25: material.viscoelastic.prony: the weights sum to 1.1; they must sum below 1 (the "
                                 "long-term modulus is 1 - sum g_i times the law's instantaneous one)"});
  CHECK(scene_errors(kFemScene + "material:\n  youngs_modulus: 5\n  viscoelastic: {prony: [{weight: 1.5, time: 1}]}\n") ==
        std::vector<std::string>{"6:35: material.viscoelastic.prony[0].weight: 1.5 is not in (0, 1): a weight is the "
                                 "fraction of the instantaneous stress that relaxes with this time constant"});
  CHECK(scene_errors(kFemScene + "material:\n  youngs_modulus: 5\n  viscoelastic: {prony: []}\n") ==
        std::vector<std::string>{"6:25: material.viscoelastic.prony: expected a list of 1 to 4 Prony terms {weight: g, "
                                 "time: tau (s)}"});
  CHECK(scene_errors(kFemScene + "material:\n  youngs_modulus: 5\n  viscoelastic: {prony: [{weight: 0.2}]}\n") ==
        std::vector<std::string>{"6:26: material.viscoelastic.prony[0]: a Prony term needs 'weight' and 'time'"});
  CHECK(scene_errors("mesh: {box: {size: [0.02, 0.02, 0.02], cells: [1, 1, 1]}}\nmaterial:\n  youngs_modulus: 5\n"
                     "  viscoelastic: {prony: [{weight: 0.2, time: 1}]}\n") ==
        std::vector<std::string>{"4:17: material.viscoelastic acts on an element law; a spring network has none: use a "
                                 "finite-element model (model: corotational_fem), or remove 'viscoelastic'"});
}

TEST_CASE("a displacement probe's reaction force includes the Prony history: held, it relaxes to g_inf of the elastic "
          "one",
          "[fem][visco]") {
  DiagnosticList diagnostics;
  const std::vector<PronyTerm> prony = {{0.5, 0.05}};
  auto setup = viscoelastic_box(2, 2, 2, prony, diagnostics);
  REQUIRE(setup);
  setup->gravity = {0.0, 0.0, 0.0};
  setup->mass_damping = 100.0;  // quasi-static by the end
  setup->precision = Precision::Double;
  ProbeLoad probe;
  for (std::size_t v = 0; v < setup->rest_positions.size(); ++v)
    if (setup->rest_positions[v][1] < 1e-6) probe.vertices.push_back(static_cast<std::int32_t>(v));
  probe.target = {0.0, -0.001, 0.0};
  probe.ramp_time = 0.01;
  setup->probe = probe;
  SimulationSetup elastic = *setup;
  elastic.elements.terms.front().prony.clear();
  const auto viscous_run = Simulation::create(*setup, diagnostics);
  const auto elastic_run = Simulation::create(elastic, diagnostics);
  REQUIRE(viscous_run);
  REQUIRE(elastic_run);
  const auto steps = static_cast<std::size_t>(0.6 / viscous_run->stability(0).time_step);
  REQUIRE(viscous_run->advance(steps, diagnostics));
  REQUIRE(elastic_run->advance(steps, diagnostics));
  const double viscous = viscous_run->probe_reading(0, diagnostics).force[1];
  const double elastic_force = elastic_run->probe_reading(0, diagnostics).force[1];
  INFO("probe force after 0.6 s held: viscoelastic " << viscous << " N, elastic " << elastic_force << " N");
  REQUIRE(elastic_force < 0.0);
  // 12 time constants: the history's own part exp(-12) is gone; the rest is the quasi-static state's settling.
  CHECK(viscous / elastic_force == Approx(0.5).epsilon(0.02));
}
