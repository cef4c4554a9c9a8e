#pragma once
// Curves over one x axis, with a legend beside the plot (never over the data), optional shaded bands (interval
// type-2 footprints), phases (shaded x ranges with a name) and notes: membership-function plots (`fmpc plot
// --terms`), the force-displacement curve of `fmpc simulate` and a cohort's curves (coloured by a value, with a
// colour bar in place of a legend when they are too many to name).
#include <optional>
#include <string>
#include <vector>

#include "tools/plot/axes.h"
#include "tools/plot/canvas.h"
#include "tools/plot/heat_map.h"

namespace fmpc::plot {

struct Series {
  std::string name;  // in the legend; empty: not listed
  std::vector<double> x;
  std::vector<double> y;
  std::vector<double> y_lower;  // when not empty, the band between y_lower and y is shaded
  Colour colour = categorical_colour(0);
  double width = 2;
  std::vector<double> dashes;
  bool markers = false;  // a dot at every point
  bool line = true;      // false: the dots alone (a scatter plot; set markers)
};

// A vertical line at x with a label at its top.
struct VerticalMarker {
  double x = 0;
  std::string label;
  Colour colour = kBlack;
};

struct LineChart {
  std::vector<std::string> title;  // first line bold
  Axis x;
  Axis y;
  bool round_axes = true;  // widen x and y to round ticks (off: exactly [lo, hi])
  std::vector<Series> series;
  std::vector<VerticalMarker> markers;
  std::vector<std::string> notes;  // lines in a box under the legend
  // A colour bar right of the plot, for series coloured by viridis over [lo, hi] (drawn left of any legend).
  std::optional<ColourBar> colour_bar;
  int width = 760;
  int height = 520;
};

std::string render_line_chart(const LineChart& chart, ImageFormat format);

}  // namespace fmpc::plot
