#include "compiler/eval/defuzzify.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>

#include "kernels/fuzzy_math.h"

namespace fmpc {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Maximising x: MATLAB's som/lom pick the smallest/largest magnitude, the first one on ties (fis.c
// defuzzSmallestOfMax / defuzzLargestOfMax compare strictly); Octave's pick the smallest/largest signed x.
bool preferred_for_som(double candidate, double best, Reference reference) {
  if (reference == Reference::Octave) return candidate < best;
  return std::fabs(candidate) < std::fabs(best);
}
bool preferred_for_lom(double candidate, double best, Reference reference) {
  if (reference == Reference::Octave) return candidate > best;
  return std::fabs(candidate) > std::fabs(best);
}

}  // namespace

std::vector<double> output_sample_points(double min, double max, int count, Reference reference) {
  const auto n = static_cast<std::size_t>(std::max(count, 1));
  std::vector<double> x(n, min);
  if (n < 2) return x;
  const double step = (max - min) / static_cast<double>(n - 1);
  for (std::size_t k = 0; k < n; ++k) x[k] = min + step * static_cast<double>(k);
  if (reference == Reference::Octave) x[n - 1] = max;  // Octave's linspace ends on the limit exactly
  return x;
}

std::optional<double> defuzzify_sampled(Defuzzifier method, const std::vector<double>& x,
                                        const std::vector<double>& grade, Reference reference) {
  const std::size_t n = std::min(x.size(), grade.size());
  if (n == 0) return std::nullopt;
  double total = 0.0;
  double peak = grade[0];
  for (std::size_t k = 0; k < n; ++k) {
    if (std::isnan(grade[k])) return kNaN;
    total += grade[k];
    peak = std::max(peak, grade[k]);
  }
  if (total == 0.0) return std::nullopt;

  switch (method) {
    case Defuzzifier::Centroid: {
      if (reference == Reference::Octave) {
        // Octave defuzz.m: trapz(x, x .* y) / trapz(x, y).
        double area = 0.0, moment = 0.0;
        for (std::size_t k = 0; k + 1 < n; ++k) {
          const double width = x[k + 1] - x[k];
          area += width * (grade[k] + grade[k + 1]);
          moment += width * (x[k] * grade[k] + x[k + 1] * grade[k + 1]);
        }
        if (area == 0.0) return std::nullopt;
        return moment / area;
      }
      double moment = 0.0;
      for (std::size_t k = 0; k < n; ++k) moment += grade[k] * x[k];
      return moment / total;
    }
    case Defuzzifier::Bisector: {
      double running = 0.0;
      for (std::size_t k = 0; k < n; ++k) {
        running += grade[k];
        if (running >= total / 2.0) return x[k];
      }
      return x[n - 1];
    }
    case Defuzzifier::MeanOfMaximum: {
      double sum = 0.0;
      std::size_t count = 0;
      for (std::size_t k = 0; k < n; ++k)
        if (grade[k] == peak) {
          sum += x[k];
          ++count;
        }
      return sum / static_cast<double>(count);
    }
    case Defuzzifier::SmallestOfMaximum:
    case Defuzzifier::LargestOfMaximum: {
      bool found = false;
      double best = 0.0;
      for (std::size_t k = 0; k < n; ++k) {
        if (grade[k] != peak) continue;
        const bool better = method == Defuzzifier::SmallestOfMaximum ? preferred_for_som(x[k], best, reference)
                                                                     : preferred_for_lom(x[k], best, reference);
        if (!found || better) best = x[k];
        found = true;
      }
      return best;
    }
    case Defuzzifier::WeightedAverage:
    case Defuzzifier::WeightedSum: break;  // Sugeno methods: not a sampled set
  }
  return kNaN;
}

// ---------------------------------------------------------------------------------------------------------------
// Exact aggregates

namespace {

double implied_grade(const ImpliedConsequent& rule, TNorm implication, double y) {
  double mu = membership(rule.kind, rule.params.data(), y);
  mu = apply_hedge(mu, rule.hedge_exponent);
  if (rule.negated) mu = fuzzy_not(mu);
  return tnorm(implication, rule.firing, mu);
}

double consequent_grade(const ImpliedConsequent& rule, double y) {
  double mu = membership(rule.kind, rule.params.data(), y);
  if (rule.negated) mu = fuzzy_not(mu);
  return mu;
}

bool is_piecewise_linear_kind(MfKind kind) {
  return kind == MfKind::Triangle || kind == MfKind::Trapezoid || kind == MfKind::LinearS ||
         kind == MfKind::LinearZ;
}

void sort_unique(std::vector<double>& values) {
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
}

// Every MF parameter inside (min, max): the kinks and jumps of piecewise-linear MFs, the centres of smooth ones.
std::vector<double> parameter_knots(const ExactAggregate& aggregate) {
  std::vector<double> knots{aggregate.min, aggregate.max};
  for (const auto& rule : aggregate.rules)
    for (double p : rule.params)
      if (p > aggregate.min && p < aggregate.max) knots.push_back(p);
  sort_unique(knots);
  return knots;
}

// The straight piece of f on the open interval (u, v), as its limits at u and v: evaluated at two interior points
// and extrapolated, so that a jump at u or v (trapmf with a == b) does not leak in.
template <typename Function>
void line_limits(const Function& f, double u, double v, double& at_u, double& at_v) {
  const double h = v - u;
  const double f1 = f(u + h / 4.0);
  const double f3 = f(u + 3.0 * h / 4.0);
  at_u = f1 - (f3 - f1) / 2.0;
  at_v = f3 + (f3 - f1) / 2.0;
}

// One straight piece of the aggregate: from (y0, g0) to (y1, g1).
struct Piece {
  double y0, y1, g0, g1;
};

// The aggregate of a piecewise-linear system as straight pieces, exactly (up to rounding).
std::vector<Piece> linear_pieces(const ExactAggregate& aggregate) {
  std::vector<double> knots = parameter_knots(aggregate);
  if (aggregate.implication == TNorm::Minimum) {
    // min(w, mf) bends where mf crosses w.
    std::vector<double> crossings;
    for (std::size_t k = 0; k + 1 < knots.size(); ++k) {
      const double u = knots[k], v = knots[k + 1];
      for (const auto& rule : aggregate.rules) {
        double at_u = 0.0, at_v = 0.0;
        line_limits([&](double y) { return consequent_grade(rule, y); }, u, v, at_u, at_v);
        const double w = rule.firing;
        if ((at_u - w) * (at_v - w) < 0.0) crossings.push_back(u + (w - at_u) / (at_v - at_u) * (v - u));
      }
    }
    knots.insert(knots.end(), crossings.begin(), crossings.end());
    sort_unique(knots);
  }

  std::vector<Piece> pieces;
  std::vector<double> left(aggregate.rules.size()), right(aggregate.rules.size());
  for (std::size_t k = 0; k + 1 < knots.size(); ++k) {
    const double u = knots[k], v = knots[k + 1];
    if (!(v > u)) continue;
    for (std::size_t r = 0; r < aggregate.rules.size(); ++r)
      line_limits([&](double y) { return implied_grade(aggregate.rules[r], aggregate.implication, y); }, u, v,
                  left[r], right[r]);
    if (aggregate.aggregation == SNorm::Sum || aggregate.rules.empty()) {
      double g0 = 0.0, g1 = 0.0;
      for (std::size_t r = 0; r < aggregate.rules.size(); ++r) {
        g0 += left[r];
        g1 += right[r];
      }
      pieces.push_back({u, v, g0, g1});
      continue;
    }
    // Maximum: the upper envelope of straight lines over s in [0, 1], walked from the left.
    auto value = [&](std::size_t r, double s) { return left[r] + (right[r] - left[r]) * s; };
    std::size_t current = 0;
    for (std::size_t r = 1; r < aggregate.rules.size(); ++r) {
      const double slope_r = right[r] - left[r], slope_c = right[current] - left[current];
      if (left[r] > left[current] || (left[r] == left[current] && slope_r > slope_c)) current = r;
    }
    double s = 0.0;
    while (s < 1.0) {
      const double slope_c = right[current] - left[current];
      double next_s = 1.0;
      std::size_t next = current;
      for (std::size_t r = 0; r < aggregate.rules.size(); ++r) {
        const double slope_r = right[r] - left[r];
        if (slope_r <= slope_c) continue;
        const double crossing = (left[current] - left[r]) / (slope_r - slope_c);
        if (crossing > s && (crossing < next_s || (crossing == next_s && slope_r > right[next] - left[next]))) {
          next_s = crossing;
          next = r;
        }
      }
      const double y0 = u + (v - u) * s, y1 = next_s >= 1.0 ? v : u + (v - u) * next_s;
      pieces.push_back({y0, y1, value(current, s), value(current, next_s)});
      s = next_s;
      current = next;
    }
  }
  return pieces;
}

// Gauss-Kronrod 7/15 (QUADPACK qk15 abscissae and weights).
constexpr double kKronrodNodes[8] = {0.991455371120812639206854697526329, 0.949107912342758524526189684047851,
                                     0.864864423359769072789712788640926, 0.741531185599394439863864773280788,
                                     0.586087235467691130294144845693013, 0.405845151377397166906606412076961,
                                     0.207784955007898467600689403773245, 0.0};
constexpr double kKronrodWeights[8] = {0.022935322010529224963732008058970, 0.063092092629978553290700663189204,
                                       0.104790010322250183839876322541518, 0.140653259715525918745189590510238,
                                       0.169004726639267902826583426598550, 0.190350578064785409913256402421014,
                                       0.204432940075298892414161999234649, 0.209482141084727828012999174891714};
constexpr double kGaussWeights[4] = {0.129484966168869693270611432679082, 0.279705391489276667901467771423780,
                                     0.381830050505118944950369775488975, 0.417959183673469387755102040816327};

struct QuadratureInterval {
  double a, b;
  double area, moment;
  double area_error, moment_error;
  bool operator<(const QuadratureInterval& other) const {  // for the max-heap: largest error on top
    return area_error + moment_error < other.area_error + other.moment_error;
  }
};

template <typename Function>
QuadratureInterval kronrod15(const Function& f, double a, double b, std::vector<double>* points) {
  const double centre = (a + b) / 2.0, half = (b - a) / 2.0;
  double kronrod_area = 0.0, kronrod_moment = 0.0, gauss_area = 0.0, gauss_moment = 0.0;
  for (int k = 0; k < 8; ++k) {
    const int sides = k == 7 ? 1 : 2;
    for (int side = 0; side < sides; ++side) {
      const double y = side == 0 ? centre - half * kKronrodNodes[k] : centre + half * kKronrodNodes[k];
      const double g = f(y);
      if (points) points->push_back(y);
      kronrod_area += kKronrodWeights[k] * g;
      kronrod_moment += kKronrodWeights[k] * g * y;
      if (k % 2 == 1) {
        gauss_area += kGaussWeights[k / 2] * g;
        gauss_moment += kGaussWeights[k / 2] * g * y;
      }
    }
  }
  return {a,
          b,
          kronrod_area * half,
          kronrod_moment * half,
          std::fabs((kronrod_area - gauss_area) * half),
          std::fabs((kronrod_moment - gauss_moment) * half)};
}

constexpr double kRelativeTolerance = 1e-10;
constexpr std::size_t kMaxIntervals = 200000;

// Which smooth branch the aggregate follows at y: for each rule whether min(w, mu) is clipped at w, and for max
// aggregation which rule is on top. Between changes of this signature the aggregate is one smooth expression.
std::size_t branch_signature(const ExactAggregate& aggregate, double y) {
  std::size_t signature = 1469598103934665603ull;  // FNV-1a
  auto mix = [&](std::size_t value) { signature = (signature ^ value) * 1099511628211ull; };
  double top = -1.0;
  std::size_t top_rule = 0;
  for (std::size_t r = 0; r < aggregate.rules.size(); ++r) {
    const ImpliedConsequent& rule = aggregate.rules[r];
    double mu = membership(rule.kind, rule.params.data(), y);
    mu = apply_hedge(mu, rule.hedge_exponent);
    if (rule.negated) mu = fuzzy_not(mu);
    if (aggregate.implication == TNorm::Minimum) mix(mu > rule.firing ? 1 : 0);
    const double implied = tnorm(aggregate.implication, rule.firing, mu);
    if (implied > top) {
      top = implied;
      top_rule = r;
    }
  }
  if (aggregate.aggregation == SNorm::Maximum) mix(top_rule + 2);
  return signature;
}

// The kinks of the aggregate that are not MF parameters (where a rule starts or stops being clipped, where the
// maximum changes rule): located by scanning each knot interval and bisecting every change of branch to
// rounding. Gauss-Kronrod then only sees smooth pieces, whose error estimates are reliable.
std::vector<double> branch_knots(const ExactAggregate& aggregate, const std::vector<double>& knots) {
  constexpr int kScanPoints = 64;
  std::vector<double> found;
  for (std::size_t k = 0; k + 1 < knots.size(); ++k) {
    const double u = knots[k], v = knots[k + 1];
    double previous_y = u + (v - u) * 1e-9;
    std::size_t previous = branch_signature(aggregate, previous_y);
    for (int step = 1; step <= kScanPoints; ++step) {
      const double y = step == kScanPoints ? v - (v - u) * 1e-9 : u + (v - u) * step / kScanPoints;
      const std::size_t signature = branch_signature(aggregate, y);
      if (signature != previous) {
        double lo = previous_y, hi = y;
        for (int iteration = 0; iteration < 80 && hi - lo > 0.0; ++iteration) {
          const double middle = lo + (hi - lo) / 2.0;
          if (!(middle > lo && middle < hi)) break;
          if (branch_signature(aggregate, middle) == previous) lo = middle;
          else hi = middle;
        }
        found.push_back(hi);
      }
      previous = signature;
      previous_y = y;
    }
  }
  return found;
}

// Global adaptive Gauss-Kronrod (QUADPACK QAG style) over the smooth pieces: split the interval with the largest
// error until the summed error estimates meet the tolerance. Returns the final intervals sorted by position.
std::vector<QuadratureInterval> adaptive_integration(const ExactAggregate& aggregate) {
  auto f = [&](double y) { return aggregate.grade(y); };
  std::vector<double> knots = parameter_knots(aggregate);
  for (const auto& rule : aggregate.rules)  // smf / zmf / pimf switch parabola at the middle of each edge
    if (rule.kind == MfKind::SShape || rule.kind == MfKind::ZShape || rule.kind == MfKind::PiShape)
      for (std::size_t p = 0; p + 1 < rule.params.size(); p += 2) {
        const double middle = (rule.params[p] + rule.params[p + 1]) / 2.0;
        if (middle > aggregate.min && middle < aggregate.max) knots.push_back(middle);
      }
  sort_unique(knots);
  const std::vector<double> kinks = branch_knots(aggregate, knots);
  knots.insert(knots.end(), kinks.begin(), kinks.end());
  sort_unique(knots);
  std::priority_queue<QuadratureInterval> queue;
  double area = 0.0, area_error = 0.0, moment_error = 0.0;
  for (std::size_t k = 0; k + 1 < knots.size(); ++k) {
    if (!(knots[k + 1] > knots[k])) continue;
    QuadratureInterval piece = kronrod15(f, knots[k], knots[k + 1], nullptr);
    area += piece.area;
    area_error += piece.area_error;
    moment_error += piece.moment_error;
    queue.push(piece);
  }
  const double scale = std::max({std::fabs(aggregate.min), std::fabs(aggregate.max), aggregate.max - aggregate.min});
  while (!queue.empty() && queue.size() < kMaxIntervals) {
    const double area_goal = kRelativeTolerance * std::fabs(area);
    if (area_error <= area_goal && moment_error <= area_goal * scale) break;
    const QuadratureInterval worst = queue.top();
    const double middle = (worst.a + worst.b) / 2.0;
    if (!(middle > worst.a && middle < worst.b)) break;  // cannot split further in double
    queue.pop();
    const QuadratureInterval left = kronrod15(f, worst.a, middle, nullptr);
    const QuadratureInterval right = kronrod15(f, middle, worst.b, nullptr);
    area += left.area + right.area - worst.area;
    area_error += left.area_error + right.area_error - worst.area_error;
    moment_error += left.moment_error + right.moment_error - worst.moment_error;
    queue.push(left);
    queue.push(right);
  }
  std::vector<QuadratureInterval> intervals;
  intervals.reserve(queue.size());
  while (!queue.empty()) {
    intervals.push_back(queue.top());
    queue.pop();
  }
  std::sort(intervals.begin(), intervals.end(),
            [](const QuadratureInterval& x, const QuadratureInterval& y) { return x.a < y.a; });
  return intervals;
}

// The maximising set of straight pieces: som / lom / mom in the continuous sense (docs/numerics.md).
std::optional<double> maximum_of_pieces(Defuzzifier method, const std::vector<Piece>& pieces, Reference reference) {
  double peak = 0.0;
  for (const auto& piece : pieces) peak = std::max({peak, piece.g0, piece.g1});
  if (peak <= 0.0) return std::nullopt;
  const double tolerance = 1e-12 * peak;
  struct Span {
    double a, b;
  };
  std::vector<Span> spans;  // maximising intervals (a < b) and points (a == b), in increasing y
  for (const auto& piece : pieces) {
    const bool left_max = piece.g0 >= peak - tolerance, right_max = piece.g1 >= peak - tolerance;
    if (left_max && right_max) spans.push_back({piece.y0, piece.y1});
    else if (left_max) spans.push_back({piece.y0, piece.y0});
    else if (right_max) spans.push_back({piece.y1, piece.y1});
  }
  if (method == Defuzzifier::MeanOfMaximum) {
    double length = 0.0, weighted = 0.0, point_sum = 0.0;
    std::size_t point_count = 0;
    for (const auto& span : spans) {
      length += span.b - span.a;
      weighted += (span.b - span.a) * (span.a + span.b) / 2.0;
      point_sum += span.a;
      ++point_count;
    }
    if (length > 0.0) return weighted / length;
    return point_sum / static_cast<double>(point_count);
  }
  bool found = false;
  double best = 0.0;
  for (const auto& span : spans) {
    // In a span the candidates are its ends and, for the smallest magnitude, 0 when the span contains it.
    double candidates[3] = {span.a, span.b, span.a <= 0.0 && span.b >= 0.0 ? 0.0 : span.a};
    for (double candidate : candidates) {
      const bool better = method == Defuzzifier::SmallestOfMaximum ? preferred_for_som(candidate, best, reference)
                                                                   : preferred_for_lom(candidate, best, reference);
      if (!found || better) best = candidate;
      found = true;
    }
  }
  return best;
}

}  // namespace

double ExactAggregate::grade(double y) const {
  double total = snorm_identity<double>();
  for (const auto& rule : rules) total = snorm(aggregation, total, implied_grade(rule, implication, y));
  return total;
}

bool ExactAggregate::piecewise_linear() const {
  if (implication != TNorm::Minimum && implication != TNorm::Product) return false;
  if (aggregation != SNorm::Maximum && aggregation != SNorm::Sum) return false;
  for (const auto& rule : rules)
    if (!is_piecewise_linear_kind(rule.kind) || rule.hedge_exponent != 1.0) return false;
  return true;
}

ExactIntegrals integrate_exact(const ExactAggregate& aggregate) {
  ExactIntegrals result;
  if (aggregate.piecewise_linear()) {
    for (const auto& piece : linear_pieces(aggregate)) {
      const double h = piece.y1 - piece.y0;
      result.area += h * (piece.g0 + piece.g1) / 2.0;
      result.moment += h / 6.0 * (piece.g0 * (2.0 * piece.y0 + piece.y1) + piece.g1 * (piece.y0 + 2.0 * piece.y1));
      result.points.push_back(piece.y0);
      result.points.push_back(piece.y1);
    }
  } else {
    auto f = [&](double y) { return aggregate.grade(y); };
    for (const auto& interval : adaptive_integration(aggregate)) {
      result.area += interval.area;
      result.moment += interval.moment;
      kronrod15(f, interval.a, interval.b, &result.points);
    }
  }
  sort_unique(result.points);
  return result;
}

ExactDefuzzification defuzzify_exact(Defuzzifier method, const ExactAggregate& aggregate, Reference reference) {
  ExactDefuzzification result;
  const bool linear = aggregate.piecewise_linear();
  switch (method) {
    case Defuzzifier::Centroid: {
      ExactIntegrals integrals = integrate_exact(aggregate);
      result.points = std::move(integrals.points);
      if (integrals.area > 0.0) result.value = integrals.moment / integrals.area;
      else if (std::isnan(integrals.area)) result.value = kNaN;
      return result;
    }
    case Defuzzifier::Bisector: {
      if (linear) {
        const std::vector<Piece> pieces = linear_pieces(aggregate);
        double total = 0.0;
        for (const auto& piece : pieces) {
          total += (piece.y1 - piece.y0) * (piece.g0 + piece.g1) / 2.0;
          result.points.push_back(piece.y0);
          result.points.push_back(piece.y1);
        }
        sort_unique(result.points);
        if (!(total > 0.0)) return result;
        double running = 0.0;
        for (const auto& piece : pieces) {
          const double h = piece.y1 - piece.y0;
          const double piece_area = h * (piece.g0 + piece.g1) / 2.0;
          if (running + piece_area >= total / 2.0 && piece_area > 0.0) {
            // Area from y0 to y0 + t is g0 t + (g1 - g0) t^2 / (2h): solve for t (stable root).
            const double need = total / 2.0 - running;
            const double a = (piece.g1 - piece.g0) / (2.0 * h), b = piece.g0;
            const double t = 2.0 * need / (b + std::sqrt(std::max(0.0, b * b + 4.0 * a * need)));
            result.value = piece.y0 + std::min(std::max(t, 0.0), h);
            return result;
          }
          running += piece_area;
        }
        result.value = aggregate.max;
        return result;
      }
      auto f = [&](double y) { return aggregate.grade(y); };
      const std::vector<QuadratureInterval> intervals = adaptive_integration(aggregate);
      double total = 0.0;
      for (const auto& interval : intervals) {
        total += interval.area;
        kronrod15(f, interval.a, interval.b, &result.points);
      }
      sort_unique(result.points);
      if (!(total > 0.0)) return result;
      double running = 0.0;
      for (const auto& interval : intervals) {
        if (running + interval.area >= total / 2.0 && interval.area > 0.0) {
          const double need = total / 2.0 - running;
          double lo = interval.a, hi = interval.b;
          for (int iteration = 0; iteration < 200 && hi - lo > 1e-13 * (aggregate.max - aggregate.min); ++iteration) {
            const double middle = (lo + hi) / 2.0;
            if (kronrod15(f, interval.a, middle, nullptr).area < need) lo = middle;
            else hi = middle;
          }
          result.value = (lo + hi) / 2.0;
          return result;
        }
        running += interval.area;
      }
      result.value = aggregate.max;
      return result;
    }
    case Defuzzifier::MeanOfMaximum:
    case Defuzzifier::SmallestOfMaximum:
    case Defuzzifier::LargestOfMaximum: {
      if (linear) {
        const std::vector<Piece> pieces = linear_pieces(aggregate);
        for (const auto& piece : pieces) {
          result.points.push_back(piece.y0);
          result.points.push_back(piece.y1);
        }
        sort_unique(result.points);
        result.value = maximum_of_pieces(method, pieces, reference);
        return result;
      }
      constexpr int kDenseSamples = 100001;
      result.points = output_sample_points(aggregate.min, aggregate.max, kDenseSamples, reference);
      std::vector<double> grades(result.points.size());
      for (std::size_t k = 0; k < grades.size(); ++k) grades[k] = aggregate.grade(result.points[k]);
      result.value = defuzzify_sampled(method, result.points, grades, reference);
      return result;
    }
    case Defuzzifier::WeightedAverage:
    case Defuzzifier::WeightedSum: break;
  }
  result.value = kNaN;
  return result;
}

}  // namespace fmpc
