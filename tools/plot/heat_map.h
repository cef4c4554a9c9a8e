#pragma once
// A control surface drawn as a heat map with contour lines: z over a grid of (x, y), axes, a colour bar in the
// output's unit, and a title block naming the inputs held fixed (with their units).
#include <string>
#include <utility>
#include <vector>

#include "tools/plot/canvas.h"

namespace fmpc::plot {

struct HeatMap {
  std::vector<double> x;  // grid columns, increasing
  std::vector<double> y;  // grid rows, increasing (drawn bottom to top)
  std::vector<double> z;  // z[iy * x.size() + ix]; NaN draws grey
  double z_min = 0.0;     // the colour scale: z_min -> first colour, z_max -> last; values beyond are clamped
  double z_max = 1.0;
  std::string x_label;
  std::string y_label;
  std::string z_label;
  std::vector<std::string> title;  // the first line in bold, the rest (fixed inputs) below it
  bool contours = true;            // iso-lines at the colour bar's ticks
};

// Viridis (van der Walt & Smith, matplotlib 2.0 default): perceptually uniform and readable in grey and by
// colour-blind readers. t in [0, 1], clamped; NaN gives grey.
Colour viridis(double t);

// A vertical viridis colour bar beside a plot: lo at the bottom, round ticks, an upright title.
struct ColourBar {
  double lo = 0.0;
  double hi = 1.0;
  std::string title;
};

// The width the bar takes to the right of a plot: the gap, the bar, its tick labels and its title.
double colour_bar_width(Canvas& canvas, const ColourBar& bar, const Font& tick_font, const Font& title_font);
// Draws the bar from (plot_right, y) down over `height`, after the gap colour_bar_width counts.
void draw_colour_bar(Canvas& canvas, double plot_right, double y, double height, const ColourBar& bar,
                     const Font& tick_font, const Font& title_font);

// Line segments where z crosses `level` (marching squares over the grid cells, linear interpolation along the
// edges; a saddle cell is split by its centre value). Cells with a NaN corner give none.
std::vector<std::pair<std::pair<double, double>, std::pair<double, double>>> contour_segments(const HeatMap& map,
                                                                                             double level);

// The figure, 760 x 600, as PNG or SVG bytes.
std::string render_heat_map(const HeatMap& map, ImageFormat format);

}  // namespace fmpc::plot
