#pragma once
// A control surface drawn as a heat map: z over a grid of (x, y), with axes, ticks, labels and a colour bar.
#include <string>
#include <vector>

#include "tools/plot/png_image.h"

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
  std::vector<std::string> title;  // lines above the plot
};

// Viridis (van der Walt & Smith, matplotlib 2.0 default): perceptually uniform and readable in grey and by
// colour-blind readers. t in [0, 1], clamped; NaN gives grey.
Rgb viridis(double t);

// About `count` evenly spaced round values (1, 2 or 5 times a power of ten) covering [lo, hi].
std::vector<double> nice_ticks(double lo, double hi, int count);

// The figure: 640 x 540 pixels, plot area 400 x 400.
RgbImage render_heat_map(const HeatMap& map);

// Geometry of render_heat_map, for tests: the plot area's top-left corner and size.
inline constexpr int kPlotLeft = 100;
inline constexpr int kPlotTop = 70;
inline constexpr int kPlotSize = 400;

}  // namespace fmpc::plot
