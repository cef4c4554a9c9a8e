#pragma once
// Axes for fmpc's figures: round tick values, log axes by decades, and a layout that measures every tick label and
// title first so that nothing is clipped or drawn over another label.
#include <string>
#include <vector>

#include "tools/plot/canvas.h"

namespace fmpc::plot {

struct Axis {
  double lo = 0;  // the data range shown; for a log axis both > 0
  double hi = 1;
  bool log = false;
  std::string title;  // with its unit: "stiffness (kPa)"
};

// About `count` evenly spaced round values (1, 2 or 5 times a power of ten) inside [lo, hi].
std::vector<double> nice_ticks(double lo, double hi, int count);
// The powers of ten inside [lo, hi] (lo > 0); when fewer than two, 1-2-5 steps within the decades.
std::vector<double> log_ticks(double lo, double hi);
// A tick's text: shortest round form for linear axes; "10³", "10⁻²" (superscripts) for powers of ten.
std::string tick_label(double value, bool log);
// [lo, hi] widened to whole decades (log) or to the nearest round ticks (linear), for a range that reads well.
Axis rounded(Axis axis);

// A plot area on the canvas and the maps from data to pixels.
struct PlotArea {
  Box box;
  Axis x;
  Axis y;
  double px(double value) const;
  double py(double value) const;
};

// The largest plot area inside `available` that leaves room for the tick labels and titles of `x` and `y`.
PlotArea layout_plot(Canvas& canvas, const Box& available, const Axis& x, const Axis& y, const Font& tick_font,
                     const Font& title_font);
// Grid lines, frame, ticks, tick labels and axis titles.
// `x_labels` false leaves out the x tick labels and title (a caller that draws something below the area first).
void draw_axes(Canvas& canvas, const PlotArea& area, const Font& tick_font, const Font& title_font,
               bool x_labels = true);

// Lines of a title block drawn from (x, y) down, each shrunk to fit `width`; returns the y below the block.
double draw_title_block(Canvas& canvas, double x, double y, double width, const std::vector<std::string>& lines,
                        const Font& first_line, const Font& other_lines);

}  // namespace fmpc::plot
