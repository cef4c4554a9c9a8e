#pragma once
// The reference the type-reduction tests hold KM, EKM and EIASC to: every switch point tried, each centroid summed
// in long double (x87 extended on x86-64: 64-bit significand, and an exponent range in which double's subnormal
// weights are normal numbers), so that it does not share the rounding of the kernels it checks
// (kernels/type_reduction_math.h). Also the tolerance those tests use and seeded adversarial interval sets.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace fmpc::testing {

struct ExactInterval {
  long double left = std::numeric_limits<long double>::quiet_NaN();
  long double right = std::numeric_limits<long double>::quiet_NaN();
  bool fired = false;
};

// yl = min_k and yr = max_k of the switched centroids (points 0..k-1 take `upper` for yl, `lower` for yr).
inline ExactInterval exact_type_reduction(const std::vector<double>& x, const std::vector<double>& lower,
                                          const std::vector<double>& upper) {
  ExactInterval result;
  const std::size_t n = x.size();
  result.fired = std::any_of(upper.begin(), upper.end(), [](double w) { return w > 0.0; });
  if (!result.fired) return result;
  for (std::size_t k = 0; k <= n; ++k) {
    long double left_sum = 0, left_weight = 0, right_sum = 0, right_weight = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const long double wl = i < k ? upper[i] : lower[i];
      const long double wr = i < k ? lower[i] : upper[i];
      left_sum += static_cast<long double>(x[i]) * wl;
      left_weight += wl;
      right_sum += static_cast<long double>(x[i]) * wr;
      right_weight += wr;
    }
    if (left_weight > 0) result.left = std::isnan(result.left) ? left_sum / left_weight
                                                               : std::min(result.left, left_sum / left_weight);
    if (right_weight > 0) result.right = std::isnan(result.right) ? right_sum / right_weight
                                                                  : std::max(result.right, right_sum / right_weight);
  }
  return result;
}

// 1e-12 of the points' range, or 2 ulps of the largest |x| where the range is narrower than the points' own
// resolution (points at 1e6 +- 1e-3 carry no more than that).
inline double type_reduction_tolerance(const std::vector<double>& x) {
  if (x.empty()) return 0.0;
  const double largest = std::max(std::fabs(x.front()), std::fabs(x.back()));
  return 1e-12 * (x.back() - x.front()) + 2.0 * std::numeric_limits<double>::epsilon() * largest;
}

struct IntervalSet {
  std::vector<double> x, lower, upper;
};

// The kinds of adversarial set adversarial_interval_set draws, in turn.
enum class AdversarialKind : int {
  Random = 0,         // zeros and equal ends common
  TinyLower,          // lower = upper * 1e-25 * u: the case (centroid rounds onto a sample)
  SubnormalLower,     // lower in the subnormal range, upper normal
  AllSubnormal,       // every weight subnormal
  EqualGrades,        // lower == upper, many equal values
  MassAtRightEnd,     // upper nonzero (beyond 1e-30) only at the last one or two points
  MassAtLeftEnd,      // ... at the first one or two
  GaussianBump,       // a sampled Gaussian upper set, lower 1e-25 or half of it
  ZeroLower,          // lower 0 everywhere, half the uppers 0
  TinySets,           // 1 to 4 points
  Count
};

// A seeded set of `kind`: sizes 1 to 257, points evenly spaced, random, or in heavy ties (four distinct values),
// around 0, -50 or 1e6, over a range of 10 or 1e-3.
inline IntervalSet adversarial_interval_set(std::mt19937_64& random, AdversarialKind kind) {
  const auto unit = [&random]() { return static_cast<double>(random() >> 11) * 0x1.0p-53; };
  static constexpr int kSizes[] = {1, 2, 3, 5, 12, 101, 101, 257};
  IntervalSet s;
  const int n = kind == AdversarialKind::TinySets ? 1 + static_cast<int>(random() % 4)
                                                  : kSizes[random() % (sizeof kSizes / sizeof kSizes[0])];
  const int spacing = static_cast<int>(random() % 4);
  const double offset = random() % 4 == 0 ? 1e6 : (random() % 3 == 0 ? -50.0 : 0.0);
  const double range = random() % 5 == 0 ? 1e-3 : 10.0;
  for (int i = 0; i < n; ++i) {
    const double even = n == 1 ? 0.5 : static_cast<double>(i) / (n - 1);
    double x = offset + range * even;
    if (spacing == 1) x = offset + range * unit();
    if (spacing == 2) x = offset + range * std::floor(unit() * 4) / 4;
    if (spacing == 3 && i > 0 && unit() < 0.3) x = s.x.back();
    else if (spacing == 3) x = offset + range * unit();
    s.x.push_back(x);
  }
  std::sort(s.x.begin(), s.x.end());
  const double first = s.x.front(), last = s.x.back();
  const double bump_centre = first + (last - first) * unit();
  const double bump_width = (last - first + 1e-300) * (0.02 + 0.3 * unit());
  for (int i = 0; i < n; ++i) {
    double a = unit(), b = unit();
    if (a > b) std::swap(a, b);
    switch (kind) {
      case AdversarialKind::Random:
        if (unit() < 0.15) a = 0.0;
        if (unit() < 0.1) b = a;
        if (unit() < 0.1) a = b = 0.0;
        break;
      case AdversarialKind::TinyLower:
        a = unit() < 0.1 ? 0.0 : b * 1e-25 * unit();
        break;
      case AdversarialKind::SubnormalLower:
        a = std::min(b, std::numeric_limits<double>::denorm_min() * static_cast<double>(random() % 1000));
        break;
      case AdversarialKind::AllSubnormal:
        b = std::numeric_limits<double>::denorm_min() * static_cast<double>(1 + random() % 100000);
        a = std::min(b, std::numeric_limits<double>::denorm_min() * static_cast<double>(random() % 100000));
        break;
      case AdversarialKind::EqualGrades:
        a = b = unit() < 0.5 ? 0.5 : unit();
        break;
      case AdversarialKind::MassAtRightEnd:
        b = i >= n - 1 - static_cast<int>(random() % 2) ? unit() : b * 1e-30;
        a = b * unit() * 1e-20;
        break;
      case AdversarialKind::MassAtLeftEnd:
        b = i <= static_cast<int>(random() % 2) ? unit() : b * 1e-30;
        a = b * unit() * 1e-20;
        break;
      case AdversarialKind::GaussianBump: {
        const double t = (s.x[static_cast<std::size_t>(i)] - bump_centre) / bump_width;
        b = std::exp(-0.5 * t * t);
        a = b * (unit() < 0.5 ? 1e-25 : 0.5) * unit();
        break;
      }
      case AdversarialKind::ZeroLower:
        a = 0.0;
        if (unit() < 0.5) b = 0.0;
        break;
      case AdversarialKind::TinySets:
        if (unit() < 0.3) a = 0.0;
        if (unit() < 0.3) b = a;
        break;
      case AdversarialKind::Count: break;
    }
    s.lower.push_back(a);
    s.upper.push_back(b);
  }
  return s;
}

// The text of a one-input interval type-2 Mamdani system (fmpc language) whose footprints leave lower grades of 1e-25 and less in the Gaussians' tails (the
// sds span a factor of 5, the means an interval), drawn from `seed`: where one rule fires weakly, the aggregated
// upper set holds its weight near one end of the output range and the lower set is almost zero, as in the
// issue's examples (tests/golden/it2_*_end_of_range).
inline std::string tail_system(std::uint64_t seed, const std::string& type_reduction) {
  std::mt19937_64 random(seed);
  const auto unit = [&random]() { return static_cast<double>(random() >> 11) * 0x1.0p-53; };
  const double range = seed % 3 == 0 ? 20.0 : 10.0;
  const int samples = seed % 4 == 0 ? 21 : 101;
  const double m1 = 10 * unit(), w1 = 0.3 + 2 * unit(), m2 = 10 * unit(), w2 = 0.3 + 2 * unit();
  const double c1 = range * unit(), s1 = 0.2 + 3 * unit(), c2 = range * (0.8 + 0.2 * unit()), s2 = 0.1 + 2 * unit();
  std::ostringstream text;
  text.precision(17);
  text << "system tail \"tail\"\n  type interval_type2 mamdani\n  type_reduction " << type_reduction
       << "\n  defuzzify centroid samples " << samples << "\n\ninput x \"in\" in [0, 10] kPa\n"
       << "  a is gauss(mean [" << m1 << ", " << m1 + unit() << "], sd " << w1 << ")\n"
       << "  b is gauss(mean " << m2 << ", sd [" << 0.3 * w2 << ", " << w2 << "])\n"
       << "output y \"out\" in [0, " << range << "] kPa\n"
       << "  p is gauss(mean " << c1 << ", sd [" << 0.2 * s1 << ", " << s1 << "])\n"
       << "  q is gauss(mean [" << c2 << ", " << std::min(range, c2 + 1) << "], sd " << s2 << ")\n"
       << "rule r1: if x is a then y is p\nrule r2: if x is b then y is q\n";
  return text.str();
}

}  // namespace fmpc::testing
