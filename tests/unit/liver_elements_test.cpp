// SOFA's liver (issue 26, item 3): liver.msh (596 tetrahedra, ../shared/data/sofa-liver) under gravity, held at
// vertices 3, 39 and 64 (SOFA's FixedConstraint indices, 0-based as fmpc's fixed.indices) or at the patches within
// 1 unit of them, E = 1 MPa, nu = 0.49, density 1 (SOFA's liver scenes), at rest: the linear static solution, which
// implicit Euler with damping settles to. Every law x element kind of the registry against CalculiX C3D10 on the
// 1:8-refined mesh (subdivide_tetrahedra: straight edges, so the quadratic geometry is refined the same way). The
// suite compares each kind on the patch-held liver with stored numbers; the hidden case "[.liver_table]" makes them
// with ccx and prints docs/validation.md's tables (both supports, and the dynamics' cost).
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>
#include <vector>
#include <time.h>

#include "runtime/fem/element_law_registry.h"
#include "runtime/integrate/simulation.h"
#include "runtime/mesh/mesh_reader.h"
#include "runtime/mesh/mesh_refinement.h"
#include "tests/support/elastic_problem.h"
#include "tests/support/generated_program.h"

using namespace fmpc;
using namespace fmpc::sim;
using namespace fmpc::testing;

namespace {

const std::string kLiver = std::string(FMPC_SHARED_DATA_DIR) + "/sofa-liver/liver.msh";
constexpr std::size_t kFixed[] = {3, 39, 64};
constexpr double kPoissonRatio = 0.49;
constexpr double kSupportRadius = 1.0;  // mesh units (the liver is about 6.5 x 4.9 x 4.4)

// CalculiX C3D10 on the 1:8-refined mesh with the patch supports (kSupportRadius), printed by `build/tests/fmpc_tests
// "[.liver_table]"` (ccx 2.20, Debian 12; about 11 minutes on the loaded 2-core build machine): the vertex of the
// coarse mesh that moves most and its displacement (m). C3D10 on the 1:64-refined mesh moves 0.972 times as far
// (field difference 2.8 %): the reference's own error.
constexpr std::size_t kReferenceVertex = 16;
constexpr Point3 kReferenceDisplacement{4.398156e-06, -0.000888201, -0.0002203159};

// fmpc on liver.msh at that vertex, printed by the same command; a law or kind without a row is named in a warning.
struct StoredDisplacement {
  const char* law;
  const char* element;
  Point3 displacement;
};
const std::vector<StoredDisplacement> kStored = {
    {"corotational", "linear", {1.262565677e-05, -0.0002708764123, -5.767950546e-05}},
    {"corotational", "quadratic", {2.5499721e-05, -0.0009889541464, -0.0002265940095}},
    {"stable_neo_hookean", "linear", {1.262565677e-05, -0.0002708764123, -5.767950546e-05}},
    {"stable_neo_hookean", "quadratic", {2.5499721e-05, -0.0009889541464, -0.0002265940095}},
    // The nodal pressure rows: the same fmpc_liver at the same precision, printed by the "[liver]" case's warning at
    // the merge of main into nodal ("[.liver_table]" was not rerun for them).
    {"corotational", "linear_nodal_pressure", {3.601154262e-05, -0.0005430425929, -0.000126709558}},
    {"stable_neo_hookean", "linear_nodal_pressure", {3.601154262e-05, -0.0005430425929, -0.000126709558}},
};

// The supports: radius 0 holds the three vertices alone (issue 26's case, SOFA's scenes); a radius (mesh units) holds
// every vertex within it of one of them, patches that stay the same as the mesh is refined. Three held points leave
// the problem without a limit: near a point support the displacement grows like 1 / r, so each refinement makes the
// liver hang lower (docs/validation.md measures it).
ElasticProblem liver_problem(const Mesh& mesh, double support_radius, double poisson_ratio = kPoissonRatio) {
  ElasticProblem p;
  p.mesh = mesh;
  p.youngs_modulus = 1e6;
  p.poisson_ratio = poisson_ratio;
  p.density = 1.0;
  p.gravity = {0.0, -9.81, 0.0};
  p.held.assign(mesh.points.size(), 0);
  for (const std::size_t fixed : kFixed)
    for (std::size_t v = 0; v < mesh.points.size(); ++v)
      if (v == fixed || distance(mesh.points[v], mesh.points[fixed]) <= support_radius) p.held[v] = 7u;
  return p;
}

std::optional<Mesh> read_liver() {
  if (!std::filesystem::exists(kLiver)) return std::nullopt;
  DiagnosticList diagnostics;
  auto mesh = read_mesh_file(kLiver, diagnostics);
  REQUIRE(mesh);
  return mesh;
}

double norm(const Point3& u) { return std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]); }

ElasticAnswer fmpc_liver(const Mesh& mesh, double support_radius, int law, int kind,
                         double poisson_ratio = kPoissonRatio) {
  std::string error;
  auto answer = solve_with_fmpc_fem(liver_problem(mesh, support_radius, poisson_ratio), law, kind, error);
  INFO(error);
  REQUIRE(answer);
  return *answer;
}

// Over the coarse mesh's `count` vertices: the largest displacement of `a` over that of `reference` (below 1: too
// stiff), and the largest distance between them over the reference's largest displacement.
struct Comparison {
  double largest_ratio = 0.0;
  double field_error = 0.0;
};
Comparison compare(const ElasticAnswer& a, const ElasticAnswer& reference, std::size_t count) {
  double largest = 0.0, largest_reference = 0.0, difference = 0.0;
  for (std::size_t v = 0; v < count; ++v) {
    largest = std::max(largest, norm(a.displacement[v]));
    largest_reference = std::max(largest_reference, norm(reference.displacement[v]));
    difference = std::max(difference, distance(a.displacement[v], reference.displacement[v]));
  }
  return {largest / largest_reference, difference / largest_reference};
}

double process_seconds() {
  timespec now{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &now);
  return static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
}

// The CPU cost of the liver's dynamics (one thread, double): steps per CPU second of the process, stepping for at
// least half a second, and the step the integrator took (semi-implicit Euler: its automatic step; implicit Euler:
// SOFA's 0.02 s).
struct Cost {
  double steps_per_second = 0.0;
  double time_step = 0.0;
  std::string solver;  // implicit Euler: the method and its iterations per step
};
Cost step_cost(const Mesh& mesh, int law, int kind, Integrator integrator,
               ImplicitMethod method = ImplicitMethod::Automatic) {
  std::string error;
  auto setup = fmpc_fem_setup(liver_problem(mesh, 0.0), law, kind, error);
  INFO(error);
  REQUIRE(setup);
  setup->integrator = integrator;
  if (integrator == Integrator::ImplicitEuler) setup->time_step = 0.02;
  setup->implicit.method = method;
  DiagnosticList diagnostics;
  auto simulation = Simulation::create(*setup, diagnostics);
  INFO(render_all(diagnostics, {}));
  REQUIRE(simulation);
  REQUIRE(simulation->advance(5, diagnostics));
  std::size_t steps = 0, batch = 10;
  const double start = process_seconds();
  double spent = 0.0;
  while (spent < 0.5) {
    REQUIRE(simulation->advance(batch, diagnostics));
    steps += batch;
    batch *= 2;
    spent = process_seconds() - start;
  }
  const ImplicitSolverReport report = simulation->implicit_solver();
  std::ostringstream solver;
  if (report.steps > 0)
    solver << to_string(report.method) << ", "
           << static_cast<double>(report.iterations_total) / static_cast<double>(report.steps) << " per step";
  return {static_cast<double>(steps) / spent, simulation->time() / static_cast<double>(steps + 5), solver.str()};
}

std::string fixed(double value, int digits) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(digits) << value;
  return out.str();
}

}  // namespace

TEST_CASE("SOFA's liver at nu 0.49: every law and element kind against CalculiX C3D10 on the refined mesh",
          "[validation][liver][heavy]") {
  const auto mesh = read_liver();
  if (!mesh) {
    WARN("skipped: " << kLiver << " is absent (../shared/data holds SOFA's liver mesh)");
    return;
  }
  std::ostringstream table;
  const double reference = norm(kReferenceDisplacement);
  for (const std::string& law : fem_law_keywords())
    for (const ElementKindRow& kind : element_kind_rows()) {
      const ElasticAnswer a = fmpc_liver(*mesh, kSupportRadius, fem_law_by_keyword(law)->law, kind.kind);
      const Point3& u = a.displacement[kReferenceVertex];
      const double ratio = norm(u) / reference, error = distance(u, kReferenceDisplacement) / reference;
      table << "\n  " << law << " / " << kind.keyword << ": " << fixed(ratio, 4)
            << " of the reference's displacement at vertex " << kReferenceVertex << ", error " << fixed(error * 100, 2)
            << " %";
      const auto stored = std::find_if(kStored.begin(), kStored.end(), [&](const StoredDisplacement& s) {
        return law == s.law && std::string(kind.keyword) == s.element;
      });
      if (stored != kStored.end()) {
        INFO(law << " / " << kind.keyword);
        CHECK(distance(u, stored->displacement) < 1e-6 * norm(stored->displacement));
      } else {
        WARN("no stored displacement for " << law << " / " << kind.keyword << " ({" << std::setprecision(10) << u[0]
                                           << ", " << u[1] << ", " << u[2]
                                           << "}): run build/tests/fmpc_tests \"[.liver_table]\" and add it");
      }
      // Each kind's locking claim (ElementKindRow::locking_poisson_ratio), by how much stiffer it is at nu 0.49
      // than at 0.3 (the same E): the quadratic kind 1.16 times, which the volume's stiffening alone explains; the
      // linear kind 2.0 times (it locks); the nodal pressure kind 1.11 times (it does not). A kind that says it locks
      // is at least twice too stiff here and stiffens by more than 1.5; one that says it does not stiffens by less
      // than 1.3. A kind that does not lock in volume can still be too stiff in bending on this coarse mesh (the
      // nodal pressure kind, 0.61 of the reference: linear shape functions; docs/validation.md), so its error against
      // the reference is its stored numbers' to keep, not part of the claim.
      const double stiffening =
          norm(fmpc_liver(*mesh, kSupportRadius, fem_law_by_keyword(law)->law, kind.kind, 0.3)
                   .displacement[kReferenceVertex]) /
          norm(u);
      table << ", |u| at nu 0.3 over |u| at 0.49: " << fixed(stiffening, 3);
      INFO(law << " / " << kind.keyword);
      if (kPoissonRatio > kind.locking_poisson_ratio) {
        CHECK(ratio < 0.5);
        CHECK(stiffening > 1.5);
      } else {
        CHECK(stiffening < 1.3);
      }
    }
  WARN("SOFA's liver held at three patches, nu 0.49, against CalculiX C3D10 on the 1:8-refined mesh:" << table.str());
}

TEST_CASE("SOFA's liver: the full table against CalculiX (docs/validation.md)", "[.liver_table]") {
  REQUIRE(calculix_available());
  const auto mesh = read_liver();
  REQUIRE(mesh);
  const std::size_t count = mesh->points.size();
  const Mesh refined = subdivide_tetrahedra(*mesh);
  const Mesh twice_refined = subdivide_tetrahedra(refined);
  std::ostringstream out;
  out << std::setprecision(10);
  for (const double radius : {0.0, kSupportRadius}) {
    const auto calculix = [&](const Mesh& on, bool quadratic, const char* tag) {
      ScratchFolder folder(tag);
      std::string error;
      auto answer = solve_with_calculix(liver_problem(on, radius), quadratic, folder.path(), error);
      INFO(error);
      REQUIRE(answer);
      return *answer;
    };
    out << "\n\nsupports: " << (radius == 0.0 ? "vertices 3, 39, 64" : "the vertices within 1 unit of them");
    const ElasticAnswer reference = calculix(refined, true, "ccx_liver_c3d10_r1");
    std::size_t vertex = 0;
    for (std::size_t v = 0; v < count; ++v)
      if (norm(reference.displacement[v]) > norm(reference.displacement[vertex])) vertex = v;
    const Point3& u = reference.displacement[vertex];
    out << "\nreference: C3D10 on the 1:8-refined mesh (" << refined.tetrahedra.size() << " tetrahedra): vertex "
        << vertex << " moves most, by {" << u[0] << ", " << u[1] << ", " << u[2] << "} m (" << norm(u) << ")";
    const Comparison r2 = compare(calculix(twice_refined, true, "ccx_liver_c3d10_r2"), reference, count);
    out << "\nC3D10 on the 1:64-refined mesh against it: largest displacement x" << r2.largest_ratio << ", field "
        << r2.field_error * 100 << " %";
    for (const bool quadratic : {false, true}) {
      const Comparison c = compare(calculix(*mesh, quadratic, "ccx_liver_same"), reference, count);
      out << "\nCalculiX " << (quadratic ? "C3D10" : "C3D4") << " on liver.msh: largest displacement x"
          << c.largest_ratio << ", field " << c.field_error * 100 << " %";
    }
    out << "\n\n| law | element | mesh | largest displacement / reference's | field error | displacement at vertex "
        << vertex << " (m) |\n| --- | --- | --- | ---: | ---: | --- |";
    for (const std::string& law : fem_law_keywords())
      for (const ElementKindRow& kind : element_kind_rows())
        for (const bool on_refined : {false, true}) {
          const ElasticAnswer a = fmpc_liver(on_refined ? refined : *mesh, radius, fem_law_by_keyword(law)->law, kind.kind);
          const Comparison c = compare(a, reference, count);
          const Point3& w = a.displacement[vertex];
          out << "\n| " << law << " | " << kind.keyword << " | " << (on_refined ? "1:8 refined" : "liver.msh") << " | "
              << fixed(c.largest_ratio, 3) << " | " << fixed(c.field_error * 100, 1) << " % | {" << w[0] << ", " << w[1]
              << ", " << w[2] << "} |";
        }
  }
  WARN("SOFA's liver, nu 0.49, against CalculiX C3D10 on the 1:8-refined mesh:" << out.str());
}

TEST_CASE("SOFA's liver: the dynamics' CPU cost per law x element kind (docs/validation.md)", "[.liver_cost]") {
  const auto mesh = read_liver();
  REQUIRE(mesh);
  std::ostringstream out;
  out << "\n| law | element | semi-implicit Euler: ns per element-step, automatic step | implicit Euler (dt 0.02 s): "
         "steps/s (solver, iterations) | the same, direct solver |\n| --- | --- | ---: | ---: | ---: |";
  for (const std::string& law : fem_law_keywords())
    for (const ElementKindRow& kind : element_kind_rows()) {
      const int law_index = fem_law_by_keyword(law)->law;
      const Cost explicit_cost = step_cost(*mesh, law_index, kind.kind, Integrator::SemiImplicitEuler);
      out << "\n| " << law << " | " << kind.keyword << " | "
          << fixed(1e9 / (explicit_cost.steps_per_second * static_cast<double>(mesh->tetrahedra.size())), 0) << " ns, "
          << std::setprecision(3) << explicit_cost.time_step << " s | ";
      // A kind implicit Euler does not run yet (element_kind_limits) says why in both implicit columns.
      if (const char* refusal = element_kind_limits(kind.kind).implicit_euler) {
        out << refusal << " | - |";
        continue;
      }
      const Cost implicit_cost = step_cost(*mesh, law_index, kind.kind, Integrator::ImplicitEuler);
      const Cost direct_cost = step_cost(*mesh, law_index, kind.kind, Integrator::ImplicitEuler, ImplicitMethod::Direct);
      out << fixed(implicit_cost.steps_per_second, 0) << " (" << implicit_cost.solver << ") | "
          << fixed(direct_cost.steps_per_second, 0) << " |";
    }
  WARN("SOFA's liver held at vertices 3, 39, 64, nu 0.49, one thread, double, CPU time of the process:" << out.str());
}
