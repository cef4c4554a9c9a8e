// compiler/eval/agreement.h: MAE, RMSE, bias, Bland-Altman limits and Pearson's r against hand computations, at
// the edges (one pair, identical values, values near DBL_MAX, subnormal differences, a difference that overflows,
// NaN and empty input), seeded comparisons with a long-double reference, and the histogram's bins.
#include <catch2/catch.hpp>

#include <cfloat>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <stdexcept>
#include <vector>

#include "compiler/eval/agreement.h"

namespace fmpc {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST_CASE("measure_agreement matches a hand computation", "[agreement]") {
  // d = predicted - measured = {0, 1, -2, 2}
  const Agreement a = measure_agreement({1, 2, 3, 4}, {1, 1, 5, 2});
  CHECK(a.count == 4);
  CHECK(a.mean_absolute_error == 1.25);
  CHECK(a.root_mean_square_error == 1.5);
  CHECK(a.bias == 0.25);
  const double sd = std::sqrt((0.0625 + 0.5625 + 5.0625 + 3.0625) / 3.0);
  CHECK(a.difference_sd == Approx(sd).epsilon(1e-15));
  CHECK(a.lower_limit == Approx(0.25 - 1.96 * sd).epsilon(1e-15));
  CHECK(a.upper_limit == Approx(0.25 + 1.96 * sd).epsilon(1e-15));
  CHECK(a.largest_absolute_error == 2.0);
  CHECK(a.largest_error_index == 2);  // the first of |d| = 2
  // r from the textbook formula: means 2.5 and 2.25.
  const double sxy = (-1.5) * (-1.25) + (-0.5) * (-1.25) + 0.5 * 2.75 + 1.5 * (-0.25);
  const double sxx = 2.25 + 0.25 + 0.25 + 2.25, syy = 1.5625 + 1.5625 + 7.5625 + 0.0625;
  CHECK(a.correlation == Approx(sxy / std::sqrt(sxx * syy)).epsilon(1e-15));
}

TEST_CASE("measure_agreement at the edges", "[agreement]") {
  SECTION("one pair: no spread, no limits, no correlation") {
    const Agreement a = measure_agreement({7.5}, {5});
    CHECK(a.mean_absolute_error == 2.5);
    CHECK(a.root_mean_square_error == 2.5);
    CHECK(a.bias == 2.5);
    CHECK(std::isnan(a.difference_sd));
    CHECK(std::isnan(a.lower_limit));
    CHECK(std::isnan(a.upper_limit));
    CHECK(std::isnan(a.correlation));
  }
  SECTION("perfect agreement: every measure 0, r = 1") {
    const Agreement a = measure_agreement({0, 1, 2}, {0, 1, 2});
    CHECK(a.mean_absolute_error == 0);
    CHECK(a.root_mean_square_error == 0);
    CHECK(a.bias == 0);
    CHECK(a.difference_sd == 0);
    CHECK(a.lower_limit == 0);
    CHECK(a.upper_limit == 0);
    CHECK(a.largest_absolute_error == 0);
    CHECK(a.largest_error_index == 0);
    CHECK(a.correlation == 1.0);
  }
  SECTION("a constant prediction has no correlation") {
    CHECK(std::isnan(measure_agreement({3, 3, 3}, {1, 2, 3}).correlation));
  }
  SECTION("values near DBL_MAX do not overflow the squares") {
    const Agreement a = measure_agreement({1e300, 2e300}, {0, 0});
    CHECK(a.mean_absolute_error == Approx(1.5e300).epsilon(1e-15));
    CHECK(a.root_mean_square_error == Approx(std::sqrt(2.5) * 1e300).epsilon(1e-15));
    CHECK(std::isfinite(a.difference_sd));
    CHECK(a.difference_sd == Approx(std::sqrt(0.5) * 1e300).epsilon(1e-14));
  }
  SECTION("subnormal differences are not lost to underflow") {
    const double tiny = std::numeric_limits<double>::denorm_min();
    const Agreement a = measure_agreement({4 * tiny, 4 * tiny}, {0, 0});
    CHECK(a.root_mean_square_error == 4 * tiny);  // a plain sum of squares would be 0
    CHECK(a.mean_absolute_error == 4 * tiny);
    CHECK(a.difference_sd == 0);
  }
  SECTION("a shared large offset cancels before summing") {
    const Agreement a = measure_agreement({1e16 + 2, 1e16 + 4}, {1e16, 1e16});
    CHECK(a.mean_absolute_error == 3.0);
    CHECK(a.bias == 3.0);
  }
  SECTION("a difference beyond DBL_MAX is infinite, never a finite number") {
    const Agreement a = measure_agreement({DBL_MAX, 0}, {-DBL_MAX, 0});
    CHECK(a.mean_absolute_error == kInf);
    CHECK(a.root_mean_square_error == kInf);
    CHECK(a.largest_absolute_error == kInf);
    CHECK_FALSE(std::isfinite(a.bias));
  }
  SECTION("refused: NaN, infinity, mismatched lengths, nothing") {
    CHECK_THROWS_AS(measure_agreement({1, kNaN}, {1, 2}), std::invalid_argument);
    CHECK_THROWS_AS(measure_agreement({1, 2}, {1, kInf}), std::invalid_argument);
    CHECK_THROWS_AS(measure_agreement({1, 2}, {1}), std::invalid_argument);
    CHECK_THROWS_AS(measure_agreement({}, {}), std::invalid_argument);
  }
}

TEST_CASE("measure_agreement agrees with a long-double reference on seeded data", "[agreement]") {
  std::mt19937_64 random(29);
  for (int trial = 0; trial < 200; ++trial) {
    const std::size_t n = 2 + random() % 300;
    const double scale = std::ldexp(1.0, static_cast<int>(random() % 60) - 30);
    std::vector<double> p(n), m(n);
    for (std::size_t i = 0; i < n; ++i) {
      p[i] = (static_cast<double>(random() >> 11) * 0x1.0p-53 - 0.3) * scale;
      m[i] = (static_cast<double>(random() >> 11) * 0x1.0p-53 - 0.5) * scale;
    }
    long double sum_abs = 0, sum_sq = 0, sum = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const long double d = static_cast<long double>(p[i]) - m[i];
      sum_abs += std::fabs(d);
      sum_sq += d * d;
      sum += d;
    }
    const long double mean = sum / n;
    long double dev = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const long double e = static_cast<long double>(p[i]) - m[i] - mean;
      dev += e * e;
    }
    const Agreement a = measure_agreement(p, m);
    CHECK(a.mean_absolute_error == Approx(static_cast<double>(sum_abs / n)).epsilon(1e-12));
    CHECK(a.root_mean_square_error == Approx(static_cast<double>(std::sqrt(sum_sq / n))).epsilon(1e-12));
    CHECK(a.bias == Approx(static_cast<double>(mean)).epsilon(1e-10).margin(1e-12 * scale));
    CHECK(a.difference_sd == Approx(static_cast<double>(std::sqrt(dev / (n - 1)))).epsilon(1e-12));
    CHECK(a.correlation >= -1.0);
    CHECK(a.correlation <= 1.0);
  }
}

TEST_CASE("histogram bins values over their range", "[agreement]") {
  SECTION("counts, edges and the upper end in the last bin") {
    const Histogram h = histogram({0, 0.5, 1, 1.5, 2, 4}, 4);
    CHECK(h.lo == 0);
    CHECK(h.hi == 4);
    CHECK(h.bin_width() == 1);
    CHECK(h.counts == std::vector<std::size_t>{2, 2, 1, 1});
  }
  SECTION("every value the same: one bin in the middle of v -/+ 0.5") {
    const Histogram h = histogram({0, 0, 0}, 5);
    CHECK(h.lo == -0.5);
    CHECK(h.hi == 0.5);
    CHECK(h.counts == std::vector<std::size_t>{0, 0, 3, 0, 0});
  }
  SECTION("a constant too large for -/+ 0.5 still gets a span") {
    const Histogram h = histogram({1e300, 1e300}, 3);
    CHECK(h.hi > h.lo);
    CHECK(h.counts == std::vector<std::size_t>{0, 2, 0});
  }
  SECTION("a span near DBL_MAX does not overflow") {
    const Histogram h = histogram({-DBL_MAX, 0, DBL_MAX}, 2);
    CHECK(h.counts == std::vector<std::size_t>{1, 2});
  }
  SECTION("every value lands in a bin") {
    std::mt19937_64 random(7);
    std::vector<double> values(1000);
    for (double& v : values) v = static_cast<double>(random() >> 11) * 0x1.0p-53 * 10 - 3;
    const Histogram h = histogram(values, sturges_bins(values.size()));
    CHECK(h.counts.size() == 11);
    CHECK(std::accumulate(h.counts.begin(), h.counts.end(), std::size_t{0}) == values.size());
  }
  SECTION("refused: no values, NaN, no bins") {
    CHECK_THROWS_AS(histogram({}, 3), std::invalid_argument);
    CHECK_THROWS_AS(histogram({1, kNaN}, 3), std::invalid_argument);
    CHECK_THROWS_AS(histogram({1}, 0), std::invalid_argument);
  }
  SECTION("Sturges' rule") {
    CHECK(sturges_bins(0) == 1);
    CHECK(sturges_bins(1) == 1);
    CHECK(sturges_bins(2) == 2);
    CHECK(sturges_bins(12) == 5);
    CHECK(sturges_bins(std::size_t{1} << 60) == 50);
  }
}

}  // namespace
}  // namespace fmpc
