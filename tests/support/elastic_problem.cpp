#include "tests/support/elastic_problem.h"

#include "runtime/fem/element_law_registry.h"
#include "tests/support/volume_term.h"

#include <Eigen/Dense>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

#include "runtime/fem/fem_model_builder.h"
#include "runtime/integrate/static_equilibrium.h"
#include "runtime/scene/spring_model_builder.h"
#include "tests/support/volume_term.h"

namespace fmpc::testing {

const char* model_name(ProblemModel model) {
  switch (model) {
    case ProblemModel::CorotationalFem:
      return "co-rotational FEM";
    case ProblemModel::SpringsVanGelder:
      return "springs (Van Gelder)";
    case ProblemModel::SpringsLloyd:
      return "springs (Lloyd)";
    case ProblemModel::SpringsVolumeTerm:
      return "springs + volume term";
    case ProblemModel::QuadraticFem:
      return "quadratic FEM";
  }
  return "?";
}

namespace {

// The consistent nodal loads of problem.traction (ElasticProblem::traction_faces) added to `loads`: `edge_node(a,
// b)` is the node on the edge from vertex a to vertex b of a quadratic discretisation, -1 for a linear one.
template <typename EdgeNode>
void add_traction_loads(const ElasticProblem& problem, EdgeNode edge_node, std::vector<sim::Point3>& loads) {
  for (const sim::Triangle& face : problem.traction_faces) {
    const double third = sim::triangle_area(problem.mesh, face) / 3.0;
    for (std::size_t k = 0; k < 3; ++k) {
      const int on_edge = edge_node(face[k], face[(k + 1) % 3]);
      const auto node = static_cast<std::size_t>(on_edge < 0 ? face[k] : on_edge);
      for (std::size_t a = 0; a < 3; ++a) loads[node][a] += third * problem.traction[a];
    }
  }
}

std::pair<int, int> edge_key(int a, int b) { return {std::min(a, b), std::max(a, b)}; }

// The problem's supports, prescribed displacements and loads applied to a model's setup.
void apply_problem(const ElasticProblem& problem, sim::SimulationSetup& setup) {
  const std::size_t n = problem.mesh.points.size();
  setup.gravity = problem.gravity;
  setup.fixed_axes = problem.held;
  setup.external_forces = problem.forces;
  setup.precision = sim::Precision::Double;
  if (!problem.prescribed.empty()) {
    setup.initial_positions.assign(setup.rest_positions.begin(), setup.rest_positions.begin() + static_cast<std::ptrdiff_t>(n));
    for (std::size_t v = 0; v < n; ++v)
      for (int a = 0; a < 3; ++a)
        if ((problem.held[v] >> a) & 1u)
          setup.initial_positions[v][static_cast<std::size_t>(a)] += problem.prescribed[v][static_cast<std::size_t>(a)];
  }
  // A kind's added edge nodes follow their ends' supports and prescribed displacements (as the C3D10 deck's do).
  sim::extend_to_added_vertices(setup, n);
  if (!problem.traction_faces.empty()) {
    setup.external_forces.resize(setup.rest_positions.size(), sim::Point3{0.0, 0.0, 0.0});
    std::map<std::pair<int, int>, int> added;
    const auto& ends = setup.elements.geometry.added_vertex_ends;
    for (std::size_t i = 0; i < ends.size(); ++i) added[edge_key(ends[i][0], ends[i][1])] = static_cast<int>(n + i);
    add_traction_loads(
        problem, [&](int a, int b) { return added.empty() ? -1 : added.at(edge_key(a, b)); }, setup.external_forces);
  }
}

std::optional<ElasticAnswer> solve_setup(const ElasticProblem& problem, sim::SimulationSetup& setup,
                                         std::string& error) {
  DiagnosticList diagnostics;
  const std::size_t n = problem.mesh.points.size();
  apply_problem(problem, setup);
  sim::StaticOptions options;
  options.linear = true;
  const auto result = sim::static_equilibrium(setup, options, diagnostics);
  if (!result) {
    error = render_all(diagnostics, {});
    return std::nullopt;
  }
  ElasticAnswer answer;
  answer.displacement.resize(n);
  for (std::size_t v = 0; v < n; ++v)
    for (std::size_t i = 0; i < 3; ++i) answer.displacement[v][i] = result->positions[v][i] - setup.rest_positions[v][i];
  answer.nodes = setup.rest_positions;
  answer.reaction = result->reactions;
  return answer;
}

sim::MassSpec density_mass(const ElasticProblem& problem) {
  sim::MassSpec mass;
  mass.source = sim::MassSpec::Source::Density;
  mass.value = problem.density;
  return mass;
}

}  // namespace

namespace {

std::optional<sim::SimulationSetup> build_fem(const ElasticProblem& problem, int law, int kind, std::string& error) {
  DiagnosticList diagnostics;
  sim::FemModelSpec spec;
  spec.law = law;
  spec.element = kind;
  spec.youngs_modulus = {problem.youngs_modulus};
  spec.poisson_ratio = {problem.poisson_ratio};
  spec.mass = density_mass(problem);
  auto setup = sim::build_fem_model(problem.mesh, spec, diagnostics);
  if (!setup) error = render_all(diagnostics, {});
  return setup;
}

}  // namespace

std::optional<sim::SimulationSetup> fmpc_fem_setup(const ElasticProblem& problem, int law, int kind,
                                                   std::string& error) {
  auto setup = build_fem(problem, law, kind, error);
  if (setup) apply_problem(problem, *setup);
  return setup;
}

std::optional<ElasticAnswer> solve_with_fmpc_fem(const ElasticProblem& problem, int law, int kind, std::string& error) {
  auto setup = build_fem(problem, law, kind, error);
  if (!setup) return std::nullopt;
  return solve_setup(problem, *setup, error);
}

std::optional<ElasticAnswer> solve_with_fmpc(const ElasticProblem& problem, ProblemModel model, std::string& error) {
  if (model == ProblemModel::CorotationalFem || model == ProblemModel::QuadraticFem)
    return solve_with_fmpc_fem(problem, sim::default_fem_law().law,
                               model == ProblemModel::QuadraticFem ? sim::element_kind_by_keyword("quadratic")->kind
                                                                   : sim::default_element_kind().kind,
                               error);
  DiagnosticList diagnostics;
  sim::SpringModelSpec spec;
  spec.stiffness.mapping = model == ProblemModel::SpringsLloyd ? sim::StiffnessMapping::LloydSzekelyHarders2007
                                                               : sim::StiffnessMapping::VanGelder1998;
  spec.stiffness.value = problem.youngs_modulus;
  std::optional<sim::VolumeTermCalibration> calibration;
  if (model == ProblemModel::SpringsVolumeTerm) {
    calibration = sim::calibrate_volume_term(problem.youngs_modulus, problem.poisson_ratio,
                                             sim::StiffnessMapping::VanGelder1998, SourceRange{}, diagnostics);
    if (calibration) spec.stiffness.value = calibration->spring_modulus;
  }
  spec.mass = density_mass(problem);
  spec.damping.ratio = 0.0;
  auto setup = sim::build_spring_model(problem.mesh, spec, diagnostics);
  if (setup) {
    setup->tetrahedra = problem.mesh.tetrahedra;
    if (calibration && !sim::add_volume_term(*setup, calibration->bulk_modulus, 0.0, 0.0, diagnostics)) setup.reset();
  }
  if (!setup) {
    error = render_all(diagnostics, {});
    return std::nullopt;
  }
  return solve_setup(problem, *setup, error);
}

// `ccx -v` prints its version and exits 1, so its presence is what is checked.
bool calculix_available() { return std::system("command -v ccx > /dev/null 2>&1") == 0; }

// CalculiX reads each number of a card from its first 20 characters (Fortran's f20.0): longer text is cut there,
// which drops digits of 0.00029999999999999997 silently and makes -5.0000000000000009e-05 an error ("*ERROR
// reading *BOUNDARY"). Thirteen significant digits in scientific notation fill at most 20.
std::string calculix_number(double value) {
  std::ostringstream out;
  out << std::scientific;
  out.precision(12);
  out << value;
  return out.str();
}

std::map<int, sim::Point3> read_calculix_block(const std::string& dat, const std::string& header) {
  std::map<int, sim::Point3> out;
  std::istringstream in(dat);
  std::string line;
  bool inside = false, seen_data = false;
  while (std::getline(in, line)) {
    if (line.find(header) != std::string::npos) {
      inside = true;
      seen_data = false;
      continue;
    }
    if (!inside) continue;
    std::istringstream row(line);
    int node = 0;
    sim::Point3 value{};
    if (row >> node >> value[0] >> value[1] >> value[2]) {
      out[node] = value;
      seen_data = true;
    } else if (seen_data) {
      inside = false;
    }
  }
  return out;
}

std::optional<std::string> run_calculix(const std::string& deck, const std::filesystem::path& folder,
                                        std::string& error) {
  std::filesystem::create_directories(folder);
  {
    std::ofstream out(folder / "problem.inp");
    out << deck;
  }
  const std::string command = "cd '" + folder.string() + "' && OMP_NUM_THREADS=1 ccx -i problem > ccx.log 2>&1";
  if (std::system(command.c_str()) != 0) {
    error = "ccx failed; see " + (folder / "ccx.log").string();
    return std::nullopt;
  }
  std::ifstream in(folder / "problem.dat");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::optional<ElasticAnswer> solve_with_calculix(const ElasticProblem& problem, bool quadratic,
                                                 const std::filesystem::path& folder, std::string& error) {
  const std::size_t n = problem.mesh.points.size();
  if (quadratic && !problem.forces.empty()) {
    error = "C3D10 needs consistent loads; give this problem displacements, gravity or a traction";
    return std::nullopt;
  }
  // Nodes: the vertices, then (C3D10) one per edge, in the order edges are met.
  std::vector<sim::Point3> nodes = problem.mesh.points;
  std::vector<std::uint8_t> held = problem.held;
  std::vector<sim::Point3> prescribed = problem.prescribed.empty() ? std::vector<sim::Point3>(n, sim::Point3{0, 0, 0})
                                                                   : problem.prescribed;
  std::map<std::pair<int, int>, int> midside;
  std::vector<std::vector<int>> elements;
  for (const sim::Tetrahedron& t : problem.mesh.tetrahedra) {
    std::vector<int> element(t.begin(), t.end());
    if (quadratic) {
      // Abaqus / CalculiX C3D10 order: corners 1-4, then edges 1-2, 2-3, 3-1, 1-4, 2-4, 3-4.
      static const int edges[6][2] = {{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}};
      for (const auto& e : edges) {
        const int a = t[static_cast<std::size_t>(e[0])], b = t[static_cast<std::size_t>(e[1])];
        const auto key = edge_key(a, b);
        auto found = midside.find(key);
        if (found == midside.end()) {
          const auto ia = static_cast<std::size_t>(a), ib = static_cast<std::size_t>(b);
          nodes.push_back({(nodes[ia][0] + nodes[ib][0]) / 2, (nodes[ia][1] + nodes[ib][1]) / 2,
                           (nodes[ia][2] + nodes[ib][2]) / 2});
          held.push_back(static_cast<std::uint8_t>(held[ia] & held[ib]));
          prescribed.push_back({(prescribed[ia][0] + prescribed[ib][0]) / 2, (prescribed[ia][1] + prescribed[ib][1]) / 2,
                                (prescribed[ia][2] + prescribed[ib][2]) / 2});
          found = midside.emplace(key, static_cast<int>(nodes.size()) - 1).first;
        }
        element.push_back(found->second);
      }
    }
    elements.push_back(std::move(element));
  }
  std::ostringstream deck;
  deck << "*NODE, NSET=Nall\n";
  for (std::size_t v = 0; v < nodes.size(); ++v)
    deck << v + 1 << ", " << calculix_number(nodes[v][0]) << ", " << calculix_number(nodes[v][1]) << ", " << calculix_number(nodes[v][2]) << "\n";
  deck << "*ELEMENT, TYPE=" << (quadratic ? "C3D10" : "C3D4") << ", ELSET=Eall\n";
  for (std::size_t e = 0; e < elements.size(); ++e) {
    deck << e + 1;
    for (const int v : elements[e]) deck << ", " << v + 1;
    deck << "\n";
  }
  deck << "*NSET, NSET=Nheld\n";
  std::size_t held_count = 0;
  for (std::size_t v = 0; v < nodes.size(); ++v)
    if (held[v] != 0) deck << v + 1 << (++held_count % 16 == 0 ? "\n" : ", ");
  deck << "\n*MATERIAL, NAME=tissue\n";
  if (problem.neo_hooke) {
    const double mu = problem.youngs_modulus / (2 * (1 + problem.poisson_ratio));
    const double bulk = problem.youngs_modulus / (3 * (1 - 2 * problem.poisson_ratio));
    deck << "*HYPERELASTIC, NEO HOOKE\n" << calculix_number(mu / 2) << ", " << calculix_number(2 / bulk) << "\n";
  } else {
    deck << "*ELASTIC\n" << calculix_number(problem.youngs_modulus) << ", " << calculix_number(problem.poisson_ratio) << "\n";
  }
  deck << "*DENSITY\n" << calculix_number(problem.density) << "\n*SOLID SECTION, ELSET=Eall, MATERIAL=tissue\n";
  if (problem.neo_hooke) {
    const double increment = 1.0 / problem.increments;
    deck << "*STEP, NLGEOM, INC=" << 100 * problem.increments << "\n*STATIC\n" << calculix_number(increment) << ", 1.0, "
         << calculix_number(increment / 64) << ", " << calculix_number(increment) << "\n*BOUNDARY\n";
  } else {
    deck << "*STEP\n*STATIC\n*BOUNDARY\n";
  }
  for (std::size_t v = 0; v < nodes.size(); ++v)
    for (int a = 0; a < 3; ++a)
      if ((held[v] >> a) & 1u)
        deck << v + 1 << ", " << a + 1 << ", " << a + 1 << ", " << calculix_number(prescribed[v][static_cast<std::size_t>(a)])
             << "\n";
  const double g = std::sqrt(problem.gravity[0] * problem.gravity[0] + problem.gravity[1] * problem.gravity[1] +
                             problem.gravity[2] * problem.gravity[2]);
  if (g > 0.0)
    deck << "*DLOAD\nEall, GRAV, " << calculix_number(g) << ", " << calculix_number(problem.gravity[0] / g) << ", "
         << calculix_number(problem.gravity[1] / g) << ", " << calculix_number(problem.gravity[2] / g) << "\n";
  std::vector<sim::Point3> loads(nodes.size(), sim::Point3{0.0, 0.0, 0.0});
  std::copy(problem.forces.begin(), problem.forces.end(), loads.begin());
  add_traction_loads(
      problem, [&](int a, int b) { return quadratic ? midside.at(edge_key(a, b)) : -1; }, loads);
  if (!problem.forces.empty() || !problem.traction_faces.empty()) {
    deck << "*CLOAD\n";
    for (std::size_t v = 0; v < nodes.size(); ++v)
      for (std::size_t a = 0; a < 3; ++a)
        if (loads[v][a] != 0.0) deck << v + 1 << ", " << a + 1 << ", " << calculix_number(loads[v][a]) << "\n";
  }
  deck << "*NODE PRINT, NSET=Nall\nU\n*NODE PRINT, NSET=Nheld\nRF\n*END STEP\n";
  const auto dat = run_calculix(deck.str(), folder, error);
  if (!dat) return std::nullopt;
  const auto u = read_calculix_block(*dat, "displacements (vx,vy,vz)");
  const auto rf = read_calculix_block(*dat, "forces (fx,fy,fz)");
  if (u.size() != nodes.size()) {
    error = "ccx wrote " + std::to_string(u.size()) + " displacements for " + std::to_string(nodes.size()) + " nodes";
    return std::nullopt;
  }
  ElasticAnswer answer;
  answer.displacement.resize(n);
  answer.nodes = nodes;
  answer.reaction.assign(nodes.size(), sim::Point3{0.0, 0.0, 0.0});
  for (std::size_t v = 0; v < n; ++v) answer.displacement[v] = u.at(static_cast<int>(v) + 1);
  for (const auto& [node, force] : rf)
    if (node >= 1 && static_cast<std::size_t>(node) <= nodes.size()) answer.reaction[static_cast<std::size_t>(node) - 1] = force;
  return answer;
}

namespace {

// L(u) of the bonded layer (see hayes_kappa), written to stay finite for large u (divide by e^{2u}).
double layer_response(double u, double e) {
  if (u > 300.0) return 1.0;
  const double s = std::exp(-2.0 * u);
  // sinh 2u = (1 - s^2) / (2 s), cosh 2u = (1 + s^2) / (2 s); multiply numerator and denominator by 2 s.
  const double numerator = 2.0 * e * (1.0 - s * s) - 8.0 * u * s;
  const double denominator = 2.0 * e * (1.0 + s * s) + 2.0 * s * (1.0 + e * e + 4.0 * u * u);
  return numerator / denominator;
}

// Gauss-Legendre nodes and weights on [0, 1] (Golub-Welsch: eigenvalues of the Jacobi matrix).
void gauss_legendre(int count, std::vector<double>& x, std::vector<double>& w) {
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(count, count);
  for (int i = 1; i < count; ++i) J(i, i - 1) = J(i - 1, i) = i / std::sqrt(4.0 * i * i - 1.0);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(J);
  x.resize(static_cast<std::size_t>(count));
  w.resize(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) {
    x[static_cast<std::size_t>(i)] = 0.5 * (solver.eigenvalues()[i] + 1.0);
    const double v = solver.eigenvectors()(0, i);
    w[static_cast<std::size_t>(i)] = v * v;  // 2 v^2 on [-1, 1], halved for [0, 1]
  }
}

}  // namespace

double hayes_kappa(double a_over_h, double poisson_ratio) {
  const double e = 3.0 - 4.0 * poisson_ratio, tau = a_over_h;
  // k(z) = tau int_0^U (1 - L(u)) cos(tau u z) du; 1 - L decays like u e^{-2u}, so U = 40 leaves < 1e-30.
  std::vector<double> ux, uw;
  gauss_legendre(64, ux, uw);
  const int panels = 80;
  const double upper = 40.0, width = upper / panels;
  std::vector<double> u_nodes, u_weights;
  for (int p = 0; p < panels; ++p)
    for (std::size_t i = 0; i < ux.size(); ++i) {
      u_nodes.push_back((p + ux[i]) * width);
      u_weights.push_back(uw[i] * width * (1.0 - layer_response((p + ux[i]) * width, e)));
    }
  const auto k = [&](double z) {
    double sum = 0.0;
    for (std::size_t i = 0; i < u_nodes.size(); ++i) sum += u_weights[i] * std::cos(tau * u_nodes[i] * z);
    return tau * sum;
  };
  std::vector<double> x, w;
  gauss_legendre(48, x, w);
  const auto m = static_cast<Eigen::Index>(x.size());
  Eigen::MatrixXd A = Eigen::MatrixXd::Identity(m, m);
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = 0; j < m; ++j) {
      const double xi = x[static_cast<std::size_t>(i)], yj = x[static_cast<std::size_t>(j)];
      A(i, j) -= w[static_cast<std::size_t>(j)] * (k(xi - yj) + k(xi + yj)) / M_PI;
    }
  const Eigen::VectorXd phi = A.partialPivLu().solve(Eigen::VectorXd::Ones(m));
  double kappa = 0.0;
  for (Eigen::Index i = 0; i < m; ++i) kappa += w[static_cast<std::size_t>(i)] * phi[i];
  return kappa;
}

}  // namespace fmpc::testing
