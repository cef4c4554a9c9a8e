#pragma once
// Linear elastic static problems on a tetrahedral mesh, solved by fmpc's force models (the static solver, linear)
// and by CalculiX (Debian's calculix-ccx, a test-only reference like fuzzylite): C3D4 on the same mesh, or C3D10 with
// mid-edge nodes added (the quadratic element, for converged answers). Used by tests/unit/validation_test.cpp.
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "runtime/integrate/simulation.h"
#include "runtime/mesh/mesh.h"

namespace fmpc::testing {

struct ElasticProblem {
  sim::Mesh mesh;  // metres, positively oriented tetrahedra
  double youngs_modulus = 0.0;  // Pa
  double poisson_ratio = 0.0;
  double density = 0.0;  // kg/m^3
  sim::Point3 gravity{0.0, 0.0, 0.0};
  std::vector<std::uint8_t> held;        // per vertex: held axes, bit a for axis a
  std::vector<sim::Point3> prescribed;   // per vertex: the held axes' displacement (m); empty: zero
  std::vector<sim::Point3> forces;       // per vertex (N); empty: none (C3D10 refuses them: no consistent loads)
  // A uniform traction (Pa) on these boundary triangles of the mesh, applied as each element's consistent nodal
  // loads: A t / 3 at each corner of a linear face, A t / 3 at each edge node and none at the corners of a quadratic
  // one (the 6-node triangle's shape functions integrate to 0 at corners and 1/3 at mid-edges). Every element kind
  // and C3D4 / C3D10 get the same load this way.
  std::vector<sim::Triangle> traction_faces;
  sim::Point3 traction{0.0, 0.0, 0.0};
  // CalculiX: the compressible neo-Hookean material (*HYPERELASTIC, NEO HOOKE: W = C10 (J^-2/3 I_1 - 3) +
  // (J - 1)^2 / D1 with C10 = mu / 2 and D1 = 2 / K, the small-strain moduli of E and nu) solved with NLGEOM in
  // `increments` equal steps, instead of linear elasticity.
  bool neo_hooke = false;
  int increments = 10;
};

enum class ProblemModel {
  CorotationalFem,
  SpringsVanGelder,
  SpringsLloyd,
  SpringsVolumeTerm,  // Van Gelder springs with the volume term calibrated to the problem's Poisson ratio
  QuadraticFem,       // the co-rotational law on quadratic (10-node) tetrahedra: edge midpoints added
};
const char* model_name(ProblemModel model);

struct ElasticAnswer {
  std::vector<sim::Point3> displacement;  // m, per vertex of the problem's mesh (corners: not the added edge nodes)
  // Every node (the vertices, then C3D10's mid-edge nodes) and the force the supports exert on it (N; zero on free
  // axes): a quadratic element carries most of a face's force at its mid-edge nodes.
  std::vector<sim::Point3> nodes;
  std::vector<sim::Point3> reaction;
};

// fmpc's linear static solution (static_equilibrium with options.linear: the small-strain answer).
std::optional<ElasticAnswer> solve_with_fmpc(const ElasticProblem& problem, ProblemModel model, std::string& error);
// The same for `model: fem` with any law and element kind (their indices in runtime/fem/element_law_registry.h's
// rows), so that a table over the registry's rows gains a row when a law or kind is added.
std::optional<ElasticAnswer> solve_with_fmpc_fem(const ElasticProblem& problem, int law, int kind, std::string& error);
// The model solve_with_fmpc_fem solves, with the problem's supports, prescribed displacements and loads, in double
// (for timing its dynamics).
std::optional<sim::SimulationSetup> fmpc_fem_setup(const ElasticProblem& problem, int law, int kind,
                                                   std::string& error);

// Whether `ccx` runs here.
bool calculix_available();

// CalculiX's linear static solution in `folder`: C3D4 elements on the problem's mesh, or C3D10 (mid-edge nodes held
// where both ends are held on an axis, with the mean of their prescribed displacements). Reactions are CalculiX's
// RF, which leaves out loads applied at the held nodes themselves (zero for problems without gravity there).
std::optional<ElasticAnswer> solve_with_calculix(const ElasticProblem& problem, bool quadratic,
                                                 const std::filesystem::path& folder, std::string& error);

// CalculiX reads each number of a card from its first 20 characters: 13 significant digits in scientific notation.
std::string calculix_number(double value);
// Writes `deck` as folder/problem.inp, runs ccx on it (one thread) and returns its .dat file's text; nullopt with
// `error` naming the log when ccx fails.
std::optional<std::string> run_calculix(const std::string& deck, const std::filesystem::path& folder,
                                        std::string& error);
// The rows "node a b c" of a .dat file after the header line containing `header`, until a blank line after data.
std::map<int, sim::Point3> read_calculix_block(const std::string& dat, const std::string& header);

// Hayes, Keer, Herrmann & Mockros (1972), "A mathematical analysis for indentation tests of articular cartilage",
// J. Biomech. 5:541-551: a rigid flat-ended cylindrical punch of radius a pressed frictionlessly by delta into an
// elastic layer of thickness h bonded to a rigid base needs the force P = 2 a E delta / (1 - nu^2) kappa(a/h, nu).
// kappa is computed here, not taken from the paper's table: the layer's surface response under a pressure of Hankel
// transform p(xi) is w(xi) = 2 (1 - nu^2) / E p(xi) / xi L(xi h), L(u) = (2 e sinh 2u - 4u) / (2 e cosh 2u + 1 +
// e^2 + 4u^2), e = 3 - 4 nu, and the punch reduces to the Fredholm equation phi(x) - 1/pi int_0^1 [k(x - y) + k(x +
// y)] phi(y) dy = 1 with k(z) = tau int_0^inf (1 - L(u)) cos(tau u z) du, tau = a/h, kappa = int_0^1 phi (solved by
// Nystroem's method on Gauss-Legendre points). Its limits are checked by the tests: kappa -> 1 as a/h -> 0
// (Sneddon's half-space punch) and kappa -> (pi/2) (a/h) (1 - nu^2) M / E for a thin compressible layer (confined
// compression, M the oedometric modulus).
double hayes_kappa(double a_over_h, double poisson_ratio);

}  // namespace fmpc::testing
