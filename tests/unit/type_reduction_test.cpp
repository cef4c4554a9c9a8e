// Type reduction (kernels/type_reduction_math.h) against the exhaustive switch-point search, on seeded random
// interval sets and hand-made edge cases.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <vector>

#include "kernels/type_reduction_math.h"

using fmpc::TypeReducedInterval;
using fmpc::TypeReduction;

namespace {

struct IntervalSet {
  std::vector<double> x, lower, upper;
};

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

TypeReducedInterval<double> run(TypeReduction method, const IntervalSet& s) {
  return fmpc::reduce_type(method, s.x.data(), s.lower.data(), s.upper.data(), static_cast<int>(s.x.size()));
}

}  // namespace

TEST_CASE("KM, EKM and EIASC equal the exhaustive switch-point search", "[type-reduction]") {
  std::mt19937_64 rng(20261122);
  for (int trial = 0; trial < 21000; ++trial) {
    // Mostly small sets (where ties and zeros dominate), then larger ones (where the iterations matter).
    const IntervalSet s = random_interval_set(rng, trial < 20000 ? 12 : 101);
    const auto reference = fmpc::exhaustive_switch_search(s.x.data(), s.lower.data(), s.upper.data(),
                                                          static_cast<int>(s.x.size()));
    for (TypeReduction method : {TypeReduction::KarnikMendel, TypeReduction::EnhancedKarnikMendel,
                                 TypeReduction::Eiasc}) {
      const auto r = run(method, s);
      INFO("trial " << trial << " method " << static_cast<int>(method) << " n " << s.x.size());
      REQUIRE(r.fired == reference.fired);
      if (!reference.fired) continue;
      REQUIRE(std::abs(r.left - reference.left) <= 1e-12 * 10.0);
      REQUIRE(std::abs(r.right - reference.right) <= 1e-12 * 10.0);
      REQUIRE(r.left <= r.right + 1e-12);
    }
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
  // yl puts the upper weight on the left: 0.5*0... -> (0*0.6 + 1*0.1) / 0.7 = 1/7;
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
    const auto f = fmpc::karnik_mendel(x.data(), lo.data(), hi.data(), static_cast<int>(x.size()));
    if (!d.fired) continue;
    REQUIRE(std::abs(static_cast<double>(f.left) - d.left) <= 1e-4 * 10.0);
    REQUIRE(std::abs(static_cast<double>(f.right) - d.right) <= 1e-4 * 10.0);
  }
}
