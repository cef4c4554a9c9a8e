// kernels/tetrahedron_math.h and kernels/laws/: rotation extraction, co-rotated forces and the volume term, their
// stiffness, bounds and stresses. Seeded property tests over thousands of elements (random shapes, slivers, rotations,
// inverted, flat and collapsed deformations), each checked against an independent statement (orthogonality, energy
// gradients by finite differences, rigid-motion invariance, eigenvalues from Eigen).
#include <Eigen/Dense>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>

#include "kernels/element_laws.h"

using namespace fmpc::kernels;

namespace {

using Matrix = std::array<double, 9>;

Matrix multiply(const Matrix& a, const Matrix& b) {
  Matrix out{};
  multiply3(a.data(), b.data(), out.data());
  return out;
}

Matrix transpose(const Matrix& a) { return {a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]}; }

// A uniformly random rotation from a normalised Gaussian quaternion.
Matrix random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  double q[4], n = 0.0;
  for (double& c : q) {
    c = normal(rng);
    n += c * c;
  }
  n = std::sqrt(n);
  const double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
  return {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
          2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
          2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
}

double max_difference(const double* a, const double* b, int n) {
  double worst = 0.0;
  for (int i = 0; i < n; ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
  return worst;
}

// F = Q diag(s) P^T with the given stretches (the smallest may be negative: an inverted element).
Matrix deformation(const Matrix& Q, const std::array<double, 3>& s, const Matrix& P) {
  const Matrix D{s[0], 0, 0, 0, s[1], 0, 0, 0, s[2]};
  return multiply(multiply(Q, D), transpose(P));
}

struct Element {
  double rest[4][3];
  double rest_inverse[9];
  double volume;
};

// A random element: the regular tetrahedron distorted by a random affine map, from near-regular to slivers.
Element random_element(std::mt19937_64& rng, double aspect) {
  const double regular[4][3] = {
      {0, 0, 0}, {1, 0, 0}, {0.5, std::sqrt(3.0) / 2, 0}, {0.5, std::sqrt(3.0) / 6, std::sqrt(2.0 / 3.0)}};
  std::uniform_real_distribution<double> uniform(1.0, aspect);
  const Matrix shape = deformation(random_rotation(rng), {uniform(rng), 1.0, 1.0 / uniform(rng)}, random_rotation(rng));
  Element e{};
  const double scale = 0.01;  // a 1 cm element
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i)
      e.rest[a][i] =
          scale * (shape[3 * i] * regular[a][0] + shape[3 * i + 1] * regular[a][1] + shape[3 * i + 2] * regular[a][2]);
  double dm[9];
  for (int i = 0; i < 3; ++i)
    for (int a = 0; a < 3; ++a) dm[3 * i + a] = e.rest[a + 1][i] - e.rest[0][i];
  const Eigen::Matrix3d inverse = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(dm).inverse();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) e.rest_inverse[3 * i + j] = inverse(i, j);
  e.volume = tetrahedron_volume(e.rest);
  if (e.volume < 0.0) {  // keep the orientation every mesh has
    for (int i = 0; i < 3; ++i) std::swap(e.rest[1][i], e.rest[2][i]);
    return random_element(rng, aspect);
  }
  return e;
}

// One linear tetrahedron of one law: the arrays of a one-element term and its view (the laws read their parameters
// through it, kernels/element_term.h).
struct OneElementTerm {
  int law = 0;
  double parameter[2] = {0.0, 0.0};
  double damping = 0.0;
  double rest_inverse[9];
  double volume = 0.0;
  int nodes[4] = {0, 1, 2, 3};
  ElementTermView<double> view() const {
    ElementTermView<double> v{};
    v.law = law;
    v.element = element_kind_index<LinearTetrahedron>;
    v.count = 1;
    v.corners = nodes;
    v.corner_slot = nodes;
    v.rest_inverse = rest_inverse;
    v.rest_volume = &volume;
    v.parameter[0] = &parameter[0];
    v.parameter[1] = &parameter[1];
    v.stiffness_damping = damping != 0.0 ? &damping : nullptr;
    return v;
  }
};

OneElementTerm term_on(const Element& e, int law) {
  OneElementTerm t;
  t.law = law;
  std::copy(e.rest_inverse, e.rest_inverse + 9, t.rest_inverse);
  t.volume = e.volume;
  return t;
}

OneElementTerm corotational(const Element& e, double E, double nu, double beta = 0.0) {
  OneElementTerm t = term_on(e, element_law_index<CorotationalLinear>);
  t.parameter[CorotationalLinear::kYoungsModulus] = E;
  t.parameter[CorotationalLinear::kPoissonRatio] = nu;
  t.damping = beta;
  return t;
}

OneElementTerm volume_term_on(const Element& e, double kappa) {
  OneElementTerm t = term_on(e, element_law_index<VolumePreservation>);
  t.parameter[VolumePreservation::kBulkModulus] = kappa;
  return t;
}

// The element's forces (velocities read where the term is damped, as the element pass reads them) and energy.
template <typename Law>
void forces(const OneElementTerm& t, const double x[4][3], const double v[4][3], double f[4][3]) {
  const ElementTermView<double> view = t.view();
  LinearTetrahedron::forces<Law>(view, 0, x, view.stiffness_damping ? v : nullptr, f);
}
template <typename Law>
double energy(const OneElementTerm& t, const double x[4][3]) {
  return LinearTetrahedron::energy<Law>(t.view(), 0, x);
}

// x_a = F X_a + t.
void deform(const Element& e, const Matrix& F, const double t[3], double x[4][3]) {
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i)
      x[a][i] = F[3 * i] * e.rest[a][0] + F[3 * i + 1] * e.rest[a][1] + F[3 * i + 2] * e.rest[a][2] + t[i];
}

}  // namespace

TEST_CASE("rotation extraction: a proper rotation for every deformation, the polar one when det F > 0", "[fem]") {
  std::mt19937_64 rng(20261124);
  std::uniform_real_distribution<double> stretch(0.2, 3.0), tiny(1e-7, 1e-3);
  int inverted = 0, flat = 0, newton_fallbacks = 0;
  for (int n = 0; n < 5000; ++n) {
    const Matrix Q = random_rotation(rng), P = random_rotation(rng);
    std::array<double, 3> s{stretch(rng), stretch(rng), stretch(rng)};
    std::sort(s.begin(), s.end(), [](double a, double b) { return a > b; });
    const int kind = n % 5;  // 0-2 ordinary, 3 inverted (smallest stretch negative), 4 nearly flat
    if (kind == 3) {
      s[2] = -s[2];
      ++inverted;
    }
    if (kind == 4) {
      s[2] = tiny(rng) * s[0];
      ++flat;
    }
    const Matrix F = deformation(Q, s, P);
    Matrix R{};
    double stretches[3];
    rotation_and_stretches(F.data(), R.data(), stretches);
    // Orthonormal with determinant +1, to rounding.
    const Matrix RtR = multiply(transpose(R), R);
    const Matrix I{1, 0, 0, 0, 1, 0, 0, 0, 1};
    INFO("case " << n << ", stretches " << s[0] << " " << s[1] << " " << s[2]);
    REQUIRE(max_difference(RtR.data(), I.data(), 9) < 1e-12);
    REQUIRE(determinant3(R.data()) == Approx(1.0).margin(1e-12));
    // The expected rotation is Q P^T (Irving et al. 2004: the smallest stretch carries the inversion's sign).
    const Matrix expected = multiply(Q, transpose(P));
    if (kind != 4) REQUIRE(max_difference(R.data(), expected.data(), 9) < 1e-9);
    // R^T F is symmetric, with the stretches as its eigenvalues.
    const Matrix S = multiply(transpose(R), F);
    REQUIRE(max_difference(S.data(), transpose(S).data(), 9) < 1e-9 * s[0]);
    CHECK(stretches[0] == Approx(s[0]).epsilon(1e-9));
    CHECK(stretches[1] == Approx(s[1]).epsilon(1e-9));
    if (kind != 4) CHECK(stretches[2] == Approx(s[2]).epsilon(1e-7));
    // Newton's iteration agrees wherever it applies; it hands inverted and flat elements to the SVD path.
    Matrix newton{};
    polar_rotation(F.data(), newton.data());
    REQUIRE(max_difference(newton.data(), R.data(), 9) < 1e-12);
    if (!(determinant3(F.data()) > 0.0)) ++newton_fallbacks;
    // Float gives the same rotation to float rounding, amplified where two stretches are close (the singular
    // vectors, and for an inverted element which one carries the sign, are ill-conditioned there).
    std::array<float, 9> Ff{}, Rf{};
    for (int i = 0; i < 9; ++i) Ff[static_cast<std::size_t>(i)] = static_cast<float>(F[static_cast<std::size_t>(i)]);
    polar_rotation(Ff.data(), Rf.data());
    const double gap = std::min(std::abs(s[0]) - std::abs(s[1]), std::abs(s[1]) - std::abs(s[2]));
    const double tolerance = kind == 3 ? 2e-5 + 16 * 1.2e-7 * s[0] / gap : 2e-5;
    for (int i = 0; i < 9; ++i)
      if (kind != 4)
        REQUIRE(std::abs(static_cast<double>(Rf[static_cast<std::size_t>(i)]) - R[static_cast<std::size_t>(i)]) <
                tolerance);
  }
  CHECK(inverted == 1000);
  CHECK(flat == 1000);
  CHECK(newton_fallbacks == 1000);
}

TEST_CASE("rotation extraction: collapsed, line-like, pure rotation, NaN", "[fem]") {
  Matrix R{};
  double s[3];
  const Matrix zero{};
  rotation_and_stretches(zero.data(), R.data(), s);
  CHECK(R == Matrix{1, 0, 0, 0, 1, 0, 0, 0, 1});
  CHECK(s[0] == 0.0);
  polar_rotation(zero.data(), R.data());
  CHECK(R == Matrix{1, 0, 0, 0, 1, 0, 0, 0, 1});
  // Everything squashed onto one line: any rotation taking v1 to u1 is right; it must be proper.
  const Matrix line{2, 0, 0, 1, 0, 0, 0, 0, 0};
  rotation_and_stretches(line.data(), R.data(), s);
  CHECK(determinant3(R.data()) == Approx(1.0));
  CHECK(s[0] == Approx(std::sqrt(5.0)));
  CHECK(s[1] == Approx(0.0).margin(1e-12));
  // A pure rotation is its own polar rotation, stretches 1.
  std::mt19937_64 rng(7);
  const Matrix Q = random_rotation(rng);
  polar_rotation(Q.data(), R.data());
  CHECK(max_difference(R.data(), Q.data(), 9) < 1e-14);
  // Subnormal-scale and huge-scale elements: the rotation does not depend on the scale.
  for (double scale : {1e-300, 1e-150, 1e150}) {
    Matrix F = Q;
    for (double& v : F) v *= scale;
    polar_rotation(F.data(), R.data());
    INFO("scale " << scale);
    CHECK(max_difference(R.data(), Q.data(), 9) < 1e-12);
  }
  // Scaled stretches come back at the element's scale.
  const Matrix big{3e200, 0, 0, 0, 2e200, 0, 0, 0, 1e200};
  rotation_and_stretches(big.data(), R.data(), s);
  CHECK(s[0] == Approx(3e200));
  CHECK(s[2] == Approx(1e200));
  // A NaN position never becomes a number: the rotation stays proper, the forces are NaN.
  std::mt19937_64 shapes(8);
  const Element e = random_element(shapes, 2.0);
  double x[4][3], v[4][3] = {}, f[4][3];
  std::copy(&e.rest[0][0], &e.rest[0][0] + 12, &x[0][0]);
  x[2][1] = std::numeric_limits<double>::quiet_NaN();
  forces<CorotationalLinear>(corotational(e, 1000.0, 0.3), x, v, f);
  for (int a = 0; a < 4; ++a) CHECK(std::isnan(f[a][0] + f[a][1] + f[a][2]));
  x[2][1] = std::numeric_limits<double>::infinity();
  forces<CorotationalLinear>(corotational(e, 1000.0, 0.3), x, v, f);
  for (int a = 0; a < 4; ++a) CHECK(!std::isfinite(f[a][0] + f[a][1] + f[a][2]));
}

TEST_CASE("co-rotated forces: zero under rigid motion, the energy's gradient, momentum kept", "[fem]") {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> stretch(0.6, 1.5), nu_pick(0.0, 0.499), shift(-0.05, 0.05);
  double worst_gradient = 0.0, worst_rigid = 0.0;
  for (int n = 0; n < 2000; ++n) {
    const Element e = random_element(rng, n % 4 == 0 ? 8.0 : 2.0);
    const double E = 5000.0, nu = nu_pick(rng);
    const OneElementTerm m = corotational(e, E, nu);
    const double t[3] = {shift(rng), shift(rng), shift(rng)};
    double zero_v[4][3] = {};
    // Rigid motion: no force.
    double x[4][3], f[4][3];
    deform(e, random_rotation(rng), t, x);
    forces<CorotationalLinear>(m, x, zero_v, f);
    const double scale = E * std::cbrt(e.volume) * std::cbrt(e.volume);  // N for a unit strain
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) worst_rigid = std::max(worst_rigid, std::abs(f[a][i]) / scale);
    // A general deformation: forces sum to zero, no net torque, and equal -dW/dx (central differences).
    const Matrix F =
        deformation(random_rotation(rng), {stretch(rng), stretch(rng), stretch(rng)}, random_rotation(rng));
    deform(e, F, t, x);
    forces<CorotationalLinear>(m, x, zero_v, f);
    double sum[3] = {0, 0, 0}, torque[3] = {0, 0, 0};
    for (int a = 0; a < 4; ++a) {
      double c[3];
      cross3(x[a], f[a], c);
      for (int i = 0; i < 3; ++i) {
        sum[i] += f[a][i];
        torque[i] += c[i];
      }
    }
    for (int i = 0; i < 3; ++i) {
      CHECK(std::abs(sum[i]) < 1e-9 * scale);
      CHECK(std::abs(torque[i]) < 1e-9 * scale * std::cbrt(e.volume));
    }
    const double h = 1e-7 * std::cbrt(e.volume);
    for (int a = 0; a < 4; ++a) {
      for (int i = 0; i < 3; ++i) {
        double plus[4][3], minus[4][3];
        std::copy(&x[0][0], &x[0][0] + 12, &plus[0][0]);
        std::copy(&x[0][0], &x[0][0] + 12, &minus[0][0]);
        plus[a][i] += h;
        minus[a][i] -= h;
        const double gradient = (energy<CorotationalLinear>(m, plus) - energy<CorotationalLinear>(m, minus)) / (2 * h);
        worst_gradient = std::max(worst_gradient, std::abs(f[a][i] + gradient) / scale);
      }
    }
  }
  WARN("worst |f + dW/dx| / (E l^2) = " << worst_gradient << ", worst rigid-motion force " << worst_rigid);
  CHECK(worst_gradient < 1e-5);
  CHECK(worst_rigid < 1e-12);
}

TEST_CASE("co-rotated damping dissipates; an inverted element is pushed back to its orientation", "[fem]") {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> velocity(-1.0, 1.0);
  for (int n = 0; n < 1000; ++n) {
    const Element e = random_element(rng, 3.0);
    const OneElementTerm m = corotational(e, 3000.0, 0.3, 0.01);
    double x[4][3], v[4][3], f[4][3], undamped[4][3], still[4][3] = {};
    const double t[3] = {0, 0, 0};
    deform(e, deformation(random_rotation(rng), {1.1, 0.95, 0.9}, random_rotation(rng)), t, x);
    for (auto& corner : v)
      for (double& c : corner) c = velocity(rng);
    forces<CorotationalLinear>(m, x, v, f);
    forces<CorotationalLinear>(m, x, still, undamped);
    double power = 0.0;
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) power += (f[a][i] - undamped[a][i]) * v[a][i];
    CHECK(power <= 1e-15);
  }
  // Push corner 3 through the opposite face: the force on it points back along the face normal.
  const Element e = random_element(rng, 1.5);
  const OneElementTerm m = corotational(e, 3000.0, 0.45);
  double x[4][3], f[4][3], still[4][3] = {};
  std::copy(&e.rest[0][0], &e.rest[0][0] + 12, &x[0][0]);
  double normal[3], e1[3], e2[3];
  for (int i = 0; i < 3; ++i) {
    e1[i] = e.rest[1][i] - e.rest[0][i];
    e2[i] = e.rest[2][i] - e.rest[0][i];
  }
  cross3(e1, e2, normal);  // points to corner 3's side
  const double height = 6.0 * e.volume / std::sqrt(dot3(normal, normal));
  for (int i = 0; i < 3; ++i) x[3][i] -= 1.5 * height * normal[i] / std::sqrt(dot3(normal, normal));
  REQUIRE(tetrahedron_volume(x) < 0.0);
  forces<CorotationalLinear>(m, x, still, f);
  CHECK(dot3(f[3], normal) > 0.0);
  const OneElementTerm volume_term = volume_term_on(e, 1000.0);
  forces<VolumePreservation>(volume_term, x, still, f);
  CHECK(dot3(f[3], normal) > 0.0);
}

TEST_CASE("volume term: Teschner's constraint energy and its gradient", "[fem]") {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> stretch(0.5, 1.6);
  for (int n = 0; n < 1000; ++n) {
    const Element e = random_element(rng, 4.0);
    const OneElementTerm m = volume_term_on(e, 2.0e4);
    double x[4][3], f[4][3], still[4][3] = {};
    const double t[3] = {0.1, 0.2, 0.3};
    deform(e, deformation(random_rotation(rng), {stretch(rng), stretch(rng), stretch(rng)}, random_rotation(rng)), t,
           x);
    forces<VolumePreservation>(m, x, still, f);
    const double change = tetrahedron_volume(x) - e.volume;
    // The law reads J - 1 from F = D Dm^-1, whose rounded Dm^-1 moves J by about 1e-16: near J = 1 that is the
    // energy's error, kappa V0 |J - 1| 1e-16, not a relative 1e-12.
    CHECK(energy<VolumePreservation>(m, x) == Approx(m.parameter[0] * change * change / (2 * e.volume))
                                                  .epsilon(1e-12)
                                                  .margin(m.parameter[0] * std::abs(change) * 1e-14));
    const double h = 1e-7 * std::cbrt(e.volume), scale = m.parameter[0] * std::cbrt(e.volume) * std::cbrt(e.volume);
    for (int a = 0; a < 4; ++a) {
      for (int i = 0; i < 3; ++i) {
        double plus[4][3], minus[4][3];
        std::copy(&x[0][0], &x[0][0] + 12, &plus[0][0]);
        std::copy(&x[0][0], &x[0][0] + 12, &minus[0][0]);
        plus[a][i] += h;
        minus[a][i] -= h;
        const double gradient = (energy<VolumePreservation>(m, plus) - energy<VolumePreservation>(m, minus)) / (2 * h);
        CHECK(std::abs(f[a][i] + gradient) < 1e-6 * scale);
      }
    }
  }
}

TEST_CASE("element stiffness: the tangent is the forces' derivative at rest, the bound holds the largest eigenvalue",
          "[fem]") {
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> nu_pick(0.0, 0.499);
  double loosest = 0.0;
  for (int n = 0; n < 1000; ++n) {
    const Element e = random_element(rng, n % 3 == 0 ? 10.0 : 2.0);
    const double nu = n == 0 ? 0.0 : n == 1 ? 0.499 : nu_pick(rng);
    const OneElementTerm m = corotational(e, 4000.0, nu);
    // At a rigidly rotated rest shape the co-rotated stiffness R K0 R^T is the exact derivative of the forces.
    const Matrix Q = random_rotation(rng);
    const double t[3] = {0.01, -0.02, 0.03};
    double x[4][3], still[4][3] = {};
    deform(e, Q, t, x);
    const ElementTermView<double> view = m.view();
    LinearTetrahedron::Linearisation<CorotationalLinear> lin{};
    LinearTetrahedron::linearise<CorotationalLinear>(view, 0, x, lin);
    REQUIRE(max_difference(lin.point.rotation, Q.data(), 9) < 1e-12);
    double whole[144];
    LinearTetrahedron::stiffness_matrix<CorotationalLinear>(view, 0, lin, whole);
    Eigen::Matrix<double, 12, 12> K;
    for (int r = 0; r < 12; ++r)
      for (int c = 0; c < 12; ++c) K(r, c) = whole[12 * r + c];
    const double scale = K.cwiseAbs().maxCoeff();
    const double h = 1e-6 * std::cbrt(e.volume);
    for (int b = 0; b < 4; ++b) {
      for (int j = 0; j < 3; ++j) {
        double plus[4][3], minus[4][3], fp[4][3], fm[4][3];
        std::copy(&x[0][0], &x[0][0] + 12, &plus[0][0]);
        std::copy(&x[0][0], &x[0][0] + 12, &minus[0][0]);
        plus[b][j] += h;
        minus[b][j] -= h;
        forces<CorotationalLinear>(m, plus, still, fp);
        forces<CorotationalLinear>(m, minus, still, fm);
        for (int a = 0; a < 4; ++a)
          for (int i = 0; i < 3; ++i)
            CHECK(std::abs(-(fp[a][i] - fm[a][i]) / (2 * h) - K(3 * a + i, 3 * b + j)) < 1e-5 * scale);
      }
    }
    // The matrix is symmetric, and its 3 x 3 blocks are the closed form V0 R (lambda g_a g_b^T + mu g_b g_a^T +
    // mu (g_a . g_b) I) R^T.
    double g[4][3], mu, lambda;
    shape_gradients(e.rest_inverse, g);
    lame_parameters(4000.0, nu, mu, lambda);
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        Eigen::Matrix3d block;
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j)
            block(i, j) = e.volume * (lambda * g[a][i] * g[b][j] + mu * g[b][i] * g[a][j] +
                                      (i == j ? mu * dot3(g[a], g[b]) : 0.0));
        const Eigen::Matrix3d R = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(Q.data());
        const Eigen::Matrix3d rotated = R * block * R.transpose();
        for (int i = 0; i < 3; ++i)
          for (int j = 0; j < 3; ++j) CHECK(K(3 * a + i, 3 * b + j) == Approx(rotated(i, j)).margin(1e-12 * scale));
      }
    // The action is the blocks' product.
    double p[4][3], out[4][3];
    Eigen::Matrix<double, 12, 1> pv;
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) p[a][i] = pv[3 * a + i] = std::sin(1.0 + 3 * a + i);
    LinearTetrahedron::stiffness_action<CorotationalLinear>(view, 0, lin, p, out);
    const Eigen::Matrix<double, 12, 1> product = K * pv;
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 3; ++i) CHECK(out[a][i] == Approx(product[3 * a + i]).margin(1e-12 * scale));
    // The bound is above the largest eigenvalue, and not far above it.
    const double largest = Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 12, 12>>(K).eigenvalues().maxCoeff();
    const double bound = LinearTetrahedron::stiffness_bound<CorotationalLinear>(view, 0);
    CHECK(bound >= largest * (1 - 1e-12));
    loosest = std::max(loosest, bound / largest);
  }
  WARN("the bound is at most " << loosest << " x the largest eigenvalue");
  CHECK(loosest < 2.0);
}

TEST_CASE("von Mises stress of uniaxial, shear and hydrostatic stress", "[fem]") {
  const double uniaxial[9] = {-7, 0, 0, 0, 0, 0, 0, 0, 0};
  CHECK(von_mises_stress(uniaxial) == Approx(7.0));
  const double shear[9] = {0, 2, 0, 2, 0, 0, 0, 0, 0};
  CHECK(von_mises_stress(shear) == Approx(2.0 * std::sqrt(3.0)));
  const double pressure[9] = {5, 0, 0, 0, 5, 0, 0, 0, 5};
  CHECK(von_mises_stress(pressure) == Approx(0.0).margin(1e-15));
}
