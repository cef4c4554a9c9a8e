// kernels/fuzzy_math.h: every MF family against hand-computed values (feet, peaks, shoulders, degenerate
// parameters, NaN and +-inf), the norms and hedges, in double and in float.
#include <catch2/catch.hpp>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "kernels/fuzzy_math.h"

namespace {

using fmpc::MfKind;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double mu(MfKind kind, std::vector<double> params, double x) {
  params.resize(4, 0.0);
  return fmpc::membership(kind, params.data(), x);
}

const std::vector<std::pair<MfKind, std::vector<double>>>& every_input_family() {
  static const std::vector<std::pair<MfKind, std::vector<double>>> families{
      {MfKind::Triangle, {1, 2, 4}},          {MfKind::Trapezoid, {1, 2, 3, 5}},
      {MfKind::Gaussian, {1.5, 2}},           {MfKind::Gaussian2, {1, 2, 0.5, 3}},
      {MfKind::GeneralizedBell, {2, 3, 1}},   {MfKind::Sigmoid, {2, 1}},
      {MfKind::DifferenceSigmoid, {5, 2, 5, 7}}, {MfKind::ProductSigmoid, {2, 3, -5, 8}},
      {MfKind::ZShape, {1, 3}},               {MfKind::SShape, {1, 3}},
      {MfKind::PiShape, {1, 3, 5, 7}},        {MfKind::LinearS, {1, 3}},
      {MfKind::LinearZ, {1, 3}},
  };
  return families;
}

}  // namespace

TEST_CASE("trimf: feet, peak, slopes and degenerate shoulders as MATLAB", "[fuzzy-math]") {
  CHECK(mu(MfKind::Triangle, {1, 2, 4}, 1) == 0.0);
  CHECK(mu(MfKind::Triangle, {1, 2, 4}, 4) == 0.0);
  CHECK(mu(MfKind::Triangle, {1, 2, 4}, 2) == 1.0);
  CHECK(mu(MfKind::Triangle, {1, 2, 4}, 1.5) == 0.5);
  CHECK(mu(MfKind::Triangle, {1, 2, 4}, 3.5) == 0.25);
  CHECK(mu(MfKind::Triangle, {1, 2, 4}, 0) == 0.0);
  CHECK(mu(MfKind::Triangle, {1, 2, 4}, 9) == 0.0);
  // a == b: a right triangle, 1 at the shoulder, 0 left of it.
  CHECK(mu(MfKind::Triangle, {2, 2, 4}, 2) == 1.0);
  CHECK(mu(MfKind::Triangle, {2, 2, 4}, 3) == 0.5);
  CHECK(mu(MfKind::Triangle, {2, 2, 4}, 1.999) == 0.0);
  // b == c
  CHECK(mu(MfKind::Triangle, {0, 4, 4}, 4) == 1.0);
  CHECK(mu(MfKind::Triangle, {0, 4, 4}, 1) == 0.25);
  CHECK(mu(MfKind::Triangle, {0, 4, 4}, 4.001) == 0.0);
  // a == b == c: a crisp singleton.
  CHECK(mu(MfKind::Triangle, {3, 3, 3}, 3) == 1.0);
  CHECK(mu(MfKind::Triangle, {3, 3, 3}, 3.0000001) == 0.0);
  CHECK(mu(MfKind::Triangle, {1, 2, 4}, kInf) == 0.0);
  CHECK(mu(MfKind::Triangle, {1, 2, 4}, -kInf) == 0.0);
}

TEST_CASE("trapmf: shoulders, feet, a == b, c == d and overlapping edges (b > c)", "[fuzzy-math]") {
  CHECK(mu(MfKind::Trapezoid, {1, 2, 3, 5}, 1) == 0.0);
  CHECK(mu(MfKind::Trapezoid, {1, 2, 3, 5}, 1.25) == 0.25);
  CHECK(mu(MfKind::Trapezoid, {1, 2, 3, 5}, 2) == 1.0);
  CHECK(mu(MfKind::Trapezoid, {1, 2, 3, 5}, 2.5) == 1.0);
  CHECK(mu(MfKind::Trapezoid, {1, 2, 3, 5}, 3) == 1.0);
  CHECK(mu(MfKind::Trapezoid, {1, 2, 3, 5}, 4) == 0.5);
  CHECK(mu(MfKind::Trapezoid, {1, 2, 3, 5}, 5) == 0.0);
  // a == b: vertical left edge, 1 on it.
  CHECK(mu(MfKind::Trapezoid, {2, 2, 3, 5}, 2) == 1.0);
  CHECK(mu(MfKind::Trapezoid, {2, 2, 3, 5}, 1.999) == 0.0);
  // c == d: vertical right edge, 1 on it.
  CHECK(mu(MfKind::Trapezoid, {1, 2, 3, 3}, 3) == 1.0);
  CHECK(mu(MfKind::Trapezoid, {1, 2, 3, 3}, 3.001) == 0.0);
  // b > c (MATLAB trapmf.m takes min of the two edges): the top is where they cross, below 1.
  CHECK(mu(MfKind::Trapezoid, {0, 4, 0, 4}, 2) == 0.5);
  // The shoulders used as a left/right shoulder far outside the range (the Octave heart-disease file).
  CHECK(mu(MfKind::Trapezoid, {-1, 0, 90, 110}, 0) == 1.0);
  CHECK(mu(MfKind::Trapezoid, {-1, 0, 90, 110}, 100) == 0.5);
  CHECK(mu(MfKind::Trapezoid, {1, 2, 3, 5}, kInf) == 0.0);
  CHECK(mu(MfKind::Trapezoid, {1, 2, 3, 5}, -kInf) == 0.0);
  CHECK(mu(MfKind::Trapezoid, {-kInf, -kInf, 3, 5}, -kInf) == 1.0);
}

TEST_CASE("gaussmf and gauss2mf", "[fuzzy-math]") {
  CHECK(mu(MfKind::Gaussian, {2, 5}, 5) == 1.0);
  CHECK(mu(MfKind::Gaussian, {2, 5}, 7) == Approx(std::exp(-0.5)).epsilon(1e-15));
  CHECK(mu(MfKind::Gaussian, {2, 5}, 1) == Approx(std::exp(-2.0)).epsilon(1e-15));
  CHECK(mu(MfKind::Gaussian, {-2, 5}, 7) == Approx(std::exp(-0.5)).epsilon(1e-15));  // sign of sigma is squared
  CHECK(mu(MfKind::Gaussian, {2, 5}, kInf) == 0.0);
  CHECK(mu(MfKind::Gaussian, {2, 5}, -kInf) == 0.0);
  // gauss2mf: 1 on [c1, c2], a Gaussian flank on each side.
  CHECK(mu(MfKind::Gaussian2, {1, 2, 0.5, 3}, 2.5) == 1.0);
  CHECK(mu(MfKind::Gaussian2, {1, 2, 0.5, 3}, 1) == Approx(std::exp(-0.5)).epsilon(1e-15));
  CHECK(mu(MfKind::Gaussian2, {1, 2, 0.5, 3}, 3.5) == Approx(std::exp(-0.5)).epsilon(1e-15));
  // c1 > c2: both flanks apply between them and the top is below 1 (MATLAB gauss2mf.m).
  CHECK(mu(MfKind::Gaussian2, {1, 3, 1, 2}, 2.5) == Approx(std::exp(-0.125) * std::exp(-0.125)).epsilon(1e-15));
  CHECK(mu(MfKind::Gaussian2, {1, 2, 0.5, 3}, kInf) == 0.0);
  CHECK(mu(MfKind::Gaussian2, {1, 2, 0.5, 3}, -kInf) == 0.0);
}

TEST_CASE("gbellmf including MATLAB's b == 0 and b < 0 centre values", "[fuzzy-math]") {
  CHECK(mu(MfKind::GeneralizedBell, {2, 3, 1}, 1) == 1.0);
  CHECK(mu(MfKind::GeneralizedBell, {2, 3, 1}, 3) == 0.5);  // |x - c| == a gives 1/2 for every b
  CHECK(mu(MfKind::GeneralizedBell, {2, 1, 0}, 4) == Approx(1.0 / (1.0 + 4.0)).epsilon(1e-15));
  CHECK(mu(MfKind::GeneralizedBell, {2, 0, 1}, 1) == 0.5);   // fis.c: tmp == 0 && b == 0 -> 0.5
  CHECK(mu(MfKind::GeneralizedBell, {2, -1, 1}, 1) == 0.0);  // fis.c: tmp == 0 && b < 0 -> 0
  CHECK(mu(MfKind::GeneralizedBell, {2, 3, 1}, kInf) == 0.0);
  CHECK(mu(MfKind::GeneralizedBell, {2, 3, 1}, -kInf) == 0.0);
  CHECK(mu(MfKind::GeneralizedBell, {2, -1, 1}, kInf) == 1.0);
}

TEST_CASE("sigmf, dsigmf, psigmf", "[fuzzy-math]") {
  CHECK(mu(MfKind::Sigmoid, {2, 1}, 1) == 0.5);
  CHECK(mu(MfKind::Sigmoid, {2, 1}, 2) == Approx(1.0 / (1.0 + std::exp(-2.0))).epsilon(1e-15));
  CHECK(mu(MfKind::Sigmoid, {2, 1}, kInf) == 1.0);
  CHECK(mu(MfKind::Sigmoid, {2, 1}, -kInf) == 0.0);
  CHECK(mu(MfKind::Sigmoid, {-2, 1}, kInf) == 0.0);
  CHECK(mu(MfKind::Sigmoid, {0, 1}, kInf) == 0.5);  // a == 0 is flat: the limit is 0.5, not 0 * inf
  CHECK(mu(MfKind::Sigmoid, {0, 1}, -3) == 0.5);
  const double s1 = 1.0 / (1.0 + std::exp(-5.0 * (4.0 - 2.0)));
  const double s2 = 1.0 / (1.0 + std::exp(-5.0 * (4.0 - 7.0)));
  CHECK(mu(MfKind::DifferenceSigmoid, {5, 2, 5, 7}, 4) == Approx(s1 - s2).epsilon(1e-15));
  // MATLAB takes the absolute difference (dsigmf.m, fis.c).
  CHECK(mu(MfKind::DifferenceSigmoid, {5, 7, 5, 2}, 4) == Approx(s1 - s2).epsilon(1e-15));
  CHECK(mu(MfKind::DifferenceSigmoid, {5, 2, 5, 7}, kInf) == 0.0);
  const double p1 = 1.0 / (1.0 + std::exp(-2.0 * (5.0 - 3.0)));
  const double p2 = 1.0 / (1.0 + std::exp(5.0 * (5.0 - 8.0)));
  CHECK(mu(MfKind::ProductSigmoid, {2, 3, -5, 8}, 5) == Approx(p1 * p2).epsilon(1e-15));
  CHECK(mu(MfKind::ProductSigmoid, {2, 3, -5, 8}, kInf) == 0.0);
  CHECK(mu(MfKind::ProductSigmoid, {2, 3, -5, 8}, -kInf) == 0.0);
}

TEST_CASE("smf, zmf, pimf with MATLAB's step for a >= b", "[fuzzy-math]") {
  CHECK(mu(MfKind::SShape, {1, 3}, 1) == 0.0);
  CHECK(mu(MfKind::SShape, {1, 3}, 1.5) == 0.125);  // 2 ((1.5-1)/2)^2
  CHECK(mu(MfKind::SShape, {1, 3}, 2) == 0.5);
  CHECK(mu(MfKind::SShape, {1, 3}, 2.5) == 0.875);  // 1 - 2 ((3-2.5)/2)^2
  CHECK(mu(MfKind::SShape, {1, 3}, 3) == 1.0);
  CHECK(mu(MfKind::SShape, {1, 3}, kInf) == 1.0);
  CHECK(mu(MfKind::SShape, {1, 3}, -kInf) == 0.0);
  CHECK(mu(MfKind::SShape, {3, 1}, 2) == 1.0);  // a >= b: x >= (a+b)/2
  CHECK(mu(MfKind::SShape, {3, 1}, 1.999) == 0.0);
  CHECK(mu(MfKind::SShape, {2, 2}, 2) == 1.0);
  CHECK(mu(MfKind::ZShape, {1, 3}, 1) == 1.0);
  CHECK(mu(MfKind::ZShape, {1, 3}, 1.5) == 0.875);
  CHECK(mu(MfKind::ZShape, {1, 3}, 2) == 0.5);
  CHECK(mu(MfKind::ZShape, {1, 3}, 2.5) == 0.125);
  CHECK(mu(MfKind::ZShape, {1, 3}, 3) == 0.0);
  CHECK(mu(MfKind::ZShape, {1, 3}, -kInf) == 1.0);
  CHECK(mu(MfKind::ZShape, {1, 3}, kInf) == 0.0);
  CHECK(mu(MfKind::ZShape, {3, 1}, 2) == 1.0);  // a >= b: x <= (a+b)/2
  CHECK(mu(MfKind::ZShape, {3, 1}, 2.001) == 0.0);
  CHECK(mu(MfKind::PiShape, {1, 3, 5, 7}, 4) == 1.0);
  CHECK(mu(MfKind::PiShape, {1, 3, 5, 7}, 2) == 0.5);
  CHECK(mu(MfKind::PiShape, {1, 3, 5, 7}, 6) == 0.5);
  CHECK(mu(MfKind::PiShape, {1, 3, 5, 7}, 0) == 0.0);
  CHECK(mu(MfKind::PiShape, {1, 3, 5, 7}, kInf) == 0.0);
}

TEST_CASE("linsmf and linzmf, including the crisp step a == b", "[fuzzy-math]") {
  CHECK(mu(MfKind::LinearS, {2, 4}, 1) == 0.0);
  CHECK(mu(MfKind::LinearS, {2, 4}, 2) == 0.0);
  CHECK(mu(MfKind::LinearS, {2, 4}, 3) == 0.5);
  CHECK(mu(MfKind::LinearS, {2, 4}, 4) == 1.0);
  CHECK(mu(MfKind::LinearS, {2, 4}, kInf) == 1.0);
  CHECK(mu(MfKind::LinearS, {3, 3}, 2.999) == 0.0);
  CHECK(mu(MfKind::LinearS, {3, 3}, 3) == 1.0);
  CHECK(mu(MfKind::LinearZ, {2, 4}, 1) == 1.0);
  CHECK(mu(MfKind::LinearZ, {2, 4}, 3.5) == 0.25);  // Octave linzmf test: 0.25 at 3.5 for [2 4]
  CHECK(mu(MfKind::LinearZ, {2, 4}, 4) == 0.0);
  CHECK(mu(MfKind::LinearZ, {2, 4}, -kInf) == 1.0);
  CHECK(mu(MfKind::LinearZ, {3, 3}, 2.999) == 1.0);
  CHECK(mu(MfKind::LinearZ, {3, 3}, 3) == 0.0);
}

TEST_CASE("NaN in gives NaN out for every family, and grades stay in [0, 1]", "[fuzzy-math]") {
  std::mt19937_64 random(12345);
  std::uniform_real_distribution<double> uniform(-10.0, 20.0);
  for (const auto& [kind, params] : every_input_family()) {
    INFO("kind " << static_cast<int>(kind));
    CHECK(std::isnan(mu(kind, params, kNaN)));
    for (int k = 0; k < 2000; ++k) {
      const double grade = mu(kind, params, uniform(random));
      CHECK(grade >= 0.0);
      CHECK(grade <= 1.0);
    }
    for (double x : {kInf, -kInf}) {
      const double grade = mu(kind, params, x);
      CHECK_FALSE(std::isnan(grade));
    }
  }
  CHECK(std::isnan(mu(MfKind::Constant, {1}, 0.5)));  // Sugeno functions are not grades
  CHECK(std::isnan(mu(MfKind::Linear, {1, 2}, 0.5)));
}

TEST_CASE("float evaluation agrees with double to float rounding", "[fuzzy-math]") {
  for (const auto& [kind, params] : every_input_family()) {
    std::vector<float> float_params(params.begin(), params.end());
    float_params.resize(4, 0.0f);
    for (int k = 0; k <= 100; ++k) {
      const double x = -1.0 + 0.1 * k;
      const float grade = fmpc::membership(kind, float_params.data(), static_cast<float>(x));
      CHECK(static_cast<double>(grade) == Approx(mu(kind, params, static_cast<double>(static_cast<float>(x))))
                                              .margin(1e-6));
    }
    CHECK(std::isnan(fmpc::membership(kind, float_params.data(), std::numeric_limits<float>::quiet_NaN())));
  }
}

TEST_CASE("t-norms and s-norms against hand values, NaN propagation", "[fuzzy-math]") {
  using fmpc::SNorm;
  using fmpc::TNorm;
  CHECK(fmpc::tnorm(TNorm::Minimum, 0.3, 0.7) == 0.3);
  CHECK(fmpc::tnorm(TNorm::Product, 0.5, 0.25) == 0.125);
  CHECK(fmpc::tnorm(TNorm::EinsteinProduct, 0.5, 0.5) == Approx(0.25 / (2.0 - 0.75)).epsilon(1e-15));
  CHECK(fmpc::tnorm(TNorm::EinsteinProduct, 1.0, 0.37) == 0.37);  // 1 is the identity
  CHECK(fmpc::tnorm(TNorm::EinsteinProduct, 0.0, 0.37) == 0.0);
  CHECK(fmpc::snorm(SNorm::Maximum, 0.3, 0.7) == 0.7);
  CHECK(fmpc::snorm(SNorm::ProbabilisticSum, 0.5, 0.5) == 0.75);
  CHECK(fmpc::snorm(SNorm::Sum, 0.75, 0.5) == 1.25);  // MATLAB's sum is not clipped
  CHECK(fmpc::snorm(SNorm::EinsteinSum, 0.5, 0.5) == 0.8);
  CHECK(fmpc::snorm(SNorm::EinsteinSum, 0.0, 0.37) == 0.37);  // 0 is the identity
  for (auto norm : {TNorm::Minimum, TNorm::Product, TNorm::EinsteinProduct}) {
    CHECK(std::isnan(fmpc::tnorm(norm, kNaN, 0.5)));
    CHECK(std::isnan(fmpc::tnorm(norm, 0.5, kNaN)));
    CHECK(fmpc::tnorm(norm, fmpc::tnorm_identity<double>(), 0.42) == Approx(0.42).epsilon(1e-15));
  }
  for (auto norm : {SNorm::Maximum, SNorm::ProbabilisticSum, SNorm::Sum, SNorm::EinsteinSum}) {
    CHECK(std::isnan(fmpc::snorm(norm, kNaN, 0.5)));
    CHECK(std::isnan(fmpc::snorm(norm, 0.5, kNaN)));
    CHECK(fmpc::snorm(norm, fmpc::snorm_identity<double>(), 0.42) == Approx(0.42).epsilon(1e-15));
  }
  // Einstein norms stay t-norm / s-norm bounded on [0, 1]^2.
  std::mt19937_64 random(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int k = 0; k < 1000; ++k) {
    const double a = unit(random), b = unit(random);
    CHECK(fmpc::tnorm(TNorm::EinsteinProduct, a, b) <= std::min(a, b) + 1e-15);
    CHECK(fmpc::snorm(SNorm::EinsteinSum, a, b) >= std::max(a, b) - 1e-15);
    CHECK(fmpc::snorm(SNorm::EinsteinSum, a, b) <= 1.0 + 1e-15);
  }
}

TEST_CASE("hedges are powers and NOT is the complement, hedge first", "[fuzzy-math]") {
  CHECK(fmpc::apply_hedge(0.25, 0.5) == 0.5);
  CHECK(fmpc::apply_hedge(0.5, 2.0) == 0.25);
  CHECK(fmpc::apply_hedge(0.5, 3.0) == 0.125);
  CHECK(fmpc::apply_hedge(0.5, 4.0) == 0.0625);
  CHECK(fmpc::apply_hedge(0.3, 1.0) == 0.3);
  CHECK(fmpc::fuzzy_not(fmpc::apply_hedge(0.5, 2.0)) == 0.75);
  CHECK(std::isnan(fmpc::apply_hedge(kNaN, 2.0)));
  CHECK(std::isnan(fmpc::fuzzy_not(kNaN)));
}
