#pragma once
// A bound on the error of multilinear interpolation over one cell of a lookup table, derived from the rule base
// (docs/compiler.md, "Error statement"). For a cell with widths h_a and a function f whose partial derivative along
// axis a lies in the interval G_a everywhere in the cell,
//
//   |f(x) - L(x)| <= sum_a h_a * width(G_a) / 4
//
// where L interpolates f's values at the corners: multilinear interpolation is the product of one linear
// interpolation per axis, f - I_1 ... I_d f = (f - I_1 f) + I_1 (f - I_2 f) + ... telescopes, each I_a is a convex
// combination, and along one axis f(x) - I f(x) = (1 - t) int_a^x f' - t int_x^b f' lies within
// t (1 - t) h (sup f' - inf f') <= h width(G) / 4. The bound is O(h^2) where f is smooth (width(G) = O(h)) and O(h)
// at a kink, where it is near tight. The G_a come from evaluating the rule base over the cell in interval
// arithmetic with derivatives (a value interval and one derivative interval per axis for every quantity: the
// input grades from each membership family's exact extrema on the cell, then hedges, negation, norms, weights, the
// aggregation at every output sample and the centroid's quotient rule, or the Sugeno weighted average). Where a
// derivative is unbounded (a step in a membership function, a square-root hedge at a foot, a region where no rule
// fires and the no-fire policy takes over), the bound falls back to the cell's value range against its corners,
// max(sup f - min corner, max corner - inf f), which needs no derivative. Both are computed in round-to-nearest
// double and the result is widened (see CellBounder::bound).
//
// Covered: type-1 Mamdani systems defuzzified by centroid over sampled outputs, and type-1 Sugeno systems (wtaver,
// wtsum) with MATLAB's semantics, every membership family, hedge, norm and weight; not covered (the table builder
// then states an estimate): interval type-2 systems, bisector / mom / som / lom (piecewise constant in the
// inputs), `samples exact`, Octave's semantics, negated Sugeno consequents, generalised bells with b <= 0.
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "compiler/eval/interpreter.h"
#include "compiler/ir/fuzzy_system.h"
#include "kernels/table_math.h"

namespace fmpc {

// Why the derived bound does not cover `system`, or nullopt when it does.
std::optional<std::string> cell_bound_limitation(const FuzzySystem& system, const EvaluationOptions& options);

struct CellBound {
  double bound = 0.0;  // over the outputs, output units (the largest of the outputs' bounds)
  // For the output with that bound, each axis's term h_a width(G_a) / 4 (infinite where G_a is unbounded): what
  // halving the cell along that axis would remove, roughly. `smooth` is false where the cell's value range gave
  // the (smaller) bound instead.
  std::array<double, kMaxTableAxes> terms{};
  bool smooth = true;
  bool has_terms = true;  // the derivative intervals were finite (the terms are known even where `smooth` is false)
};

class CellBounder {
 public:
  // Precondition: cell_bound_limitation(system, options) is nullopt. `system`'s inputs are the table's axes.
  CellBounder(const FuzzySystem& system, const EvaluationOptions& options);
  ~CellBounder();
  CellBounder(CellBounder&&) noexcept;
  CellBounder& operator=(CellBounder&&) noexcept;
  CellBounder(const CellBounder&) = delete;
  CellBounder& operator=(const CellBounder&) = delete;

  // The bound over the cell [lo_a, hi_a] (per axis) for the table values stored at its corners:
  // `corner_min` / `corner_max` per output, and `rounding`, the largest |stored - computed| at its corners
  // (float32 tables). With `widths`, [lo, hi] is a block of cells whose widths along each axis are at most
  // widths[a]: the derivative intervals hold over the whole block, so the derivative bound (with widths[a] for
  // h_a) holds for every cell in it; pass infinite corner extremes then, which leaves the value bound out.
  // Not thread-safe; use one per thread.
  CellBound bound(const double* lo, const double* hi, const double* corner_min, const double* corner_max,
                  double rounding, const double* widths = nullptr);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace fmpc
