// The stable neo-Hookean law (issue 26, item 2; kernels/laws/stable_neo_hookean.h): its stress against the paper's
// formula written apart, its energy (with the log computed from +, -, *, /) against std::log, its projected Hessian
// against the numerically projected Hessian of its own stress, finite and restoring stresses for inverted, flat and
// collapsed elements, the co-rotational law in the small-strain limit, and the finite-element solution of
// homogeneous deformations (uniaxial stretch, compression to 50 %, simple shear) against the analytic stress-stretch
// curves. docs/validation.md records the printed numbers.
#include <Eigen/Dense>
#include <catch2/catch.hpp>
#include <cmath>
#include <optional>
#include <random>
#include <sstream>
#include <vector>

#include "kernels/element_laws.h"
#include "runtime/fem/element_law_registry.h"
#include "runtime/fem/fem_model_builder.h"
#include "runtime/integrate/static_equilibrium.h"
#include "runtime/mesh/generated_mesh.h"
#include "tests/support/elastic_problem.h"
#include "tests/support/generated_program.h"

using namespace fmpc;
using namespace fmpc::sim;

namespace {

using Law = kernels::StableNeoHookean;
using Matrix3 = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;
using Matrix9 = Eigen::Matrix<double, 9, 9>;

constexpr double kE = 5000.0;

Law::Material<double> material(double nu) {
  return Law::Material<double>{kE, nu, 0.0, kernels::StrainTableView{nullptr, nullptr, 0}};
}

// The paper's parameters (Smith, de Goes & Kim 2018, section 3.4 and eq. 14), written apart from the header.
struct Paper {
  double mu_s, lambda_s, alpha;
  explicit Paper(double nu) {
    const double mu = kE / (2 * (1 + nu)), lambda = kE * nu / ((1 + nu) * (1 - 2 * nu));
    mu_s = 4.0 / 3.0 * mu;
    lambda_s = lambda + 5.0 / 6.0 * mu;
    alpha = 1 + 3 * mu_s / (4 * lambda_s);
  }
  // cof(F): columns c2 x c3, c3 x c1, c1 x c2 of F's columns.
  static Matrix3 cofactor(const Matrix3& F) {
    Matrix3 C;
    for (int j = 0; j < 3; ++j) C.col(j) = F.col((j + 1) % 3).cross(F.col((j + 2) % 3));
    return C;
  }
  Matrix3 piola(const Matrix3& F) const {
    const double ic = F.squaredNorm();
    return mu_s * (1 - 1 / (ic + 1)) * F + lambda_s * (F.determinant() - alpha) * cofactor(F);
  }
  double energy(const Matrix3& F) const {
    const auto psi = [&](const Matrix3& G) {
      const double ic = G.squaredNorm(), J = G.determinant();
      return mu_s / 2 * (ic - 3) + lambda_s / 2 * (J - alpha) * (J - alpha) - mu_s / 2 * std::log(ic + 1);
    };
    return psi(F) - psi(Matrix3::Identity());
  }
};

Matrix3 law_piola(const Matrix3& F, double nu) {
  Matrix3 P;
  Law::first_piola(material(nu), F.data(), static_cast<const double*>(nullptr), P.data());
  return P;
}

// The law's projected tangent as a 9 x 9 matrix on row-major dF.
Matrix9 law_tangent(const Matrix3& F, double nu) {
  Law::Linearisation lin{};
  Law::linearise(material(nu), F.data(), lin);
  Matrix9 A;
  for (int c = 0; c < 9; ++c) {
    double dF[9] = {}, dP[9];
    dF[c] = 1.0;
    Law::stress_differential(material(nu), lin, dF, dP);
    for (int r = 0; r < 9; ++r) A(r, c) = dP[r];
  }
  return A;
}

// The Hessian of the energy: central differences of the law's own P, symmetrised.
Matrix9 numerical_hessian(const Matrix3& F, double nu) {
  Matrix9 H;
  const double h = 1e-6 * std::max(1.0, F.norm());
  for (int c = 0; c < 9; ++c) {
    Matrix3 plus = F, minus = F;
    plus.data()[c] += h;
    minus.data()[c] -= h;
    const Matrix3 dP = (law_piola(plus, nu) - law_piola(minus, nu)) / (2 * h);
    for (int r = 0; r < 9; ++r) H(r, c) = dP.data()[r];
  }
  return (H + H.transpose()) / 2;
}

// Its positive semi-definite part: negative eigenvalues set to zero.
Matrix9 projected(const Matrix9& H) {
  Eigen::SelfAdjointEigenSolver<Matrix9> eigen(H);
  return eigen.eigenvectors() * eigen.eigenvalues().cwiseMax(0.0).asDiagonal() * eigen.eigenvectors().transpose();
}

Matrix3 random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  Eigen::Quaterniond q(normal(rng), normal(rng), normal(rng), normal(rng));
  q.normalize();
  return q.toRotationMatrix();
}

}  // namespace

TEST_CASE("stable neo-Hookean: P is the paper's, the energy its potential, log from +-*/ matches std::log1p",
          "[fem][snh]") {
  std::mt19937_64 rng(2018);
  std::normal_distribution<double> normal(0.0, 0.3);
  for (const double nu : {0.0, 0.3, 0.45, 0.499})
    for (int n = 0; n < 200; ++n) {
      Matrix3 F = Matrix3::Identity();
      for (int i = 0; i < 9; ++i) F.data()[i] += normal(rng);
      if (n % 3 == 0) F.col(2) *= -1.0;  // inverted
      const Paper paper(nu);
      const Matrix3 P = law_piola(F, nu);
      INFO("nu " << nu << ", F " << F);
      CHECK((P - paper.piola(F)).norm() <= 1e-13 * kE * (1 + F.squaredNorm()) * (1 + F.norm()));
      const double W = Law::energy_density(material(nu), F.data());
      CHECK(std::abs(W - paper.energy(F)) <= 1e-12 * kE * (1 + F.squaredNorm()) * (1 + F.squaredNorm()));
    }
  // log(1 + x) within 2 ulp of the C library's, from near -1 through tiny to large arguments.
  std::vector<double> arguments;
  for (double k = -300; k <= 12; k += 0.0731) {
    arguments.push_back(std::pow(10.0, k));
    if (k < 0) arguments.push_back(-std::pow(10.0, k));
    if (k < -1e-9 && k > -16) arguments.push_back(std::pow(10.0, k) - 1.0);
  }
  double worst = 0.0;
  for (const double x : arguments) {
    const double exact = std::log1p(x), ours = Law::log_one_plus(x);
    worst = std::max(worst, std::abs(ours - exact) / std::abs(exact));
  }
  CHECK(Law::log_one_plus(0.0) == 0.0);
  CHECK(worst <= 4.5e-16);
  WARN("log_one_plus: worst relative difference from std::log1p " << worst);
}

TEST_CASE("stable neo-Hookean: the tangent is the energy's Hessian projected to positive semi-definite", "[fem][snh]") {
  std::mt19937_64 rng(37);
  std::normal_distribution<double> normal(0.0, 0.35);
  double worst = 0.0;
  int clamped = 0;
  for (const double nu : {0.2, 0.45, 0.499})
    for (int n = 0; n < 60; ++n) {
      Matrix3 F = Matrix3::Identity();
      for (int i = 0; i < 9; ++i) F.data()[i] += normal(rng);
      if (n % 4 == 0) F.col(0) *= -1.0;            // inverted
      if (n % 10 == 5) F.col(1) = 0.5 * F.col(2);  // flat
      if (n == 7) F = 0.5 * random_rotation(rng);  // uniform compression to half
      if (n == 8) F = Matrix3::Identity();         // rest
      if (n == 9) F = random_rotation(rng);        // rotated rest
      const Matrix9 H = numerical_hessian(F, nu), A = law_tangent(F, nu), expected = projected(H);
      const double scale = H.norm() + 1.0;
      INFO("nu " << nu << ", F " << F);
      CHECK((A - A.transpose()).cwiseAbs().maxCoeff() <= 1e-12 * scale);
      Eigen::SelfAdjointEigenSolver<Matrix9> eigen((A + A.transpose()) / 2);
      CHECK(eigen.eigenvalues().minCoeff() >= -1e-12 * scale);
      const double difference = (A - expected).norm() / scale;
      CHECK(difference <= 1e-6);
      worst = std::max(worst, difference);
      clamped += Eigen::SelfAdjointEigenSolver<Matrix9>(H).eigenvalues().minCoeff() < -1e-6 * scale ? 1 : 0;
    }
  CHECK(clamped > 0);  // the sample reaches states whose Hessian is indefinite
  WARN("stable neo-Hookean tangent: worst |A - proj(H)| / |H| = " << worst);
}

TEST_CASE("stable neo-Hookean: inverted, flat and collapsed elements get finite, restoring stresses", "[fem][snh]") {
  std::mt19937_64 rng(12);
  for (const double nu : {0.0, 0.45, 0.499})
    for (int n = 0; n < 100; ++n) {
      // det F <= 0: a random rotation pair around diag(s1, s2, -s3) (inverted) or diag(s1, s2, 0) (flat).
      std::uniform_real_distribution<double> stretch(0.05, 2.0);
      const Matrix3 F = random_rotation(rng) *
                        Eigen::Vector3d(stretch(rng), stretch(rng), n % 5 == 0 ? 0.0 : -stretch(rng)).asDiagonal() *
                        random_rotation(rng);
      const Matrix3 P = law_piola(F, nu);
      INFO("nu " << nu << ", F " << F);
      REQUIRE(P.allFinite());
      CHECK(std::isfinite(Law::energy_density(material(nu), F.data())));
      // Moving along dJ/dF = cof(F) raises J and lowers the energy: P : cof(F) < 0.
      CHECK((P.array() * Paper::cofactor(F).array()).sum() < 0.0);
      CHECK(law_tangent(F, nu).allFinite());
    }
  // Collapsed to a point or a line: finite, and the line is pushed apart.
  const Matrix3 point = Matrix3::Zero();
  CHECK(law_piola(point, 0.45).allFinite());
  CHECK(law_tangent(point, 0.45).allFinite());
  CHECK(Law::energy_density(material(0.45), point.data()) > 0.0);
  // An inverted tetrahedron on its own: its corner forces raise its signed volume.
  const double rest[4][3] = {{0, 0, 0}, {0.01, 0, 0}, {0, 0.01, 0}, {0, 0, 0.01}};
  double inverse[9] = {100, 0, 0, 0, 100, 0, 0, 0, 100};
  double volume = kernels::tetrahedron_volume(rest);
  const std::int32_t nodes[4] = {0, 1, 2, 3};
  std::vector<double> youngs = {kE}, poisson = {0.45};
  kernels::ElementTermView<double> view{};
  view.law = kernels::element_law_index<Law>;
  view.count = 1;
  view.corners = nodes;
  view.corner_slot = nodes;
  view.rest_inverse = inverse;
  view.rest_volume = &volume;
  view.parameter[Law::kYoungsModulus] = youngs.data();
  view.parameter[Law::kPoissonRatio] = poisson.data();
  double x[4][3] = {{0, 0, 0}, {0.01, 0, 0}, {0, 0.01, 0}, {0.001, 0.002, -0.004}}, f[4][3];
  REQUIRE(kernels::tetrahedron_volume(x) < 0.0);
  kernels::LinearTetrahedron::forces<Law>(view, 0, x, static_cast<const double(*)[3]>(nullptr), f);
  double rate = 0.0;  // dV/dt under velocities f: sum_a f_a . dV/dx_a
  const double h = 1e-9;
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i) {
      double moved[4][3];
      std::copy(&x[0][0], &x[0][0] + 12, &moved[0][0]);
      moved[a][i] += h;
      rate += f[a][i] * (kernels::tetrahedron_volume(moved) - kernels::tetrahedron_volume(x)) / h;
    }
  CHECK(rate > 0.0);
}

TEST_CASE("stable neo-Hookean equals the co-rotational law in the small-strain limit", "[fem][snh]") {
  std::mt19937_64 rng(4);
  std::normal_distribution<double> normal;
  using Corotational = kernels::CorotationalLinear;
  const Corotational::Material<double> linear{kE, 0.45, 0.0, kernels::StrainTableView{nullptr, nullptr, 0}};
  double ratio_at[2] = {0.0, 0.0};
  for (int n = 0; n < 50; ++n) {
    const Matrix3 R = random_rotation(rng);
    Matrix3 G;
    for (int i = 0; i < 9; ++i) G.data()[i] = normal(rng);
    for (int k = 0; k < 2; ++k) {
      const double strain = k == 0 ? 1e-4 : 1e-5;  // times |G| (about 3): the strain's size
      const Matrix3 F = R * (Matrix3::Identity() + strain * G);
      Matrix3 expected;
      Corotational::first_piola(linear, F.data(), static_cast<const double*>(nullptr), expected.data());
      ratio_at[k] = std::max(ratio_at[k], (law_piola(F, 0.45) - expected).norm() / expected.norm());
    }
  }
  // The difference is second order: relative to the stress, it falls with the strain.
  CHECK(ratio_at[0] < 2e-3);
  CHECK(ratio_at[1] < 2e-4);
  CHECK(ratio_at[1] < 0.2 * ratio_at[0]);
  // At rest (also rotated) the tangents are the same.
  for (const Matrix3& F : {Matrix3(Matrix3::Identity()), Matrix3(random_rotation(rng))}) {
    Corotational::Linearisation corotated{};
    Corotational::linearise(linear, F.data(), corotated);
    Matrix9 expected;
    for (int c = 0; c < 9; ++c) {
      double dF[9] = {}, dP[9];
      dF[c] = 1.0;
      Corotational::stress_differential(linear, corotated, dF, dP);
      for (int r = 0; r < 9; ++r) expected(r, c) = dP[r];
    }
    CHECK((law_tangent(F, 0.45) - expected).norm() <= 1e-12 * expected.norm());
  }
  WARN("stable neo-Hookean against co-rotational: |dP| / |P| <= " << ratio_at[0] << " at strain 1e-4, " << ratio_at[1]
                                                                  << " at 1e-5");
}

namespace {

// A homogeneous problem on a box of 2 cm, 4^3 cells: for a stretch, the nominal traction P N of the target F on every
// boundary triangle as consistent nodal forces (a third of its area to each corner), three vertices held against
// rigid motion where (F - I) X is zero on their held axes; for a shear, the boundary moved to F X. The static
// solver's answer is compared with (F - I) X.
// Returns max |u - (F - I) X| / max |(F - I) X|.
double homogeneous_error(const Matrix3& target, double nu, std::ostringstream& log) {
  const double L = 0.02;
  DiagnosticList diagnostics;
  BoxSpec box;
  box.size = {L, L, L};
  box.cells_x = box.cells_y = box.cells_z = 4;
  const Mesh mesh = generate_box(box, diagnostics);
  FemModelSpec spec;
  spec.law = kernels::element_law_index<Law>;
  spec.youngs_modulus = {kE};
  spec.poisson_ratio = {nu};
  spec.mass.source = MassSpec::Source::Density;
  spec.mass.value = 1000.0;
  auto setup = build_fem_model(mesh, spec, diagnostics);
  INFO(render_all(diagnostics, {}));
  REQUIRE(setup);
  const std::size_t n = mesh.points.size();
  setup->fixed_axes.assign(n, 0);
  for (std::size_t v = 0; v < n; ++v) {
    const Point3& X = mesh.points[v];
    const bool x0 = X[0] == 0.0, y0 = X[1] == 0.0, z0 = X[2] == 0.0;
    if (x0 && y0 && z0) setup->fixed_axes[v] = 7;             // the origin: u = 0
    if (X[0] == L && y0 && z0) setup->fixed_axes[v] = 2 | 4;  // (L, 0, 0): u_y = u_z = 0 (F_21 = F_31 = 0)
    if (x0 && y0 && X[2] == L) setup->fixed_axes[v] = 2;      // (0, 0, L): u_y = 0 (F_23 = 0)
  }
  setup->precision = Precision::Double;
  const std::vector<Triangle> boundary = boundary_triangles(mesh);
  const bool diagonal = (target - Matrix3(target.diagonal().asDiagonal())).norm() == 0.0;
  std::optional<StaticResult> result;
  if (diagonal) {
    const Matrix3 P = Paper(nu).piola(target);
    setup->external_forces.assign(n, Point3{0, 0, 0});
    for (const Triangle& t : boundary) {
      Eigen::Vector3d normal = Eigen::Vector3d::Zero();
      for (std::size_t axis = 0; axis < 3; ++axis) {
        bool low = true, high = true;
        for (const auto v : t) {
          low = low && std::abs(mesh.points[static_cast<std::size_t>(v)][axis]) < 1e-12;
          high = high && std::abs(mesh.points[static_cast<std::size_t>(v)][axis] - L) < 1e-12;
        }
        if (low) normal[static_cast<Eigen::Index>(axis)] = -1.0;
        if (high) normal[static_cast<Eigen::Index>(axis)] = 1.0;
      }
      REQUIRE(normal.norm() == 1.0);
      const Eigen::Vector3d force = P * normal * triangle_area(mesh, t) / 3.0;
      for (const auto v : t)
        for (std::size_t i = 0; i < 3; ++i)
          setup->external_forces[static_cast<std::size_t>(v)][i] += force[static_cast<Eigen::Index>(i)];
    }
  } else {
    // A shear under dead tractions is unstable (a rotation lowers the loads' potential): its boundary is moved to
    // (F - I) X instead, and the interior vertices must find the homogeneous state.
    setup->initial_positions = setup->rest_positions;
    for (std::size_t v = 0; v < n; ++v) {
      const Point3& X = mesh.points[v];
      bool on_boundary = false;
      for (std::size_t axis = 0; axis < 3; ++axis)
        on_boundary = on_boundary || X[axis] == 0.0 || std::abs(X[axis] - L) < 1e-12;
      if (!on_boundary) continue;
      setup->fixed_axes[v] = 7;
      const Eigen::Vector3d moved = target * Eigen::Vector3d(X[0], X[1], X[2]);
      for (std::size_t i = 0; i < 3; ++i) setup->initial_positions[v][i] = moved[static_cast<Eigen::Index>(i)];
    }
  }
  // Newton on the projected tangent stalls at a few 1e-10 of the load on this mesh (measured 1.2e-9 N of 2.8 N for the
  // stretch to 1.3): 1e-8 of it, far below the displacement error checked.
  StaticOptions options;
  options.tolerance = 1e-8;
  result = static_equilibrium(*setup, options, diagnostics);
  INFO(render_all(diagnostics, {}));
  REQUIRE(result);
  const int iterations = result->iterations;
  double largest = 0.0, error = 0.0;
  for (std::size_t v = 0; v < n; ++v) {
    const Eigen::Vector3d X(mesh.points[v][0], mesh.points[v][1], mesh.points[v][2]);
    const Eigen::Vector3d expected = (target - Matrix3::Identity()) * X;
    const Eigen::Vector3d got(result->positions[v][0] - X[0], result->positions[v][1] - X[1],
                              result->positions[v][2] - X[2]);
    largest = std::max(largest, expected.norm());
    error = std::max(error, (got - expected).norm());
  }
  log << " " << iterations << " Newton steps, error " << error / largest;
  return error / largest;
}

// The uniaxial-stress curve: stretch s along z, lateral stretch t with P_xx = 0, i.e.
// mu' (1 - 1/(I_C + 1)) t + lambda' (s t^2 - alpha) s t = 0 with I_C = s^2 + 2 t^2, solved by bisection
// (P_xx / t rises monotonically with t).
double lateral_stretch(double s, double nu) {
  const Paper paper(nu);
  const auto g = [&](double t) {
    return paper.mu_s * (1 - 1 / (s * s + 2 * t * t + 1)) + paper.lambda_s * (s * t * t - paper.alpha) * s;
  };
  double low = 1e-3, high = 10.0;
  REQUIRE(g(low) < 0.0);
  REQUIRE(g(high) > 0.0);
  for (int i = 0; i < 200; ++i) {
    const double middle = (low + high) / 2;
    (g(middle) < 0.0 ? low : high) = middle;
  }
  return (low + high) / 2;
}

}  // namespace

TEST_CASE("stable neo-Hookean FEM in homogeneous deformations equals the analytic stress-stretch curves",
          "[fem][snh][validation]") {
  std::ostringstream log;
  for (const double nu : {0.3, 0.45}) {
    for (const double s : {1.3, 0.7, 0.5}) {
      const double t = lateral_stretch(s, nu);
      Matrix3 F = Matrix3::Identity();
      F(0, 0) = F(1, 1) = t;
      F(2, 2) = s;
      const Matrix3 P = Paper(nu).piola(F);
      CHECK(std::abs(P(0, 0)) < 1e-9 * std::abs(P(2, 2)));
      log << "\n  nu " << nu << ", uniaxial stretch " << s << ": lateral " << t << ", P_zz " << P(2, 2) << " Pa;";
      CHECK(homogeneous_error(F, nu, log) < 1e-6);
    }
    Matrix3 shear = Matrix3::Identity();
    shear(0, 1) = 0.5;
    log << "\n  nu " << nu << ", simple shear 0.5: P_xy " << Paper(nu).piola(shear)(0, 1) << " Pa;";
    CHECK(homogeneous_error(shear, nu, log) < 1e-6);
  }
  WARN("stable neo-Hookean, homogeneous deformations on a 4 x 4 x 4-cell box (384 tetrahedra):" << log.str());
}

namespace {

// CalculiX's compressible neo-Hookean (NEO HOOKE with C10 = mu / 2, D1 = 2 / K):
// P = mu J^-2/3 (F - I_1 / 3 F^-T) + K (J - 1) J F^-T.
Matrix3 calculix_neo_hooke_piola(const Matrix3& F, double nu) {
  const double mu = kE / (2 * (1 + nu)), bulk = kE / (3 * (1 - 2 * nu));
  const double J = F.determinant(), i1 = F.squaredNorm();
  const Matrix3 inverse_transpose = F.inverse().transpose();
  return mu * std::pow(J, -2.0 / 3.0) * (F - i1 / 3 * inverse_transpose) + bulk * (J - 1) * J * inverse_transpose;
}

// The uniaxial stress curve of a law: P_zz at stretch s with the lateral stretch that makes P_xx zero (bisection).
template <typename Piola>
double uniaxial_stress(double s, Piola piola) {
  const auto lateral = [&](double t) {
    Matrix3 F = Matrix3::Identity();
    F(0, 0) = F(1, 1) = t;
    F(2, 2) = s;
    return F;
  };
  double low = 0.3, high = 3.0;
  REQUIRE(piola(lateral(low))(0, 0) < 0.0);
  REQUIRE(piola(lateral(high))(0, 0) > 0.0);
  for (int i = 0; i < 200; ++i) {
    const double middle = (low + high) / 2;
    (piola(lateral(middle))(0, 0) < 0.0 ? low : high) = middle;
  }
  return piola(lateral((low + high) / 2))(2, 2);
}

// A box of nx x ny x nz cells with E = kE, nothing held or moved yet, for CalculiX's NEO HOOKE (10 increments).
testing::ElasticProblem neo_hooke_block(Point3 size, int nx, int ny, int nz, double nu) {
  testing::ElasticProblem p;
  BoxSpec box;
  box.size = size;
  box.cells_x = nx;
  box.cells_y = ny;
  box.cells_z = nz;
  DiagnosticList diagnostics;
  p.mesh = generate_box(box, diagnostics);
  p.youngs_modulus = kE;
  p.poisson_ratio = nu;
  p.density = 1000.0;
  p.neo_hooke = true;
  p.held.assign(p.mesh.points.size(), 0);
  p.prescribed.assign(p.mesh.points.size(), Point3{0, 0, 0});
  return p;
}

// Whether ccx is missing, after saying so (the CalculiX cases skip visibly).
bool calculix_missing() {
  if (testing::calculix_available()) return false;
  WARN("skipped: CalculiX (ccx, Debian's calculix-ccx) is not installed; tools/run installs it");
  return true;
}

// fmpc's stable neo-Hookean static solution of `problem` (held axes moved by `prescribed`), loaded in `increments`
// equal steps, each from the last one's answer.
std::vector<Point3> fmpc_stable_neo_hookean(const testing::ElasticProblem& problem, int increments,
                                            std::vector<Point3>& reactions) {
  DiagnosticList diagnostics;
  FemModelSpec spec;
  spec.law = kernels::element_law_index<Law>;
  spec.youngs_modulus = {problem.youngs_modulus};
  spec.poisson_ratio = {problem.poisson_ratio};
  spec.mass.source = MassSpec::Source::Density;
  spec.mass.value = problem.density;
  auto setup = build_fem_model(problem.mesh, spec, diagnostics);
  REQUIRE(setup);
  setup->fixed_axes = problem.held;
  setup->precision = Precision::Double;
  std::vector<Point3> x = setup->rest_positions;
  for (int k = 1; k <= increments; ++k) {
    setup->initial_positions = x;
    for (std::size_t v = 0; v < x.size(); ++v)
      for (std::size_t a = 0; a < 3; ++a)
        if ((problem.held[v] >> a) & 1u)
          setup->initial_positions[v][a] = setup->rest_positions[v][a] + problem.prescribed[v][a] * k / increments;
    StaticOptions options;
    options.tolerance = 1e-11;
    const auto result = static_equilibrium(*setup, options, diagnostics);
    INFO("increment " << k << ": " << render_all(diagnostics, {}));
    REQUIRE(result);
    x = result->positions;
    reactions = result->reactions;
  }
  return x;
}

}  // namespace

TEST_CASE("stable neo-Hookean against CalculiX's NEO HOOKE with NLGEOM: a cube compressed by 30 %",
          "[fem][snh][validation]") {
  if (calculix_missing()) return;
  const double nu = 0.45;
  std::ostringstream table;
  {
    // A 1 cm cube, 2^3 cells, its x = 0, y = 0 and z = 0 faces sliding on their planes, its top face pushed down 3 mm
    // (also sliding): homogeneous uniaxial stress, so each code's reaction is its law's uniaxial curve at s = 0.7.
    const double L = 0.01;
    testing::ElasticProblem p = neo_hooke_block({L, L, L}, 2, 2, 2, nu);
    for (std::size_t v = 0; v < p.mesh.points.size(); ++v) {
      for (std::size_t a = 0; a < 3; ++a)
        if (p.mesh.points[v][a] == 0.0) p.held[v] = static_cast<std::uint8_t>(p.held[v] | (1u << a));
      if (std::abs(p.mesh.points[v][2] - L) < 1e-12) {
        p.held[v] = static_cast<std::uint8_t>(p.held[v] | 4u);
        p.prescribed[v][2] = -0.3 * L;
      }
    }
    testing::ScratchFolder folder("ccx_snh_cube");
    std::string error;
    const auto calculix = testing::solve_with_calculix(p, false, folder.path(), error);
    INFO(error);
    REQUIRE(calculix);
    std::vector<Point3> reactions;
    fmpc_stable_neo_hookean(p, 10, reactions);
    double ours = 0.0, theirs = 0.0;
    for (std::size_t v = 0; v < p.mesh.points.size(); ++v)
      if (std::abs(p.mesh.points[v][2] - L) < 1e-12) {
        ours += reactions[v][2];
        theirs += calculix->reaction[v][2];
      }
    const double area = L * L;
    const double snh = uniaxial_stress(0.7, [&](const Matrix3& F) { return Paper(nu).piola(F); }) * area;
    const double nh = uniaxial_stress(0.7, [&](const Matrix3& F) { return calculix_neo_hooke_piola(F, nu); }) * area;
    // The supports' forces on the top face, summed: the nominal stress P_zz (negative in compression) times its area.
    CHECK(std::abs(ours / snh - 1) < 1e-6);
    CHECK(std::abs(theirs / nh - 1) < 1e-4);
    const double predicted = snh / nh - 1, measured = ours / theirs - 1;
    CHECK(std::abs(measured - predicted) < 2e-4);
    table << "\n  cube to 70 % (uniaxial, sliding faces): fmpc " << ours << " N (its curve " << snh << "), CalculiX "
          << theirs << " N (its curve " << nh << "): difference " << measured * 100 << " %, the laws predict "
          << predicted * 100 << " %";
  }
  WARN("stable neo-Hookean against CalculiX NEO HOOKE (NLGEOM), nu = " << nu << ":" << table.str());
}

namespace {

// CalculiX's NEO HOOKE energy density with C10 = mu / 2, D1 = 2 / K: W = mu / 2 (J^-2/3 I_1 - 3) + K / 2 (J - 1)^2.
double calculix_neo_hooke_energy(const Matrix3& F, double nu) {
  const double mu = kE / (2 * (1 + nu)), bulk = kE / (3 * (1 - 2 * nu));
  const double J = F.determinant();
  return mu / 2 * (std::pow(J, -2.0 / 3.0) * F.squaredNorm() - 3) + bulk / 2 * (J - 1) * (J - 1);
}

// The stored energy of the deformed mesh (vertex positions x): the sum over its linear tetrahedra of V W(F), F = Ds
// Dm^-1 constant in each (C3D4 is the same element).
template <typename Energy>
double stored_energy(const Mesh& mesh, const std::vector<Point3>& x, Energy energy) {
  double total = 0.0;
  for (const Tetrahedron& t : mesh.tetrahedra) {
    Matrix3 rest, deformed;
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) {
        const auto a = static_cast<std::size_t>(t[0]), b = static_cast<std::size_t>(t[static_cast<std::size_t>(c + 1)]);
        rest(r, c) = mesh.points[b][static_cast<std::size_t>(r)] - mesh.points[a][static_cast<std::size_t>(r)];
        deformed(r, c) = x[b][static_cast<std::size_t>(r)] - x[a][static_cast<std::size_t>(r)];
      }
    total += rest.determinant() / 6 * energy(Matrix3(deformed * rest.inverse()));
  }
  return total;
}

}  // namespace

TEST_CASE("stable neo-Hookean against CalculiX's NEO HOOKE with NLGEOM: a 20 % indentation",
          "[fem][snh][validation][heavy]") {
  if (calculix_missing()) return;
  // A 2 x 2 x 1 cm block of 6 x 6 x 3 cells (648 linear tetrahedra, C3D4 in CalculiX), its base clamped; the 3 x 3
  // top vertices of its middle third (a 6.7 mm square punch) pushed down by 2 mm, 20 % of the height, free to slide
  // sideways (a frictionless flat punch by prescribed displacement).
  const double nu = 0.45, W = 0.02, H = 0.01, depth = 0.2 * H;
  testing::ElasticProblem p = neo_hooke_block({W, W, H}, 6, 6, 3, nu);
  std::vector<std::size_t> punch;
  for (std::size_t v = 0; v < p.mesh.points.size(); ++v) {
    const Point3& x = p.mesh.points[v];
    if (x[2] < 1e-12) p.held[v] = 7u;
    const bool middle = x[0] > W / 3 - 1e-12 && x[0] < 2 * W / 3 + 1e-12 && x[1] > W / 3 - 1e-12 && x[1] < 2 * W / 3 + 1e-12;
    if (std::abs(x[2] - H) < 1e-12 && middle) {
      p.held[v] = 4u;
      p.prescribed[v][2] = -depth;
      punch.push_back(v);
    }
  }
  REQUIRE(punch.size() == 9);
  const auto snh_energy = [&](const Matrix3& F) { return Paper(nu).energy(F); };
  const auto nh_energy = [&](const Matrix3& F) { return calculix_neo_hooke_energy(F, nu); };
  const auto punch_force = [&](const std::vector<Point3>& reaction) {
    double sum = 0.0;
    for (const std::size_t v : punch) sum += reaction[v][2];
    return sum;
  };

  testing::ScratchFolder folder("ccx_snh_indentation");
  std::string error;
  const auto calculix = testing::solve_with_calculix(p, false, folder.path(), error);
  INFO(error);
  REQUIRE(calculix);
  std::vector<Point3> x_nh(p.mesh.points.size());
  for (std::size_t v = 0; v < x_nh.size(); ++v)
    for (std::size_t a = 0; a < 3; ++a) x_nh[v][a] = p.mesh.points[v][a] + calculix->displacement[v][a];
  // fmpc at the depth and 1 % either side of it (the energies' derivative in the depth is the punch force).
  std::vector<Point3> reactions;
  const std::vector<Point3> x_snh = fmpc_stable_neo_hookean(p, 10, reactions);
  const double force_snh = punch_force(reactions), force_nh = punch_force(calculix->reaction);
  const double h = 0.01;
  double nh_at_snh_state[2];
  for (int side = 0; side < 2; ++side) {
    testing::ElasticProblem shifted = p;
    for (Point3& u : shifted.prescribed) u[2] *= side == 0 ? 1 - h : 1 + h;
    std::vector<Point3> ignored;
    nh_at_snh_state[side] = stored_energy(p.mesh, fmpc_stable_neo_hookean(shifted, 10, ignored), nh_energy);
  }

  // Each code's answer minimises its own energy over the fields with the punch's displacement, so the energies at
  // the two answers bracket the difference of the minima: Pi_NH(x_NH) - Pi_SNH(x_NH) <= E_NH - E_SNH <=
  // Pi_NH(x_SNH) - Pi_SNH(x_SNH). The bracket's width is second order in the laws' difference.
  const double e_snh = stored_energy(p.mesh, x_snh, snh_energy), e_nh = stored_energy(p.mesh, x_nh, nh_energy);
  const double lower = e_nh - stored_energy(p.mesh, x_nh, snh_energy);
  const double upper = stored_energy(p.mesh, x_snh, nh_energy) - e_snh;
  const double measured = e_nh - e_snh;
  CHECK(measured >= lower - 1e-4 * e_snh);
  CHECK(measured <= upper + 1e-4 * e_snh);
  // The force: d E_NH / d depth, with E_NH(d) = Pi_NH(x_SNH(d)) to second order, by central differences.
  const double predicted_nh_force = -(nh_at_snh_state[1] - nh_at_snh_state[0]) / (2 * h * depth);
  const double predicted = predicted_nh_force / force_snh - 1, difference = force_nh / force_snh - 1;
  CHECK(std::abs(difference - predicted) < 0.1 * std::abs(predicted));
  WARN("stable neo-Hookean against CalculiX NEO HOOKE (NLGEOM), nu = "
       << nu << ", a 20 % indentation:\n  stored energy: fmpc " << e_snh << " J, CalculiX " << e_nh
       << " J, difference " << measured / e_snh * 100 << " %, the energies bracket it in [" << lower / e_snh * 100
       << ", " << upper / e_snh * 100 << "] %\n  punch force: fmpc " << force_snh << " N, CalculiX " << force_nh
       << " N, difference " << difference * 100 << " %, predicted " << predicted * 100 << " %");
}
