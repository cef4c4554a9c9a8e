#pragma once
// Curves y(x) on linear axes as a PNG-ready raster: the thesis benchmark's displacement and velocity against time
// (`fmpc thesis-benchmark --plot`). The axes are those of `fmpc simulate`'s force-displacement plot; the CLI work
// (worktree wt-cli) is building tools/plot/line_chart for every line chart: when it lands, this file goes and
// thesis-benchmark draws with it. Ticks from nice_ticks; the axes always include 0; a legend
// below the axes when there is more than one curve.
#include <string>
#include <vector>

#include "tools/plot/png_image.h"

namespace fmpc::plot {

struct LineSeries {
  std::string label;      // the legend's text (unused for a single curve)
  std::vector<double> x;  // as many as y
  std::vector<double> y;
  Rgb colour{31, 119, 180};
};

struct LinePlot {
  std::string title;
  std::string x_label;
  std::string y_label;
  std::vector<LineSeries> series;
};

// 640 x 480 pixels (taller by the legend), plot area 500 x 340; tick labels with six significant digits.
RgbImage render_line_plot(const LinePlot& plot);

// Distinct colours for up to 8 curves (matplotlib's tab10 order), repeating after.
Rgb series_colour(std::size_t index);

}  // namespace fmpc::plot
