#pragma once
// The speed/accuracy trade of `fmpc trade` as a scatter plot: evaluations per second (log x) against the maximum
// error (log y), one labelled point per variant, the Pareto front (no other variant is both faster and more
// accurate) joined by a line.
#include <string>
#include <vector>

#include "tools/plot/png_image.h"

namespace fmpc::plot {

struct TradePoint {
  std::string label;
  double evaluations_per_second = 0.0;  // > 0
  double max_error = 0.0;               // >= 0; 0 is drawn at the floor of the error axis
};

struct TradePlot {
  std::vector<TradePoint> points;
  std::string error_unit;  // for the y label
  std::vector<std::string> title;
  std::string speed_label = "evaluations per second (one core)";  // the x label
};

// Indices of the points on the Pareto front (faster or equally fast and strictly more accurate than every point
// they are compared with, or the reverse), sorted by speed.
std::vector<std::size_t> pareto_front(const std::vector<TradePoint>& points);

// The figure: 720 x 540 pixels.
RgbImage render_trade_plot(const TradePlot& plot);

}  // namespace fmpc::plot
