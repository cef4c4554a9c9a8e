// The curve similarity of runtime/analysis/curve_similarity.h: closed forms, every stated property over thousands
// of seeded random curves, an independent brute-force integration, and every refusal.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>

#include "runtime/analysis/curve_similarity.h"

namespace {

using fmpc::DiagnosticList;
using fmpc::sim::compare_curves;
using fmpc::sim::CurveComparison;
using fmpc::sim::Curve;

Curve make_curve(std::string name, std::vector<double> time, std::vector<double> value) {
  return Curve{std::move(name), std::move(time), std::move(value)};
}

CurveComparison compare(const Curve& a, const Curve& b) {
  DiagnosticList diagnostics;
  const auto result = compare_curves(a, b, diagnostics);
  INFO(fmpc::render_all(diagnostics, fmpc::SourceFiles{}));
  REQUIRE(result);
  REQUIRE_FALSE(diagnostics.has_errors());
  return *result;
}

std::string refusal(const Curve& a, const Curve& b) {
  DiagnosticList diagnostics;
  const auto result = compare_curves(a, b, diagnostics);
  CHECK_FALSE(result);
  CHECK(diagnostics.error_count() == 1);
  return fmpc::render_all(diagnostics, fmpc::SourceFiles{});
}

// A random curve: 2 to 40 samples, random positive gaps starting at `start`, values of a random scale and sign.
Curve random_curve(std::mt19937_64& rng, const std::string& name, double start) {
  std::uniform_int_distribution<int> count(2, 40);
  std::uniform_real_distribution<double> gap(0.01, 1.0), unit(-1.0, 1.0), exponent(-6.0, 6.0);
  const double scale = std::pow(10.0, exponent(rng));
  const double offset = unit(rng) < 0.0 ? 0.0 : scale * unit(rng);
  Curve curve{name, {}, {}};
  double t = start;
  for (int i = count(rng); i > 0; --i) {
    curve.time.push_back(t);
    curve.value.push_back(offset + scale * unit(rng));
    t += gap(rng);
  }
  return curve;
}

// The curve's piecewise-linear value at t (inside its span), for the brute-force reference.
double value_at(const Curve& c, double t) {
  for (std::size_t i = 0; i + 1 < c.time.size(); ++i)
    if (t <= c.time[i + 1]) return c.value[i] + (c.value[i + 1] - c.value[i]) * (t - c.time[i]) / (c.time[i + 1] - c.time[i]);
  return c.value.back();
}

}  // namespace

TEST_CASE("curve similarity: closed forms", "[similarity]") {
  SECTION("identical curves give exactly 1, and so do two zero curves") {
    const Curve a = make_curve("a", {0.0, 0.5, 2.0}, {0.0, 3.0, -1.0});
    CHECK(compare(a, a).similarity == 1.0);
    CHECK(compare(a, a).difference_norm == 0.0);
    CHECK(*compare(a, a).correlation == Approx(1.0).margin(1e-15));
    const Curve zero = make_curve("zero", {0.0, 1.0}, {0.0, 0.0});
    CHECK(compare(zero, zero).similarity == 1.0);
    CHECK_FALSE(compare(zero, zero).correlation);
  }
  SECTION("t against 1 - t on [0, 1]: ||a|| = ||b|| = ||a - b|| = 1/sqrt(3), S = 1/2, r = -1") {
    const auto r = compare(make_curve("a", {0.0, 1.0}, {0.0, 1.0}), make_curve("b", {0.0, 1.0}, {1.0, 0.0}));
    CHECK(r.norm_a == Approx(1.0 / std::sqrt(3.0)).epsilon(1e-15));
    CHECK(r.norm_b == Approx(1.0 / std::sqrt(3.0)).epsilon(1e-15));
    CHECK(r.difference_norm == Approx(1.0 / std::sqrt(3.0)).epsilon(1e-15));
    CHECK(r.similarity == Approx(0.5).epsilon(1e-15));
    CHECK(*r.correlation == Approx(-1.0).epsilon(1e-15));
  }
  SECTION("opposite curves and a zero curve against any other give 0") {
    const Curve a = make_curve("a", {0.0, 1.0, 3.0}, {1.0, -2.0, 5.0});
    const Curve minus = make_curve("-a", {0.0, 1.0, 3.0}, {-1.0, 2.0, -5.0});
    const Curve zero = make_curve("zero", {0.0, 3.0}, {0.0, 0.0});
    CHECK(compare(a, minus).similarity == 0.0);
    CHECK(compare(a, zero).similarity == 0.0);
    CHECK(compare(zero, a).similarity == 0.0);
    CHECK_FALSE(compare(a, zero).correlation);  // a zero curve has no shape
  }
  SECTION("constant curves: 1 and 2 give 1 - 1/3; the correlation is undefined") {
    const auto r = compare(make_curve("one", {0.0, 4.0}, {1.0, 1.0}), make_curve("two", {1.0, 2.0, 3.0}, {2.0, 2.0, 2.0}));
    CHECK(r.similarity == Approx(2.0 / 3.0).epsilon(1e-15));
    CHECK_FALSE(r.correlation);
    CHECK(r.interval_start == 1.0);
    CHECK(r.interval_end == 3.0);
    // A constant 0.1 whose mean rounds is still constant (the variance floor), not a shape.
    const auto s = compare(make_curve("tenth", {0.0, 0.1, 0.7, 3.0}, {0.1, 0.1, 0.1, 0.1}),
                           make_curve("ramp", {0.0, 3.0}, {0.0, 1.0}));
    CHECK_FALSE(s.correlation);
  }
  SECTION("a scaled copy b = lambda a gives 2 min(1, lambda) / (1 + lambda)") {
    const Curve a = make_curve("a", {0.0, 0.3, 1.0, 1.7}, {0.2, -1.0, 0.5, 2.0});
    for (const double lambda : {0.0, 0.1, 0.5, 1.0, 2.0, 10.0, 1e6}) {
      Curve b = a;
      for (double& y : b.value) y *= lambda;
      const auto r = compare(a, b);
      CHECK(r.similarity == Approx(2.0 * std::min(1.0, lambda) / (1.0 + lambda)).margin(1e-14));
      if (lambda > 0.0) CHECK(*r.correlation == Approx(1.0).margin(1e-12));
    }
  }
  SECTION("an offset and a delay lower S; the correlation ignores the offset") {
    const Curve a = make_curve("a", {0.0, 1.0, 2.0, 3.0}, {0.0, 1.0, 1.0, 1.0});
    const Curve offset = make_curve("a + 1", {0.0, 1.0, 2.0, 3.0}, {1.0, 2.0, 2.0, 2.0});
    const Curve delayed = make_curve("a delayed", {0.0, 1.0, 2.0, 3.0}, {0.0, 0.0, 1.0, 1.0});
    CHECK(compare(a, offset).similarity < 0.8);
    CHECK(*compare(a, offset).correlation == Approx(1.0).margin(1e-12));
    CHECK(compare(a, delayed).similarity < 0.8);
  }
}

TEST_CASE("curve similarity: curves of different lengths and sample times", "[similarity]") {
  const Curve line = make_curve("line", {0.0, 10.0}, {0.0, 10.0});
  SECTION("the same line sampled differently is the same curve") {
    Curve fine{"fine", {}, {}};
    for (int i = 0; i <= 1000; ++i) {
      fine.time.push_back(0.01 * i);
      fine.value.push_back(0.01 * i);
    }
    CHECK(compare(line, fine).similarity == Approx(1.0).margin(1e-13));
  }
  SECTION("only the common interval counts: a longer curve compares as if cut") {
    const Curve shorter = make_curve("shorter", {2.0, 3.0, 5.0}, {1.0, 4.0, 4.0});
    const Curve cut = make_curve("cut", {2.0, 5.0}, {2.0, 5.0});
    const auto r = compare(line, shorter), s = compare(cut, shorter);
    CHECK(r.interval_start == 2.0);
    CHECK(r.interval_end == 5.0);
    CHECK(r.similarity == Approx(s.similarity).epsilon(1e-14));
    CHECK(*r.correlation == Approx(*s.correlation).epsilon(1e-14));
  }
}

TEST_CASE("curve similarity: properties over 5,000 seeded random pairs", "[similarity]") {
  std::mt19937_64 rng(20261124);
  std::uniform_real_distribution<double> start(-1.0, 1.0), factor(1e-3, 1e3), shift(-100.0, 100.0);
  for (int trial = 0; trial < 5000; ++trial) {
    INFO("trial " << trial);
    const Curve a = random_curve(rng, "a", start(rng));
    const Curve b = random_curve(rng, "b", start(rng));
    DiagnosticList diagnostics;
    const auto ab = compare_curves(a, b, diagnostics);
    if (!ab) {  // no common interval: refused, never a number
      CHECK((a.time.back() <= b.time.front() || b.time.back() <= a.time.front()));
      continue;
    }
    const auto ba = compare(b, a);
    // Bounded and exactly symmetric.
    CHECK(ab->similarity >= 0.0);
    CHECK(ab->similarity <= 1.0);
    CHECK(ab->similarity == ba.similarity);
    CHECK(ab->correlation.has_value() == ba.correlation.has_value());
    if (ab->correlation) {
      CHECK(std::abs(*ab->correlation) <= 1.0);
      CHECK(*ab->correlation == *ba.correlation);
    }
    // Triangle inequality, as computed.
    CHECK(ab->difference_norm <= (ab->norm_a + ab->norm_b) * (1.0 + 1e-12));
    // The unit of y does not matter.
    Curve a_scaled = a, b_scaled = b;
    const double c = factor(rng);
    for (double& y : a_scaled.value) y *= c;
    for (double& y : b_scaled.value) y *= c;
    CHECK(compare(a_scaled, b_scaled).similarity == Approx(ab->similarity).margin(1e-11));
    // Nor where time starts.
    Curve a_shifted = a, b_shifted = b;
    const double tau = shift(rng);
    for (double& t : a_shifted.time) t += tau;
    for (double& t : b_shifted.time) t += tau;
    CHECK(compare(a_shifted, b_shifted).similarity == Approx(ab->similarity).margin(1e-9));
    // Nor a sample inserted on a straight segment (the midpoint of every segment of a).
    Curve a_refined{"a refined", {}, {}};
    for (std::size_t i = 0; i < a.time.size(); ++i) {
      a_refined.time.push_back(a.time[i]);
      a_refined.value.push_back(a.value[i]);
      if (i + 1 < a.time.size()) {
        a_refined.time.push_back((a.time[i] + a.time[i + 1]) / 2.0);
        a_refined.value.push_back((a.value[i] + a.value[i + 1]) / 2.0);
      }
    }
    CHECK(compare(a_refined, b).similarity == Approx(ab->similarity).margin(1e-12));
    // A curve against itself is 1.
    CHECK(compare(a, a).similarity == 1.0);
  }
}

TEST_CASE("curve similarity: the exact integrals agree with brute-force quadrature", "[similarity]") {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    INFO("trial " << trial);
    const Curve a = random_curve(rng, "a", 0.0);
    Curve b = random_curve(rng, "b", 0.0);
    const auto r = compare(a, b);
    // Midpoint rule on 20,000 cells of the common interval, written independently of the library.
    const double t0 = r.interval_start, t1 = r.interval_end;
    const int cells = 20000;
    const double h = (t1 - t0) / cells;
    double aa = 0.0, bb = 0.0, dd = 0.0, sa = 0.0, sb = 0.0, ab = 0.0;
    for (int i = 0; i < cells; ++i) {
      const double t = t0 + (i + 0.5) * h;
      const double x = value_at(a, t), y = value_at(b, t);
      aa += x * x * h;
      bb += y * y * h;
      dd += (x - y) * (x - y) * h;
      sa += x * h;
      sb += y * h;
      ab += x * y * h;
    }
    const double expected = 1.0 - std::sqrt(dd) / (std::sqrt(aa) + std::sqrt(bb));
    CHECK(r.similarity == Approx(expected).margin(1e-5));
    const double length = t1 - t0;
    const double covariance = ab / length - sa * sb / (length * length);
    const double var_a = aa / length - sa * sa / (length * length), var_b = bb / length - sb * sb / (length * length);
    REQUIRE(r.correlation);
    CHECK(*r.correlation == Approx(covariance / std::sqrt(var_a * var_b)).margin(1e-4));
  }
}

TEST_CASE("curve similarity: tiny and huge values keep their similarity", "[similarity]") {
  const Curve a = make_curve("a", {0.0, 1.0, 2.0}, {0.0, 1.0, 0.5});
  const Curve b = make_curve("b", {0.0, 1.5, 2.0}, {0.2, 0.7, 0.4});
  const double s = compare(a, b).similarity;
  for (const double scale : {std::numeric_limits<double>::denorm_min() * 1e6, 1e-300, 1e300}) {
    Curve as = a, bs = b;
    for (double& y : as.value) y *= scale;
    for (double& y : bs.value) y *= scale;
    INFO("scale " << scale);
    CHECK(compare(as, bs).similarity == Approx(s).margin(scale < 1e-307 ? 1e-4 : 1e-14));  // subnormals carry ~20 bits
  }
}

TEST_CASE("curve similarity: refusals name the curve and the sample", "[similarity]") {
  const Curve good = make_curve("good", {0.0, 1.0}, {0.0, 1.0});
  const double nan = std::nan("");
  const double inf = std::numeric_limits<double>::infinity();
  CHECK_THAT(refusal(make_curve("bad", {0.0, 1.0}, {0.0, nan}), good),
             Catch::Contains("curve 'bad' sample 1") && Catch::Contains("not finite"));
  CHECK_THAT(refusal(good, make_curve("bad", {0.0, inf}, {0.0, 1.0})),
             Catch::Contains("curve 'bad' sample 1") && Catch::Contains("not finite"));
  CHECK_THAT(refusal(make_curve("flat", {0.0, 1.0, 1.0}, {0.0, 1.0, 2.0}), good),
             Catch::Contains("curve 'flat' sample 2") && Catch::Contains("strictly increase"));
  CHECK_THAT(refusal(make_curve("back", {0.0, 2.0, 1.0}, {0.0, 1.0, 2.0}), good), Catch::Contains("sample 2"));
  CHECK_THAT(refusal(make_curve("one", {0.0}, {1.0}), good), Catch::Contains("at least 2"));
  CHECK_THAT(refusal(make_curve("none", {}, {}), good), Catch::Contains("0 sample"));
  CHECK_THAT(refusal(make_curve("ragged", {0.0, 1.0}, {1.0}), good),
             Catch::Contains("2 times and 1 values"));
  CHECK_THAT(refusal(good, make_curve("later", {1.0, 2.0}, {0.0, 1.0})), Catch::Contains("share no interval"));
  CHECK_THAT(refusal(good, make_curve("far", {5.0, 6.0}, {0.0, 1.0})), Catch::Contains("share no interval"));
  CHECK_THAT(refusal(make_curve("big", {0.0, 1.0, 2.0}, {-1.7e308, 1.7e308, 0.0}),
                     make_curve("probe", {0.0, 0.5, 2.0}, {0.0, 0.0, 0.0})),
             Catch::Contains("overflows"));
}
