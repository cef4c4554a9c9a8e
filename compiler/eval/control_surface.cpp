#include "compiler/eval/control_surface.h"

#include <algorithm>
#include <cmath>

namespace fmpc {

ControlSurface control_surface(const FuzzySystem& system, std::size_t x_input, std::size_t y_input, std::size_t output,
                               std::vector<double> point, std::size_t resolution, const EvaluationOptions& options,
                               const std::function<void(std::size_t, std::size_t)>& row_started) {
  ControlSurface surface;
  const Variable& xv = system.inputs[x_input];
  const Variable& yv = system.inputs[y_input];
  surface.x.resize(resolution);
  surface.y.resize(resolution);
  for (std::size_t k = 0; k < resolution; ++k) {
    const double t = static_cast<double>(k) / static_cast<double>(resolution - 1);
    surface.x[k] = xv.min + t * (xv.max - xv.min);
    surface.y[k] = yv.min + t * (yv.max - yv.min);
  }
  surface.z.resize(resolution * resolution);
  surface.strongest_firing.resize(resolution * resolution);
  Interpreter interpreter(system, options);
  for (std::size_t r = 0; r < resolution; ++r)
    for (std::size_t c = 0; c < resolution; ++c) {
      if (c == 0 && row_started) row_started(r, resolution);
      point[x_input] = surface.x[c];
      point[y_input] = surface.y[r];
      const Evaluation evaluation = interpreter.evaluate(point);
      const double z = evaluation.outputs[output];
      surface.z[r * resolution + c] = z;
      if (std::isnan(z)) ++surface.nan_points;
      double strongest = 0.0;
      for (double w : evaluation.firing_strengths) strongest = std::max(strongest, w);
      surface.strongest_firing[r * resolution + c] = strongest;
    }
  return surface;
}

}  // namespace fmpc
