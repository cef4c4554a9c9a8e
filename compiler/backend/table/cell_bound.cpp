#include "compiler/backend/table/cell_bound.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <tuple>

#include "compiler/eval/defuzzify.h"
#include "kernels/fuzzy_math.h"
#include "kernels/type_reduction_math.h"

namespace fmpc {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// A closed interval of reals; [-inf, inf] stands for "unbounded" (a derivative that has no finite bound).
struct Interval {
  double lo = 0.0, hi = 0.0;
};

Interval point(double v) { return {v, v}; }
Interval unbounded() { return {-kInf, kInf}; }
bool is_zero(Interval a) { return a.lo == 0.0 && a.hi == 0.0; }
bool finite(Interval a) { return std::isfinite(a.lo) && std::isfinite(a.hi); }
double width(Interval a) { return a.hi - a.lo; }
Interval hull(Interval a, Interval b) { return {std::min(a.lo, b.lo), std::max(a.hi, b.hi)}; }
// Where round-to-nearest arithmetic met inf - inf or 0 * inf, nothing is known.
Interval checked(Interval a) { return std::isnan(a.lo) || std::isnan(a.hi) ? unbounded() : a; }

Interval operator+(Interval a, Interval b) { return checked({a.lo + b.lo, a.hi + b.hi}); }
Interval operator-(Interval a, Interval b) { return checked({a.lo - b.hi, a.hi - b.lo}); }
Interval operator-(Interval a) { return {-a.hi, -a.lo}; }
Interval operator*(Interval a, Interval b) {
  // An exact zero times anything is zero: a quantity that is 0 throughout the cell contributes nothing, even
  // beside a factor with an unbounded derivative.
  if (is_zero(a) || is_zero(b)) return point(0.0);
  const double p[4] = {a.lo * b.lo, a.lo * b.hi, a.hi * b.lo, a.hi * b.hi};
  Interval r{p[0], p[0]};
  for (double v : p) {
    if (std::isnan(v)) return unbounded();
    r.lo = std::min(r.lo, v);
    r.hi = std::max(r.hi, v);
  }
  return r;
}
Interval operator*(Interval a, double c) { return a * point(c); }
Interval operator/(Interval a, Interval b) {
  if (!(b.lo > 0.0 || b.hi < 0.0)) return unbounded();
  return a * Interval{1.0 / b.hi, 1.0 / b.lo};
}

// A quantity over the cell: the interval of its values and, per axis, the interval of its partial derivative.
struct Dual {
  Interval v;
  std::array<Interval, kMaxTableAxes> g{};
};

Dual constant(double c) {
  Dual d;
  d.v = point(c);
  return d;
}

// Arithmetic on Duals over the first `axes` axes: values by interval arithmetic, derivatives by the sum, product
// and quotient rules, min and max by their Clarke gradients (either operand's derivative where they may cross).
class DualArithmetic {
 public:
  explicit DualArithmetic(int axes) : axes_(axes) {}

  Dual add(const Dual& a, const Dual& b) const {
    Dual r;
    r.v = a.v + b.v;
    for (int i = 0; i < axes_; ++i) r.g[i] = a.g[i] + b.g[i];
    return r;
  }
  Dual sub(const Dual& a, const Dual& b) const {
    Dual r;
    r.v = a.v - b.v;
    for (int i = 0; i < axes_; ++i) r.g[i] = a.g[i] - b.g[i];
    return r;
  }
  Dual mul(const Dual& a, const Dual& b) const {
    Dual r;
    r.v = a.v * b.v;
    for (int i = 0; i < axes_; ++i) r.g[i] = a.g[i] * b.v + a.v * b.g[i];
    return r;
  }
  Dual scale(const Dual& a, double c) const {
    Dual r;
    r.v = a.v * c;
    for (int i = 0; i < axes_; ++i) r.g[i] = a.g[i] * c;
    return r;
  }
  Dual div(const Dual& a, const Dual& b) const {
    Dual r;
    r.v = a.v / b.v;
    for (int i = 0; i < axes_; ++i) r.g[i] = (a.g[i] - r.v * b.g[i]) / b.v;
    return r;
  }
  Dual min(const Dual& a, const Dual& b) const { return extremum(a, b, true); }
  Dual max(const Dual& a, const Dual& b) const { return extremum(a, b, false); }
  // The smaller (or larger) of two: the one surely on that side, else the hull of both derivatives (which one is
  // chosen may switch inside the cell).
  Dual extremum(const Dual& a, const Dual& b, bool smaller) const {
    if (a.v.hi <= b.v.lo) return smaller ? a : b;
    if (b.v.hi <= a.v.lo) return smaller ? b : a;
    Dual r;
    r.v = smaller ? Interval{std::min(a.v.lo, b.v.lo), std::min(a.v.hi, b.v.hi)}
                  : Interval{std::max(a.v.lo, b.v.lo), std::max(a.v.hi, b.v.hi)};
    for (int i = 0; i < axes_; ++i) r.g[i] = hull(a.g[i], b.g[i]);
    return r;
  }
  Dual abs(const Dual& a) const {
    if (a.v.lo >= 0.0) return a;
    Dual r;
    for (int i = 0; i < axes_; ++i) r.g[i] = -a.g[i];
    r.v = -a.v;
    if (a.v.hi <= 0.0) return r;
    r.v = {0.0, std::max(-a.v.lo, a.v.hi)};
    for (int i = 0; i < axes_; ++i) r.g[i] = hull(a.g[i], -a.g[i]);
    return r;
  }
  Dual complement(const Dual& a) const { return sub(constant(1.0), a); }
  // a^p for grades a >= 0 and p > 0 (hedges, Sugeno's w^(1/hedge)): nondecreasing in a; p a^(p-1) a' has no bound
  // where a reaches 0 and p < 1.
  Dual power(const Dual& a, double p) const {
    if (p == 1.0) return a;
    const double lo = std::max(0.0, a.v.lo), hi = std::max(0.0, a.v.hi);
    Dual r;
    r.v = {std::pow(lo, p), std::pow(hi, p)};
    Interval slope;
    if (p >= 1.0) slope = Interval{std::pow(lo, p - 1.0), std::pow(hi, p - 1.0)} * p;
    else slope = lo > 0.0 ? Interval{std::pow(hi, p - 1.0), std::pow(lo, p - 1.0)} * p : Interval{0.0, kInf};
    for (int i = 0; i < axes_; ++i) r.g[i] = a.g[i] * slope;
    return r;
  }
  Dual tnorm(TNorm norm, const Dual& a, const Dual& b) const {
    switch (norm) {
      case TNorm::Minimum: return min(a, b);
      case TNorm::Product: return mul(a, b);
      case TNorm::EinsteinProduct:
        // a b / (2 - (a + b - a b)), with the denominator written 1 + (1 - a)(1 - b): the same number, but in
        // interval arithmetic it stays within [1, 2] for grades in [0, 1] instead of spanning 0.
        return div(mul(a, b), add(constant(1.0), mul(complement(a), complement(b))));
    }
    return min(a, b);
  }
  Dual snorm(SNorm norm, const Dual& a, const Dual& b) const {
    switch (norm) {
      case SNorm::Maximum: return max(a, b);
      case SNorm::ProbabilisticSum: return sub(add(a, b), mul(a, b));
      case SNorm::Sum: return add(a, b);
      case SNorm::EinsteinSum: return div(add(a, b), add(constant(1.0), mul(a, b)));
    }
    return max(a, b);
  }

 private:
  int axes_;
};

// ---- membership functions over an interval of x ----------------------------------------------------------

// One of the pieces the membership families are built from, with its value, its derivative and the points where
// either changes monotonicity or jumps. Between consecutive such points both are monotone, so their ranges over
// [lo, hi] are spanned by their values at lo, hi and the points inside (evaluated one ulp to each side, which
// gives the one-sided limits at a kink or a step).
struct Primitive {
  enum class Kind { Rise, Fall, Gaussian, GaussianLeft, GaussianRight, Sigmoid, Bell, SShape, ZShape } kind;
  double p0 = 0.0, p1 = 0.0, p2 = 0.0;
  // Rise / Fall with equal ends: which value the step point itself takes (MATLAB's conventions differ by family).
  double step_value = 1.0;

  double value(double x) const {
    switch (kind) {
      case Kind::Rise:  // 0 below p0, linear to 1 at p1
        if (p0 == p1) return x < p0 ? 0.0 : (x == p0 ? step_value : 1.0);
        if (x <= p0) return 0.0;
        if (x >= p1) return 1.0;
        return (x - p0) / (p1 - p0);
      case Kind::Fall:  // 1 below p0, linear to 0 at p1
        if (p0 == p1) return x < p0 ? 1.0 : (x == p0 ? step_value : 0.0);
        if (x <= p0) return 1.0;
        if (x >= p1) return 0.0;
        return (p1 - x) / (p1 - p0);
      case Kind::Gaussian: return mf::gaussian(x, p0, p1);
      case Kind::GaussianLeft: return x <= p1 ? mf::gaussian(x, p0, p1) : 1.0;
      case Kind::GaussianRight: return x >= p1 ? mf::gaussian(x, p0, p1) : 1.0;
      case Kind::Sigmoid: return mf::sigmoid(x, p0, p1);
      case Kind::Bell: return mf::generalized_bell(x, p0, p1, p2);
      case Kind::SShape: return mf::s_shape(x, p0, p1);
      case Kind::ZShape: return mf::z_shape(x, p0, p1);
    }
    return 0.0;
  }

  // The derivative away from the points (at a point, the caller evaluates one ulp to a side).
  double slope(double x) const {
    switch (kind) {
      case Kind::Rise: return p0 < x && x < p1 ? 1.0 / (p1 - p0) : 0.0;
      case Kind::Fall: return p0 < x && x < p1 ? -1.0 / (p1 - p0) : 0.0;
      case Kind::Gaussian: return -(x - p1) / (p0 * p0) * mf::gaussian(x, p0, p1);
      case Kind::GaussianLeft: return x < p1 ? -(x - p1) / (p0 * p0) * mf::gaussian(x, p0, p1) : 0.0;
      case Kind::GaussianRight: return x > p1 ? -(x - p1) / (p0 * p0) * mf::gaussian(x, p0, p1) : 0.0;
      case Kind::Sigmoid: {
        const double s = mf::sigmoid(x, p0, p1);
        return p0 * s * (1.0 - s);
      }
      case Kind::Bell: {
        // f = 1 / (1 + u^b), u = t^2, t = (x - c) / a: f' = -b u^(b-1) 2 t / a / (1 + u^b)^2.
        const double t = (x - p2) / p0, u = t * t;
        if (u == 0.0) return p1 > 0.5 ? 0.0 : (p1 == 0.5 ? 0.0 : kInf);
        const double ub = std::pow(u, p1);
        return -p1 * (ub / u) * 2.0 * t / p0 / ((1.0 + ub) * (1.0 + ub));
      }
      case Kind::SShape: {
        if (p0 >= p1) return 0.0;
        const double m = (p0 + p1) / 2.0, w = (p1 - p0) * (p1 - p0);
        if (x <= p0 || x >= p1) return 0.0;
        return x <= m ? 4.0 * (x - p0) / w : 4.0 * (p1 - x) / w;
      }
      case Kind::ZShape: {
        if (p0 >= p1) return 0.0;
        const double m = (p0 + p1) / 2.0, w = (p1 - p0) * (p1 - p0);
        if (x <= p0 || x >= p1) return 0.0;
        return x <= m ? -4.0 * (x - p0) / w : -4.0 * (p1 - x) / w;
      }
    }
    return 0.0;
  }

  // Where the value or the derivative changes monotonicity (`smooth`: the function is differentiable there),
  // has a kink (`kinks`), or jumps (`steps`, also listed as kinks).
  void points(std::vector<double>& smooth, std::vector<double>& kinks, std::vector<double>& steps) const {
    switch (kind) {
      case Kind::Rise:
      case Kind::Fall:
        if (p0 == p1) steps.push_back(p0);
        kinks.insert(kinks.end(), {p0, p1});
        return;
      case Kind::Gaussian: smooth.insert(smooth.end(), {p1 - std::fabs(p0), p1, p1 + std::fabs(p0)}); return;
      case Kind::GaussianLeft:
        smooth.push_back(p1 - std::fabs(p0));
        kinks.push_back(p1);  // C1 there, but its second derivative jumps: take both sides
        return;
      case Kind::GaussianRight:
        smooth.push_back(p1 + std::fabs(p0));
        kinks.push_back(p1);
        return;
      case Kind::Sigmoid: smooth.push_back(p1); return;
      case Kind::Bell: {
        kinks.push_back(p2);  // for b <= 1/2 the derivative jumps (or is unbounded) at the centre
        if (p1 <= 0.5) return;
        const double t = std::pow((2.0 * p1 - 1.0) / (2.0 * p1 + 1.0), 1.0 / (2.0 * p1));
        smooth.insert(smooth.end(), {p2 - std::fabs(p0) * t, p2 + std::fabs(p0) * t});
        return;
      }
      case Kind::SShape:
      case Kind::ZShape: {
        const double m = (p0 + p1) / 2.0;
        if (p0 >= p1) {
          steps.push_back(m);
          kinks.push_back(m);
          return;
        }
        kinks.insert(kinks.end(), {p0, m, p1});
        return;
      }
    }
  }

  Dual over(double lo, double hi, int axis) const {
    std::vector<double> smooth, kinks, steps;
    points(smooth, kinks, steps);
    const bool kink_at_lo = std::find(kinks.begin(), kinks.end(), lo) != kinks.end();
    const bool kink_at_hi = std::find(kinks.begin(), kinks.end(), hi) != kinks.end();
    // At an end that is a kink, the cell's side of it (one ulp in).
    const double lo_side = kink_at_lo ? std::nextafter(lo, kInf) : lo;
    const double hi_side = kink_at_hi ? std::nextafter(hi, -kInf) : hi;
    Dual r;
    r.v = hull(point(value(lo)), point(value(hi)));
    Interval g = hull(point(slope(lo_side)), point(slope(hi_side)));
    if (kink_at_lo) r.v = hull(r.v, point(value(lo_side)));
    if (kink_at_hi) r.v = hull(r.v, point(value(hi_side)));
    for (double p : smooth)
      if (p > lo && p < hi) {
        r.v = hull(r.v, point(value(p)));
        g = hull(g, point(slope(p)));
      }
    for (double p : kinks)
      if (p > lo && p < hi)
        for (double x : {std::nextafter(p, -kInf), p, std::nextafter(p, kInf)}) {
          r.v = hull(r.v, point(value(x)));
          g = hull(g, point(slope(x)));
        }
    // A jump inside the closed cell (or between an end and the cell's side of it) has no derivative bound.
    bool jumps = false;
    for (double p : steps) {
      if (p > lo && p < hi) jumps = true;
      if (p == lo && value(lo) != value(lo_side)) jumps = true;
      if (p == hi && value(hi) != value(hi_side)) jumps = true;
    }
    r.g[axis] = jumps || !std::isfinite(g.lo) || !std::isfinite(g.hi) ? unbounded() : g;
    return r;
  }
};

Dual membership_over(const MembershipFunction& mf, double lo, double hi, int axis, const DualArithmetic& dual) {
  const std::vector<double>& p = mf.params;
  using K = Primitive::Kind;
  const auto prim = [&](K kind, double a, double b, double c = 0.0, double step_value = 1.0) {
    return Primitive{kind, a, b, c, step_value}.over(lo, hi, axis);
  };
  switch (mf.kind) {
    case MfKind::Triangle: return dual.min(prim(K::Rise, p[0], p[1]), prim(K::Fall, p[1], p[2]));
    case MfKind::Trapezoid: return dual.min(prim(K::Rise, p[0], p[1]), prim(K::Fall, p[2], p[3]));
    case MfKind::Gaussian: return prim(K::Gaussian, p[0], p[1]);
    case MfKind::Gaussian2: return dual.mul(prim(K::GaussianLeft, p[0], p[1]), prim(K::GaussianRight, p[2], p[3]));
    case MfKind::GeneralizedBell: return prim(K::Bell, p[0], p[1], p[2]);
    case MfKind::Sigmoid: return p[0] == 0.0 ? constant(0.5) : prim(K::Sigmoid, p[0], p[1]);
    case MfKind::DifferenceSigmoid: {
      const Dual a = p[0] == 0.0 ? constant(0.5) : prim(K::Sigmoid, p[0], p[1]);
      const Dual b = p[2] == 0.0 ? constant(0.5) : prim(K::Sigmoid, p[2], p[3]);
      return dual.abs(dual.sub(a, b));
    }
    case MfKind::ProductSigmoid: {
      const Dual a = p[0] == 0.0 ? constant(0.5) : prim(K::Sigmoid, p[0], p[1]);
      const Dual b = p[2] == 0.0 ? constant(0.5) : prim(K::Sigmoid, p[2], p[3]);
      return dual.mul(a, b);
    }
    case MfKind::ZShape: return prim(K::ZShape, p[0], p[1]);
    case MfKind::SShape: return prim(K::SShape, p[0], p[1]);
    case MfKind::PiShape: return dual.mul(prim(K::SShape, p[0], p[1]), prim(K::ZShape, p[2], p[3]));
    case MfKind::LinearS: return prim(K::Rise, p[0], p[1], 0.0, 1.0);   // linsmf: 1 from a on
    case MfKind::LinearZ: return prim(K::Fall, p[0], p[1], 0.0, 0.0);   // linzmf: 0 from a on
    case MfKind::Constant:
    case MfKind::Linear: break;
  }
  Dual r;
  r.v = unbounded();
  r.g[axis] = unbounded();
  return r;
}

}  // namespace

std::optional<std::string> cell_bound_limitation(const FuzzySystem& system, const EvaluationOptions& options) {
  if (system.interval_type2) return std::string("an interval type-2 system (type reduction has no derivative bound here)");
  if (options.reference == Reference::Octave) return std::string("Octave's semantics (--semantics octave)");
  if (system.type == SystemType::Mamdani) {
    if (system.defuzzifier != Defuzzifier::Centroid)
      return std::string("defuzzifier ") + to_string(system.defuzzifier) +
             " (piecewise constant in the inputs: it jumps between samples)";
    if (system.samples <= 0) return std::string("'samples exact' (adaptive quadrature)");
  } else {
    for (const Rule& rule : system.rules)
      for (const Clause& clause : rule.consequent)
        if (clause.negated) return std::string("a negated Sugeno consequent (it jumps where the rule stops firing)");
  }
  for (const Variable& input : system.inputs)
    for (const Term& term : input.terms)
      if (term.mf.kind == MfKind::GeneralizedBell && !(term.mf.params[1] > 0.0))
        return "a generalised bell with b <= 0 (term '" + term.name + "' of '" + input.name + "')";
  return std::nullopt;
}

struct CellBounder::State {
  const FuzzySystem& system;
  EvaluationOptions options;
  int axes;
  DualArithmetic dual;
  std::vector<std::vector<Clause>> antecedents;  // per rule, sorted by input
  // Mamdani: per output, the consequent columns (rules with the same term, hedge and negation) and their grades
  // at the output's samples, hedged and negated.
  struct Column {
    std::vector<std::size_t> rules;
    std::vector<double> grades;
  };
  std::vector<std::vector<Column>> columns;
  bool merge_columns = false;  // max aggregation with min or prod implication: columns take the max of their rules
  std::vector<std::vector<double>> samples;  // per output
  // Sugeno: per output, the concluding rules and their terms; whether each rule concludes on the output.
  struct Conclusion {
    std::size_t rule;
    const Term* term;
    double hedge_exponent;
  };
  std::vector<std::vector<Conclusion>> conclusions;
  std::vector<std::vector<bool>> concludes;
  // Scratch.
  std::vector<std::vector<Dual>> grades;  // per input, per term
  std::vector<Dual> strengths;
  std::vector<Dual> aggregate;

  State(const FuzzySystem& source, const EvaluationOptions& chosen)
      : system(source), options(chosen), axes(static_cast<int>(source.inputs.size())), dual(axes) {
    antecedents.resize(system.rules.size());
    for (std::size_t r = 0; r < system.rules.size(); ++r) {
      antecedents[r] = system.rules[r].antecedent;
      std::stable_sort(antecedents[r].begin(), antecedents[r].end(),
                       [](const Clause& a, const Clause& b) { return a.variable < b.variable; });
    }
    grades.resize(system.inputs.size());
    for (std::size_t i = 0; i < system.inputs.size(); ++i) grades[i].resize(system.inputs[i].terms.size());
    strengths.resize(system.rules.size());
    if (system.type == SystemType::Mamdani) prepare_mamdani();
    else prepare_sugeno();
  }

  void prepare_mamdani() {
    merge_columns = system.aggregation == SNorm::Maximum &&
                    (system.implication == TNorm::Minimum || system.implication == TNorm::Product);
    columns.resize(system.outputs.size());
    samples.resize(system.outputs.size());
    for (std::size_t o = 0; o < system.outputs.size(); ++o) {
      const Variable& output = system.outputs[o];
      samples[o] = output_sample_points(output.min, output.max, system.samples, options.reference);
      std::map<std::tuple<int, int, bool>, std::size_t> column_of;
      for (std::size_t r = 0; r < system.rules.size(); ++r)
        for (const Clause& clause : system.rules[r].consequent) {
          if (clause.variable != static_cast<int>(o)) continue;
          const auto key = std::make_tuple(clause.term, static_cast<int>(clause.hedge), clause.negated);
          const auto found = merge_columns ? column_of.find(key) : column_of.end();
          if (found != column_of.end()) {
            columns[o][found->second].rules.push_back(r);
            continue;
          }
          Column column;
          column.rules.push_back(r);
          const MembershipFunction& mf = output.terms[static_cast<std::size_t>(clause.term)].mf;
          for (double y : samples[o]) {
            double mu = apply_hedge(membership(mf.kind, mf.params.data(), y), hedge_exponent(clause.hedge));
            if (clause.negated) mu = fuzzy_not(mu);
            column.grades.push_back(mu);
          }
          column_of.emplace(key, columns[o].size());
          columns[o].push_back(std::move(column));
        }
    }
    aggregate.resize(static_cast<std::size_t>(system.samples));
  }

  void prepare_sugeno() {
    conclusions.resize(system.outputs.size());
    concludes.assign(system.outputs.size(), std::vector<bool>(system.rules.size(), false));
    for (std::size_t r = 0; r < system.rules.size(); ++r)
      for (const Clause& clause : system.rules[r].consequent) {
        if (clause.variable < 0 || static_cast<std::size_t>(clause.variable) >= system.outputs.size()) continue;
        const auto o = static_cast<std::size_t>(clause.variable);
        conclusions[o].push_back({r, &system.outputs[o].terms[static_cast<std::size_t>(clause.term)],
                                  hedge_exponent(clause.hedge)});
        concludes[o][r] = true;
      }
  }

  void compute_strengths(const double* lo, const double* hi) {
    for (std::size_t i = 0; i < system.inputs.size(); ++i)
      for (std::size_t t = 0; t < system.inputs[i].terms.size(); ++t)
        grades[i][t] = membership_over(system.inputs[i].terms[t].mf, lo[i], hi[i], static_cast<int>(i), dual);
    for (std::size_t r = 0; r < system.rules.size(); ++r) {
      const Rule& rule = system.rules[r];
      const bool conjunction = rule.connective == Connective::And;
      Dual strength = constant(rule.folded_grade ? *rule.folded_grade : conjunction ? 1.0 : 0.0);
      for (const Clause& clause : antecedents[r]) {
        Dual mu = grades[static_cast<std::size_t>(clause.variable)][static_cast<std::size_t>(clause.term)];
        mu = dual.power(mu, hedge_exponent(clause.hedge));
        if (clause.negated) mu = dual.complement(mu);
        strength = conjunction ? dual.tnorm(system.and_method, strength, mu) : dual.snorm(system.or_method, strength, mu);
      }
      strengths[r] = dual.scale(strength, rule.weight);
    }
  }

  double no_fire_value(std::size_t o) const {
    switch (system.no_fire) {
      case NoFirePolicy::Midrange: return (system.outputs[o].min + system.outputs[o].max) / 2.0;
      case NoFirePolicy::Value: return system.no_fire_value;
      case NoFirePolicy::Error: break;
    }
    return std::numeric_limits<double>::quiet_NaN();
  }

  // The output's value interval F and derivative intervals G (unbounded where the policy may take over).
  struct OutputEnclosure {
    Interval value;
    std::array<Interval, kMaxTableAxes> gradient{};
    bool smooth = true;
  };

  // [yl, yr] over weights [lower_k, upper_k] at points x_k (sorted): the exact range of a weighted average whose
  // weights vary independently within their intervals (kernels/type_reduction_math.h).
  static Interval average_range(const std::vector<double>& x, const std::vector<double>& lower,
                                const std::vector<double>& upper) {
    for (std::size_t k = 0; k < x.size(); ++k)
      if (!std::isfinite(x[k]) || !std::isfinite(upper[k])) return unbounded();
    const TypeReducedInterval<double> r =
        karnik_mendel(x.data(), lower.data(), upper.data(), static_cast<int>(x.size()));
    if (!r.fired || r.iteration_cap_hit) return unbounded();
    return checked({r.left, r.right});
  }

  // Where the weights' total may reach 0 (the no-fire policy takes over: a jump) or the policy is `error`.
  OutputEnclosure with_policy(OutputEnclosure enclosure, std::size_t o, bool any_weight) const {
    enclosure.smooth = false;
    const double policy = no_fire_value(o);
    if (std::isnan(policy)) enclosure.value = unbounded();
    else enclosure.value = any_weight ? hull(enclosure.value, point(policy)) : point(policy);
    return enclosure;
  }

  // max over columns of implication(w_c, grade): per sample, the value interval and the hull of the derivatives
  // of the columns that may be the largest there (the Clarke gradient of max and min), without building a Dual
  // per operation (this loop is most of a cell's cost).
  void aggregate_max(std::size_t o, const std::vector<Dual>& column_strength) {
    const std::size_t columns_here = columns[o].size();
    std::vector<Interval> implied(columns_here);
    for (std::size_t k = 0; k < samples[o].size(); ++k) {
      Interval value = point(0.0);
      for (std::size_t c = 0; c < columns_here; ++c) {
        const double grade = columns[o][c].grades[k];
        const Interval w = column_strength[c].v;
        implied[c] = system.implication == TNorm::Minimum ? Interval{std::min(w.lo, grade), std::min(w.hi, grade)}
                                                          : w * grade;
        value = {std::max(value.lo, implied[c].lo), std::max(value.hi, implied[c].hi)};
      }
      Dual& g = aggregate[k];
      g.v = value;
      bool first = true;
      for (int a = 0; a < axes; ++a) g.g[static_cast<std::size_t>(a)] = point(0.0);
      if (value.hi <= 0.0) continue;
      for (std::size_t c = 0; c < columns_here; ++c) {
        if (implied[c].hi < value.lo) continue;  // never the largest in this cell
        const double grade = columns[o][c].grades[k];
        const Dual& w = column_strength[c];
        for (int a = 0; a < axes; ++a) {
          const auto i = static_cast<std::size_t>(a);
          Interval d;
          if (system.implication == TNorm::Minimum)
            d = w.v.hi <= grade ? w.g[i] : (w.v.lo >= grade ? point(0.0) : hull(w.g[i], point(0.0)));
          else
            d = w.g[i] * grade;
          g.g[i] = first ? d : hull(g.g[i], d);
        }
        first = false;
      }
      // A column whose implied set may be 0 here is the max only where all are: 0 (the s-norm's identity) joins.
      if (value.lo <= 0.0)
        for (int a = 0; a < axes; ++a) g.g[static_cast<std::size_t>(a)] = hull(g.g[static_cast<std::size_t>(a)], point(0.0));
    }
  }

  OutputEnclosure mamdani(std::size_t o) {
    const std::vector<double>& x = samples[o];
    if (merge_columns) {
      std::vector<Dual> column_strength;
      for (const Column& column : columns[o]) {
        Dual w = constant(0.0);
        for (std::size_t r : column.rules) w = dual.max(w, strengths[r]);
        column_strength.push_back(w);
      }
      aggregate_max(o, column_strength);
    } else {
      for (Dual& g : aggregate) g = constant(0.0);
      for (const Column& column : columns[o]) {
        const Dual& w = strengths[column.rules.front()];  // one rule per column
        for (std::size_t k = 0; k < x.size(); ++k)
          aggregate[k] = dual.snorm(system.aggregation, aggregate[k],
                                    dual.tnorm(system.implication, w, constant(column.grades[k])));
      }
    }
    OutputEnclosure e;
    std::vector<double> lower(x.size()), upper(x.size());
    Interval total = point(0.0);
    for (std::size_t k = 0; k < x.size(); ++k) {
      lower[k] = std::max(0.0, aggregate[k].v.lo);
      upper[k] = std::max(0.0, aggregate[k].v.hi);
      total = total + Interval{lower[k], upper[k]};
    }
    const bool any = total.hi > 0.0;
    e.value = any ? average_range(x, lower, upper) : point(0.0);
    if (!(total.lo > 0.0) || !finite(e.value)) return with_policy(e, o, any && finite(e.value));
    // d centroid / dx_a = sum_k (x_k - centroid) dg_k/dx_a / sum_k g_k.
    for (int a = 0; a < axes; ++a) {
      Interval numerator = point(0.0);
      for (std::size_t k = 0; k < x.size(); ++k)
        numerator = numerator + (point(x[k]) - e.value) * aggregate[k].g[static_cast<std::size_t>(a)];
      e.gradient[static_cast<std::size_t>(a)] = numerator / total;
    }
    return e;
  }

  OutputEnclosure sugeno(std::size_t o, const double* lo, const double* hi) {
    struct Term2 {
      Dual z, w;
    };
    std::vector<Term2> terms;
    Interval concluding = point(0.0);
    for (const Conclusion& c : conclusions[o]) {
      Dual z;
      const MembershipFunction& mf = c.term->mf;
      if (mf.kind == MfKind::Constant) {
        z = constant(mf.params[0]);
      } else {
        z = constant(mf.params.back());
        for (int i = 0; i < axes; ++i) {
          Dual xi;
          xi.v = {lo[i], hi[i]};
          xi.g[static_cast<std::size_t>(i)] = point(1.0);
          z = dual.add(z, dual.scale(xi, mf.params[static_cast<std::size_t>(i)]));
        }
      }
      Dual h = strengths[c.rule];
      if (c.hedge_exponent != 1.0) h = dual.power(h, 1.0 / c.hedge_exponent);
      concluding = concluding + Interval{std::max(0.0, h.v.lo), std::max(0.0, h.v.hi)};
      terms.push_back({z, h});
    }
    for (std::size_t r = 0; r < system.rules.size(); ++r)
      if (!concludes[o][r]) terms.push_back({constant(0.0), strengths[r]});
    OutputEnclosure e;
    if (system.defuzzifier == Defuzzifier::WeightedSum) {
      Dual sum = constant(0.0);
      for (std::size_t t = 0; t < conclusions[o].size(); ++t) sum = dual.add(sum, dual.mul(terms[t].z, terms[t].w));
      e.value = sum.v;
      e.gradient = sum.g;
      if (!(concluding.lo > 0.0)) return with_policy(e, o, concluding.hi > 0.0);
      return e;
    }
    // wtaver: yl over the points sorted by their lowest z, yr by their highest (centre of sets).
    Interval total = point(0.0);
    for (const Term2& t : terms) total = total + Interval{std::max(0.0, t.w.v.lo), std::max(0.0, t.w.v.hi)};
    const auto end = [&](bool low) {
      std::vector<std::size_t> order(terms.size());
      for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
      std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
        return low ? terms[a].z.v.lo < terms[b].z.v.lo : terms[a].z.v.hi < terms[b].z.v.hi;
      });
      std::vector<double> x, lower, upper;
      for (std::size_t i : order) {
        x.push_back(low ? terms[i].z.v.lo : terms[i].z.v.hi);
        lower.push_back(std::max(0.0, terms[i].w.v.lo));
        upper.push_back(std::max(0.0, terms[i].w.v.hi));
      }
      return average_range(x, lower, upper);
    };
    const bool any = concluding.hi > 0.0 && total.hi > 0.0;
    e.value = any ? Interval{end(true).lo, end(false).hi} : point(0.0);
    if (!(concluding.lo > 0.0) || !(total.lo > 0.0) || !finite(e.value))
      return with_policy(e, o, any && finite(e.value));
    // d/dx_a sum w z / sum w = (sum_t (z_t - f) dw_t/dx_a + w_t dz_t/dx_a) / sum w.
    for (int a = 0; a < axes; ++a) {
      const auto i = static_cast<std::size_t>(a);
      Interval numerator = point(0.0);
      for (const Term2& t : terms) numerator = numerator + (t.z.v - e.value) * t.w.g[i] + t.w.v * t.z.g[i];
      e.gradient[i] = numerator / total;
    }
    return e;
  }
};

CellBounder::CellBounder(const FuzzySystem& system, const EvaluationOptions& options)
    : state_(std::make_unique<State>(system, options)) {}
CellBounder::~CellBounder() = default;
CellBounder::CellBounder(CellBounder&&) noexcept = default;
CellBounder& CellBounder::operator=(CellBounder&&) noexcept = default;

CellBound CellBounder::bound(const double* lo, const double* hi, const double* corner_min, const double* corner_max,
                             double rounding, const double* widths) {
  State& s = *state_;
  s.compute_strengths(lo, hi);
  CellBound result;
  result.bound = -1.0;
  for (std::size_t o = 0; o < s.system.outputs.size(); ++o) {
    const State::OutputEnclosure e = s.system.type == SystemType::Mamdani ? s.mamdani(o) : s.sugeno(o, lo, hi);
    std::array<double, kMaxTableAxes> terms{};
    double from_derivatives = kInf;
    if (e.smooth) {
      from_derivatives = rounding;
      for (int a = 0; a < s.axes; ++a) {
        const Interval g = e.gradient[static_cast<std::size_t>(a)];
        const double h = widths ? widths[a] : hi[a] - lo[a];
        terms[static_cast<std::size_t>(a)] = finite(g) ? h * width(g) / 4.0 : kInf;
        from_derivatives += terms[static_cast<std::size_t>(a)];
      }
    }
    // The interpolated value lies between the corners' extremes, the function within its value interval.
    const double from_values =
        finite(e.value) ? std::max(e.value.hi - corner_min[o], corner_max[o] - e.value.lo) : kInf;
    const bool values_win = !(from_derivatives <= from_values);
    double b = values_win ? from_values : from_derivatives;
    if (std::isnan(b)) b = kInf;
    if (b > result.bound) {
      result.bound = b;
      result.terms = terms;
      result.smooth = !values_win;
      result.has_terms = std::isfinite(from_derivatives);
    }
  }
  // Round-to-nearest interval arithmetic is not outward-rounded: widen by far more than its rounding.
  result.bound *= 1.0 + 1e-9;
  return result;
}

}  // namespace fmpc
