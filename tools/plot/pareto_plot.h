#pragma once
// The speed/accuracy trade of `fmpc trade` as a scatter plot: evaluations per second (log x) against the maximum
// error (log y), one labelled point per variant coloured by its kind, the Pareto front (no other variant is both
// faster and more accurate) joined by a line, and a legend. Exact variants (error 0, which a log axis cannot show)
// sit in a strip below the axis marked "0 (exact)".
#include <string>
#include <vector>

#include "tools/plot/canvas.h"

namespace fmpc::plot {

struct TradePoint {
  std::string label;                    // "table 17x17"
  double evaluations_per_second = 0.0;  // > 0
  double max_error = 0.0;               // >= 0
  std::string kind;                     // legend group: "interpreter", "compiled C++", "table"; empty: "other"
};

struct TradePlot {
  std::vector<TradePoint> points;
  std::string error_unit;  // for the y label
  std::vector<std::string> title;
  std::string speed_label = "evaluations per second (one core)";  // the x label
  // A required error (fmpc trade --max-error E), drawn as a horizontal line with its legend entry; 0: none.
  double error_bound = 0.0;
  std::string error_bound_label = "";  // the legend's words for it
};

// Indices of the points on the Pareto front (faster or equally fast and strictly more accurate than every point
// they are compared with, or the reverse), sorted by speed.
std::vector<std::size_t> pareto_front(const std::vector<TradePoint>& points);

// Where each point's label went: its box, or none (then the point carries a number and the legend the label).
struct LabelPlacement {
  std::vector<Box> boxes;
  std::vector<bool> placed;
  std::vector<std::string> legend;  // the legend's entries, top to bottom
};

// The figure, 860 x 600, as PNG or SVG bytes; `placement` (optional) receives where the labels went, for tests.
std::string render_trade_plot(const TradePlot& plot, ImageFormat format, LabelPlacement* placement = nullptr);

}  // namespace fmpc::plot
