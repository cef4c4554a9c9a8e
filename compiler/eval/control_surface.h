#pragma once
// A control surface (MATLAB's gensurf): one output over a grid of two inputs, the others held at given values, with
// the strongest rule's firing strength at every grid point so that coverage holes (points where no rule reaches a
// threshold, as lint's coverage-hole check defines them) can be marked. `fmpc plot --x --y` and the studio draw it.
#include <cstddef>
#include <functional>
#include <vector>

#include "compiler/eval/interpreter.h"
#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

struct ControlSurface {
  std::vector<double> x;  // `resolution` points over the x input's range, ends included
  std::vector<double> y;  // the same over the y input's range
  // Row-major, y outer: z[iy * x.size() + ix] is the output at (x[ix], y[iy]); NaN where the no-fire policy `error`
  // applied (or an input is NaN).
  std::vector<double> z;
  // The largest firing strength of any rule at each grid point (type-2: the upper end), laid out as z.
  std::vector<double> strongest_firing;
  std::size_t nan_points = 0;
};

// Precondition: the system passed sema; x_input != y_input are input indices, output an output index, `point` one
// value per input (the values of the inputs not on an axis), resolution >= 2. `row_started(r, resolution)`, where
// given, is called before each row (a caller's progress: 1001 x 1001 points of a 100,000-rule system take minutes).
ControlSurface control_surface(const FuzzySystem& system, std::size_t x_input, std::size_t y_input, std::size_t output,
                               std::vector<double> point, std::size_t resolution, const EvaluationOptions& options = {},
                               const std::function<void(std::size_t, std::size_t)>& row_started = {});

}  // namespace fmpc
