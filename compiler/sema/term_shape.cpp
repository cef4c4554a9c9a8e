#include "compiler/sema/term_shape.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "kernels/fuzzy_math.h"

namespace fmpc {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

bool is_one_sided(MfKind kind) {
  return kind == MfKind::ZShape || kind == MfKind::SShape || kind == MfKind::LinearS || kind == MfKind::LinearZ ||
         kind == MfKind::Sigmoid || kind == MfKind::DifferenceSigmoid || kind == MfKind::ProductSigmoid;
}

// The x positions a family's parameters name (feet, shoulders, centres), where grades have kinks or extremes.
std::vector<double> breakpoints(const Term& term) {
  const std::vector<double>& p = term.mf.params;
  switch (term.mf.kind) {
    case MfKind::Triangle: return {p[0], p[1], p[2]};
    case MfKind::Trapezoid: return {p[0], p[1], p[2], p[3]};
    case MfKind::Gaussian: return {p[1]};
    case MfKind::Gaussian2: return {p[1], p[3], (p[1] + p[3]) / 2};
    case MfKind::GeneralizedBell: return {p[2]};
    case MfKind::Sigmoid: return {p[1]};
    case MfKind::DifferenceSigmoid:
    case MfKind::ProductSigmoid: return {p[1], p[3], (p[1] + p[3]) / 2};
    case MfKind::ZShape:
    case MfKind::SShape:
    case MfKind::LinearS:
    case MfKind::LinearZ: return {p[0], p[1], (p[0] + p[1]) / 2};
    case MfKind::PiShape: return {p[0], p[1], p[2], p[3], (p[0] + p[1]) / 2, (p[2] + p[3]) / 2};
    case MfKind::Constant:
    case MfKind::Linear: return {};
  }
  return {};
}

}  // namespace

bool is_gradable(const Term& term) {
  const MfKind kind = term.mf.kind;
  if (kind == MfKind::Constant || kind == MfKind::Linear) return false;
  const int count = mf_param_count(kind);
  if (count < 0 || term.mf.params.size() < static_cast<std::size_t>(count)) return false;
  for (int i = 0; i < count; ++i)
    if (!std::isfinite(term.mf.params[static_cast<std::size_t>(i)])) return false;
  return true;
}

double term_grade(const Term& term, double x) { return membership(term.mf.kind, term.mf.params.data(), x); }

double clause_grade(const Term& term, const Clause& clause, double x) {
  return clause_grade_of_term_grade(clause, term_grade(term, x));
}

double clause_grade_of_term_grade(const Clause& clause, double term_grade) {
  const double hedged = apply_hedge(term_grade, hedge_exponent(clause.hedge));
  return clause.negated ? fuzzy_not(hedged) : hedged;
}

SampledGradeRange clause_grade_bounds(const Term& term, const Clause& clause, double lo, double hi, int samples) {
  SampledGradeRange bounds{kInfinity, -kInfinity};
  auto visit = [&](double x) {
    const double grade = clause_grade(term, clause, x);
    bounds.lowest = std::min(bounds.lowest, grade);
    bounds.highest = std::max(bounds.highest, grade);
  };
  const int n = std::max(samples, 2);
  for (int i = 0; i < n; ++i) visit(lo + (hi - lo) * i / (n - 1));
  for (double x : breakpoints(term))
    if (x >= lo && x <= hi) visit(x);
  return bounds;
}

std::optional<CoreInterval> term_core(const Term& term) {
  if (!is_gradable(term)) return std::nullopt;
  const std::vector<double>& p = term.mf.params;
  switch (term.mf.kind) {
    case MfKind::Triangle: return CoreInterval{p[1], p[1]};
    case MfKind::Trapezoid:
    case MfKind::PiShape: return CoreInterval{std::min(p[1], p[2]), std::max(p[1], p[2])};
    case MfKind::Gaussian: return CoreInterval{p[1], p[1]};
    case MfKind::Gaussian2: return CoreInterval{std::min(p[1], p[3]), std::max(p[1], p[3])};
    case MfKind::GeneralizedBell: return CoreInterval{p[2], p[2]};
    case MfKind::ZShape:
    case MfKind::LinearZ: return CoreInterval{-kInfinity, (p[0] + p[1]) / 2};
    case MfKind::SShape:
    case MfKind::LinearS: return CoreInterval{(p[0] + p[1]) / 2, kInfinity};
    case MfKind::Sigmoid:
      if (p[0] > 0) return CoreInterval{p[1], kInfinity};
      if (p[0] < 0) return CoreInterval{-kInfinity, p[1]};
      return CoreInterval{-kInfinity, kInfinity};
    case MfKind::DifferenceSigmoid:
    case MfKind::ProductSigmoid:
    case MfKind::Constant:
    case MfKind::Linear: return std::nullopt;
  }
  return std::nullopt;
}

std::optional<double> term_centre(const Term& term, double lo, double hi) {
  if (!is_gradable(term)) return std::nullopt;
  if (!is_one_sided(term.mf.kind)) {
    const std::optional<CoreInterval> core = term_core(term);
    if (core) return (core->lo + core->hi) / 2;
  }
  // Midpoint rule on a fixed grid: precise enough to order terms, and the same for every term of a variable.
  constexpr int kPoints = 401;
  double area = 0.0;
  double moment = 0.0;
  for (int i = 0; i < kPoints; ++i) {
    const double x = lo + (hi - lo) * (i + 0.5) / kPoints;
    const double grade = term_grade(term, x);
    area += grade;
    moment += grade * x;
  }
  if (!(area > 0.0)) return std::nullopt;
  return moment / area;
}

std::vector<TermWidth> term_widths(const Term& term) {
  if (!is_gradable(term)) return {};
  const std::vector<double>& p = term.mf.params;
  auto slope_width = [](double slope, const char* name) {
    // sigmf rises from 0.27 to 0.73 over 2/|a|: 1/|a| is its half-width. A flat sigmoid (a == 0) is not narrow.
    return slope == 0.0 ? std::vector<TermWidth>{} : std::vector<TermWidth>{{name, 1.0 / std::fabs(slope)}};
  };
  std::vector<TermWidth> widths;
  switch (term.mf.kind) {
    case MfKind::Triangle: return {{"foot distance c - a", p[2] - p[0]}};
    case MfKind::Trapezoid: return {{"foot distance d - a", p[3] - p[0]}};
    case MfKind::PiShape: return {{"foot distance d - a", p[3] - p[0]}};
    case MfKind::Gaussian: return {{"sd", p[0]}};
    case MfKind::Gaussian2: return {{"sd1", p[0]}, {"sd2", p[2]}};
    case MfKind::GeneralizedBell: return {{"width a", std::fabs(p[0])}};
    case MfKind::Sigmoid: return slope_width(p[0], "transition width 1/|a|");
    case MfKind::DifferenceSigmoid:
    case MfKind::ProductSigmoid:
      widths = slope_width(p[0], "transition width 1/|a1|");
      for (const TermWidth& width : slope_width(p[2], "transition width 1/|a2|")) widths.push_back(width);
      return widths;
    case MfKind::ZShape:
    case MfKind::SShape:
    case MfKind::LinearS:
    case MfKind::LinearZ:
      if (p[1] == p[0]) return {};
      return {{"transition width b - a", p[1] - p[0]}};
    case MfKind::Constant:
    case MfKind::Linear: return {};
  }
  return {};
}

}  // namespace fmpc
