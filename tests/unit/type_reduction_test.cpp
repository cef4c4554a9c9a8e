// Type reduction (kernels/type_reduction_math.h) against an exhaustive search over switch points in long double
// (tests/support/type_reduction_reference.h), on seeded random and adversarial interval sets (ties, zeros,
// subnormals, equal grades, all mass at one end, lower grades of 1e-25), on the cases and on hand-made
// edge cases.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "kernels/type_reduction_math.h"
#include "tests/support/type_reduction_reference.h"

using fmpc::TypeReducedInterval;
using fmpc::TypeReduction;
using fmpc::testing::AdversarialKind;
using fmpc::testing::IntervalSet;

namespace {

TypeReducedInterval<double> run(TypeReduction method, const IntervalSet& s) {
  return fmpc::reduce_type(method, s.x.data(), s.lower.data(), s.upper.data(), static_cast<int>(s.x.size()));
}

IntervalSet random_interval_set(std::mt19937_64& rng, int max_points = 12) {
  std::uniform_int_distribution<int> size(1, max_points);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  IntervalSet s;
  const int n = size(rng);
  for (int i = 0; i < n; ++i) {
    // Ties in x and zero weights are the cases where switch points are ambiguous: make them common.
    s.x.push_back(unit(rng) < 0.2 && i > 0 ? s.x.back() : -5.0 + 10.0 * unit(rng));
    double a = unit(rng) < 0.15 ? 0.0 : unit(rng);
    double b = unit(rng) < 0.1 ? a : unit(rng);
    if (a > b) std::swap(a, b);
    s.lower.push_back(a);
    s.upper.push_back(b);
  }
  std::sort(s.x.begin(), s.x.end());
  return s;
}

// 101 samples of [0, 10] (a Mamdani output's), weight 1 on the last sample and lower grades of about 1e-25
// elsewhere: the centroid of the embedded set that keeps the last sample's upper weight is 10 - 1e-24, which
// rounds to 10 = x[100], and the old step "k = number of points with x <= y" then took the last sample's lower
// weight and cycled to the cap (the second example: yr = 9.9505 instead of 10 after 103 iterations).
IntervalSet mass_on_last_sample() {
  IntervalSet s;
  for (int i = 0; i <= 100; ++i) {
    s.x.push_back(i == 100 ? 10.0 : 10.0 * i / 100.0);
    const double grade = std::exp(-0.5 * std::pow((s.x.back() - 1.0) / 3.0, 2.0));
    s.upper.push_back(i == 100 ? 1.0 : grade * 1e-3);
    s.lower.push_back(grade * 1e-25);
  }
  return s;
}

}  // namespace

TEST_CASE("KM, EKM and EIASC equal the exhaustive switch-point search on adversarial sets", "[heavy][type-reduction]") {
  // 30,000 sets, 3,000 of each kind of fmpc::testing::AdversarialKind, to 1e-12 of the points' range.
  std::mt19937_64 rng(20260517);
  const int kinds = static_cast<int>(AdversarialKind::Count);
  std::vector<double> worst(4, 0.0);
  for (int trial = 0; trial < 30000; ++trial) {
    const auto kind = static_cast<AdversarialKind>(trial % kinds);
    const IntervalSet s = fmpc::testing::adversarial_interval_set(rng, kind);
    const auto exact = fmpc::testing::exact_type_reduction(s.x, s.lower, s.upper);
    const double tolerance = fmpc::testing::type_reduction_tolerance(s.x);
    const int n = static_cast<int>(s.x.size());
    const auto exhaustive = fmpc::exhaustive_switch_search(s.x.data(), s.lower.data(), s.upper.data(), n);
    const TypeReducedInterval<double> results[] = {run(TypeReduction::KarnikMendel, s),
                                                   run(TypeReduction::EnhancedKarnikMendel, s),
                                                   run(TypeReduction::Eiasc, s), exhaustive};
    for (int m = 0; m < 4; ++m) {
      const TypeReducedInterval<double>& r = results[m];
      INFO("trial " << trial << " kind " << static_cast<int>(kind) << " method " << m << " (3: exhaustive) n " << n);
      REQUIRE_FALSE(r.iteration_cap_hit);
      REQUIRE(r.fired == exact.fired);
      if (!exact.fired) continue;
      const double left_error = std::fabs(static_cast<double>(r.left - exact.left));
      const double right_error = std::fabs(static_cast<double>(r.right - exact.right));
      REQUIRE(left_error <= tolerance);
      REQUIRE(right_error <= tolerance);
      worst[static_cast<std::size_t>(m)] =
          std::max(worst[static_cast<std::size_t>(m)], std::max(left_error, right_error) / tolerance);
      if (m < 2) {
        // Strictly improving steps visit no switch point twice: at most n + 1 steps (EKM: its own steps first).
        REQUIRE(r.left_iterations <= (m == 0 ? n + 1 : 2 * n + 3));
        REQUIRE(r.right_iterations <= (m == 0 ? n + 1 : 2 * n + 3));
      }
    }
  }
  WARN("worst error / tolerance: KM " << worst[0] << ", EKM " << worst[1] << ", EIASC " << worst[2]
                                      << ", exhaustive " << worst[3]);
}

TEST_CASE("KM, EKM and EIASC equal the exhaustive search on small random sets with ties", "[type-reduction]") {
  std::mt19937_64 rng(20261122);
  for (int trial = 0; trial < 21000; ++trial) {
    // Mostly small sets (where ties and zeros dominate), then larger ones (where the iterations matter).
    const IntervalSet s = random_interval_set(rng, trial < 20000 ? 12 : 101);
    const auto exact = fmpc::testing::exact_type_reduction(s.x, s.lower, s.upper);
    for (TypeReduction method : {TypeReduction::KarnikMendel, TypeReduction::EnhancedKarnikMendel,
                                 TypeReduction::Eiasc}) {
      const auto r = run(method, s);
      INFO("trial " << trial << " method " << static_cast<int>(method) << " n " << s.x.size());
      REQUIRE(r.fired == exact.fired);
      if (!exact.fired) continue;
      REQUIRE(std::fabs(static_cast<double>(r.left - exact.left)) <= 1e-12 * 10.0);
      REQUIRE(std::fabs(static_cast<double>(r.right - exact.right)) <= 1e-12 * 10.0);
      REQUIRE(r.left <= r.right + 1e-12);
    }
  }
}

TEST_CASE("the issue's case: the centroid rounds onto the last sample", "[type-reduction]") {
  const IntervalSet s = mass_on_last_sample();
  const auto exact = fmpc::testing::exact_type_reduction(s.x, s.lower, s.upper);
  REQUIRE(static_cast<double>(exact.right) == 10.0);
  for (TypeReduction method : {TypeReduction::KarnikMendel, TypeReduction::EnhancedKarnikMendel,
                               TypeReduction::Eiasc}) {
    const auto r = run(method, s);
    INFO("method " << static_cast<int>(method) << ": [" << r.left << ", " << r.right << "] after "
                   << r.left_iterations << ", " << r.right_iterations << " iterations");
    REQUIRE_FALSE(r.iteration_cap_hit);
    CHECK(r.right == 10.0);
    CHECK(std::fabs(static_cast<double>(r.left - exact.left)) <= 1e-12 * 10.0);
    CHECK(r.right_iterations <= 5);
  }
}

TEST_CASE("Nie-Tan lies inside the KM interval and its distance from the KM midpoint is bounded", "[type-reduction]") {
  std::mt19937_64 rng(7);
  double worst = 0.0;
  for (int trial = 0; trial < 5000; ++trial) {
    const IntervalSet s = random_interval_set(rng);
    const auto km = run(TypeReduction::KarnikMendel, s);
    const auto nt = run(TypeReduction::NieTan, s);
    if (!km.fired) continue;
    REQUIRE(nt.left >= km.left - 1e-12);
    REQUIRE(nt.left <= km.right + 1e-12);
    // Both are in the interval, so the distance is at most half its width.
    REQUIRE(std::abs(nt.left - 0.5 * (km.left + km.right)) <= 0.5 * (km.right - km.left) + 1e-12);
    worst = std::max(worst, std::abs(nt.left - 0.5 * (km.left + km.right)));
  }
  REQUIRE(worst > 0.0);  // it is an approximation: a zero here would mean the test exercises nothing
}

TEST_CASE("Nie-Tan and every method keep their precision on subnormal weights", "[type-reduction]") {
  // Weights of 1e-320 carry 11 significant bits in double; summed as they are, x * w would round to that. The
  // kernels lift them by 2^600 first (exact), so the centroid keeps double's precision.
  const double tiny = 1e-320;
  const std::vector<double> x{0.1, 0.3, 0.7};
  const std::vector<double> w{3 * tiny, 5 * tiny, 7 * tiny};
  const long double centroid = (0.1L * w[0] + 0.3L * w[1] + 0.7L * w[2]) / (static_cast<long double>(w[0]) + w[1] + w[2]);
  for (TypeReduction method : {TypeReduction::KarnikMendel, TypeReduction::EnhancedKarnikMendel,
                               TypeReduction::Eiasc, TypeReduction::NieTan}) {
    const auto r = fmpc::reduce_type(method, x.data(), w.data(), w.data(), 3);
    INFO("method " << static_cast<int>(method));
    CHECK(std::fabs(static_cast<double>(r.left - centroid)) <= 1e-15);
    CHECK(std::fabs(static_cast<double>(r.right - centroid)) <= 1e-15);
  }
}

TEST_CASE("a footprint of zero width reduces to the type-1 centroid", "[type-reduction]") {
  const std::vector<double> x{1.0, 2.0, 4.0, 8.0};
  const std::vector<double> w{0.5, 1.0, 0.25, 0.125};
  const double centroid = (0.5 * 1 + 1.0 * 2 + 0.25 * 4 + 0.125 * 8) / (0.5 + 1.0 + 0.25 + 0.125);
  for (TypeReduction method : {TypeReduction::KarnikMendel, TypeReduction::EnhancedKarnikMendel,
                               TypeReduction::Eiasc, TypeReduction::NieTan}) {
    const auto r = fmpc::reduce_type(method, x.data(), w.data(), w.data(), 4);
    REQUIRE(r.fired);
    REQUIRE(r.left == Approx(centroid).epsilon(1e-15));
    REQUIRE(r.right == Approx(centroid).epsilon(1e-15));
  }
}

TEST_CASE("a hand-computed interval", "[type-reduction]") {
  // Two points, x = 0 and 1, weights [0.2, 0.6] and [0.1, 0.5]:
  // yl puts the upper weight on the left: (0*0.6 + 1*0.1) / 0.7 = 1/7;
  // yr puts the lower weight on the left: (0*0.2 + 1*0.5) / 0.7 = 5/7.
  const double x[] = {0.0, 1.0}, lower[] = {0.2, 0.1}, upper[] = {0.6, 0.5};
  for (TypeReduction method : {TypeReduction::KarnikMendel, TypeReduction::EnhancedKarnikMendel,
                               TypeReduction::Eiasc}) {
    const auto r = fmpc::reduce_type(method, x, lower, upper, 2);
    REQUIRE(r.left == Approx(1.0 / 7.0).epsilon(1e-15));
    REQUIRE(r.right == Approx(5.0 / 7.0).epsilon(1e-15));
    REQUIRE(r.left_switch == 1);
    REQUIRE(r.right_switch == 1);
  }
}

TEST_CASE("edge cases: nothing fired, one point, only upper weights", "[type-reduction]") {
  const double x[] = {1.0, 2.0, 3.0}, zero[] = {0.0, 0.0, 0.0}, upper[] = {0.0, 1.0, 0.0};
  for (TypeReduction method : {TypeReduction::KarnikMendel, TypeReduction::EnhancedKarnikMendel,
                               TypeReduction::Eiasc, TypeReduction::NieTan}) {
    const auto none = fmpc::reduce_type(method, x, zero, zero, 3);
    REQUIRE_FALSE(none.fired);
    REQUIRE(std::isnan(none.left));
    REQUIRE(std::isnan(none.right));
    const auto empty = fmpc::reduce_type<double>(method, nullptr, nullptr, nullptr, 0);
    REQUIRE_FALSE(empty.fired);
    const auto single = fmpc::reduce_type(method, x + 1, upper + 1, upper + 1, 1);
    REQUIRE(single.left == 2.0);
    REQUIRE(single.right == 2.0);
    // Lower weights all zero: the embedded sets include the single spike at x = 2 only.
    const auto spike = fmpc::reduce_type(method, x, zero, upper, 3);
    REQUIRE(spike.fired);
    REQUIRE(spike.left == Approx(2.0));
    REQUIRE(spike.right == Approx(2.0));
  }
}

TEST_CASE("float instantiation agrees with double to float rounding", "[type-reduction]") {
  std::mt19937_64 rng(99);
  for (int trial = 0; trial < 2000; ++trial) {
    const IntervalSet s = random_interval_set(rng);
    std::vector<float> x(s.x.begin(), s.x.end()), lo(s.lower.begin(), s.lower.end()),
        hi(s.upper.begin(), s.upper.end());
    const auto d = run(TypeReduction::KarnikMendel, s);
    for (TypeReduction method : {TypeReduction::KarnikMendel, TypeReduction::EnhancedKarnikMendel,
                                 TypeReduction::Eiasc}) {
      const auto f = fmpc::reduce_type(method, x.data(), lo.data(), hi.data(), static_cast<int>(x.size()));
      if (!d.fired) continue;
      REQUIRE_FALSE(f.iteration_cap_hit);
      REQUIRE(std::abs(static_cast<double>(f.left) - d.left) <= 1e-4 * 10.0);
      REQUIRE(std::abs(static_cast<double>(f.right) - d.right) <= 1e-4 * 10.0);
    }
  }
}
