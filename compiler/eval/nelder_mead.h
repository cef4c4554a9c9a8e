#pragma once
// Bounded, deterministic Nelder-Mead simplex minimisation: J. A. Nelder and R. Mead, "A simplex method for function
// minimization", The Computer Journal 7(4):308-313, 1965, with the coefficients of J. C. Lagarias, J. A. Reeds,
// M. H. Wright and P. E. Wright, "Convergence properties of the Nelder-Mead simplex method in low dimensions",
// SIAM J. Optimization 9(1):112-147, 1998 (reflection 1, expansion 2, contraction 1/2, shrink 1/2), which MATLAB's
// fminsearch uses. On a box: every point tried is clamped into [lower, upper] per coordinate, and a point where the
// objective is not finite (infeasible) ranks below every finite one. No randomness: the start simplex is the start
// point and, per coordinate, the start moved by `initial_step` of that coordinate's box width towards the box's
// larger side.
#include <functional>
#include <vector>

namespace fmpc {

struct NelderMeadOptions {
  int max_evaluations = 0;     // 0: 200 per coordinate (fminsearch's MaxFunEvals)
  double value_tolerance = 1e-10;  // stop when the simplex's values spread less than this times (1 + |best|) ...
  double point_tolerance = 1e-6;   // ... and its vertices lie within this fraction of each coordinate's box width
  double initial_step = 0.05;
};

struct NelderMeadResult {
  std::vector<double> point;  // the best point found
  double value = 0.0;         // the objective there
  int evaluations = 0;
  int iterations = 0;
  bool converged = false;  // both tolerances met; false when the evaluation cap stopped the search
  double value_spread = 0.0;  // max - min of the simplex's values when it stopped (the residual reached)
};

NelderMeadResult minimise_nelder_mead(const std::function<double(const std::vector<double>&)>& objective,
                                      const std::vector<double>& start, const std::vector<double>& lower,
                                      const std::vector<double>& upper, const NelderMeadOptions& options = {});

}  // namespace fmpc
