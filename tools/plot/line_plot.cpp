#include "tools/plot/line_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "tools/plot/bitmap_font.h"
#include "tools/plot/heat_map.h"

namespace fmpc::plot {

namespace {

// Tick labels: six significant digits (hiding residues such as 0.6000000000000001).
std::string six_digits(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", std::abs(value) < 1e-12 ? 0.0 : value);
  return text;
}

}  // namespace

Rgb series_colour(std::size_t index) {
  static const Rgb colours[] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44},  {214, 39, 40},
                                {148, 103, 189}, {140, 86, 75}, {227, 119, 194}, {127, 127, 127}};
  return colours[index % (sizeof colours / sizeof colours[0])];
}

RgbImage render_line_plot(const LinePlot& plot) {
  const int width = 640, left = 100, top = 60, plot_width = 500, plot_height = 340;
  // Several curves: a legend below the axis label, two entries a row, so it never hides a curve.
  const int legend_row = text_height(1) + 6;
  const int legend_rows = plot.series.size() > 1 ? static_cast<int>((plot.series.size() + 1) / 2) : 0;
  const int axes_height = 480, height = axes_height + (legend_rows > 0 ? legend_rows * legend_row + 10 : 0);
  const Rgb white{255, 255, 255}, black{0, 0, 0}, grey{200, 200, 200};
  RgbImage image(width, height, white);
  double x_min = 0.0, x_max = 0.0, y_min = 0.0, y_max = 0.0;
  for (const LineSeries& series : plot.series)
    for (std::size_t i = 0; i < series.x.size() && i < series.y.size(); ++i) {
      x_min = std::min(x_min, series.x[i]);
      x_max = std::max(x_max, series.x[i]);
      y_min = std::min(y_min, series.y[i]);
      y_max = std::max(y_max, series.y[i]);
    }
  if (!(x_max > x_min)) x_max = x_min + 1.0;
  if (!(y_max > y_min)) y_max = y_min + 1.0;
  const std::vector<double> x_ticks = nice_ticks(x_min, x_max, 6);
  const std::vector<double> y_ticks = nice_ticks(y_min, y_max, 6);
  x_min = std::min(x_min, x_ticks.front());
  x_max = std::max(x_max, x_ticks.back());
  y_min = std::min(y_min, y_ticks.front());
  y_max = std::max(y_max, y_ticks.back());
  const auto px = [&](double x) { return left + static_cast<int>(std::lround((x - x_min) / (x_max - x_min) * plot_width)); };
  const auto py = [&](double y) {
    return top + plot_height - static_cast<int>(std::lround((y - y_min) / (y_max - y_min) * plot_height));
  };
  for (const double x : x_ticks) {
    image.fill_rect(px(x), top, 1, plot_height, grey);
    const std::string label = six_digits(x);
    draw_text(image, px(x) - text_width(label, 2) / 2, top + plot_height + 8, label, black, 2);
  }
  for (const double y : y_ticks) {
    image.fill_rect(left, py(y), plot_width, 1, grey);
    const std::string label = six_digits(y);
    draw_text(image, left - 8 - text_width(label, 2), py(y) - text_height(2) / 2, label, black, 2);
  }
  image.fill_rect(left, top, 1, plot_height + 1, black);
  image.fill_rect(left, top + plot_height, plot_width + 1, 1, black);
  // Segments drawn densely enough to leave no gaps (one dot per pixel of the longer side), 3 pixels thick.
  for (const LineSeries& series : plot.series) {
    for (std::size_t i = 1; i < series.x.size() && i < series.y.size(); ++i) {
      const double x0 = px(series.x[i - 1]), y0 = py(series.y[i - 1]);
      const double x1 = px(series.x[i]), y1 = py(series.y[i]);
      const int n = std::max(1, static_cast<int>(std::max(std::abs(x1 - x0), std::abs(y1 - y0))));
      for (int k = 0; k <= n; ++k) {
        const double t = static_cast<double>(k) / n;
        image.fill_rect(static_cast<int>(std::lround(x0 + t * (x1 - x0))) - 1,
                        static_cast<int>(std::lround(y0 + t * (y1 - y0))) - 1, 3, 3, series.colour);
      }
    }
  }
  for (std::size_t i = 0; legend_rows > 0 && i < plot.series.size(); ++i) {
    const int x = 20 + static_cast<int>(i % 2) * (width / 2), y = axes_height + static_cast<int>(i / 2) * legend_row;
    image.fill_rect(x, y + text_height(1) / 2 - 1, 16, 3, plot.series[i].colour);
    draw_text(image, x + 22, y, plot.series[i].label, black, 1);
  }
  draw_text(image, left + plot_width / 2 - text_width(plot.x_label, 2) / 2, axes_height - 40, plot.x_label, black, 2);
  draw_text(image, 8, top + plot_height / 2 + text_width(plot.y_label, 2) / 2, plot.y_label, black, 2, true);
  const int title_scale = text_width(plot.title, 2) <= width - 20 ? 2 : 1;
  draw_text(image, (width - text_width(plot.title, title_scale)) / 2, 20, plot.title, black, title_scale);
  return image;
}

}  // namespace fmpc::plot
