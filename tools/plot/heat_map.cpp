#include "tools/plot/heat_map.h"

#include <algorithm>
#include <cmath>

#include "tools/plot/axes.h"

namespace fmpc::plot {

namespace {

constexpr int kWidth = 760;
constexpr int kHeight = 600;
constexpr Colour kNanGrey{0.6, 0.6, 0.6, 1};
constexpr double kBarGap = 24;
constexpr double kBarWidth = 20;

}  // namespace

double colour_bar_width(Canvas& canvas, const ColourBar& bar, const Font& tick_font, const Font& title_font) {
  double label_width = 0;
  for (double v : nice_ticks(bar.lo, bar.hi, 6))
    label_width = std::max(label_width, canvas.measure(tick_label(v, false), tick_font).first);
  return kBarGap + kBarWidth + 6 + label_width + 8 + canvas.measure(bar.title, title_font).second + 12;
}

void draw_colour_bar(Canvas& canvas, double plot_right, double y, double height, const ColourBar& bar,
                     const Font& tick_font, const Font& title_font) {
  const std::vector<double> ticks = nice_ticks(bar.lo, bar.hi, 6);
  double label_width = 0;
  for (double v : ticks) label_width = std::max(label_width, canvas.measure(tick_label(v, false), tick_font).first);
  const double x = plot_right + kBarGap;
  const int steps = 256;
  std::vector<Colour> cells(steps);
  for (int k = 0; k < steps; ++k) cells[static_cast<std::size_t>(k)] = viridis(1.0 - (k + 0.5) / steps);
  canvas.raster(x, y, kBarWidth, height, 1, steps, cells);
  canvas.frame(x, y, kBarWidth, height, kBlack);
  const double span = bar.hi - bar.lo;
  if (span > 0)
    for (double v : ticks) {
      const double py = y + height - (v - bar.lo) / span * height;
      canvas.line(x, py, x + kBarWidth + 4, py, kBlack);
      canvas.text(x + kBarWidth + 6, py, tick_label(v, false), tick_font, Align::Start, Align::Centre);
    }
  canvas.text(x + kBarWidth + 6 + label_width + 8, y + height / 2, bar.title, title_font, Align::Centre, Align::Start,
              kBlack, true);
}

Colour viridis(double t) {
  // Nine samples of matplotlib's viridis table (_cm_listed.py, entries 0, 32, ..., 255), linearly interpolated.
  static constexpr double kStops[9][3] = {
      {0.267004, 0.004874, 0.329415}, {0.277018, 0.185228, 0.489898}, {0.229739, 0.322361, 0.545706},
      {0.172719, 0.448791, 0.557885}, {0.127568, 0.566949, 0.550556}, {0.157851, 0.683765, 0.501686},
      {0.369214, 0.788888, 0.382914}, {0.678489, 0.863742, 0.189503}, {0.993248, 0.906157, 0.143936}};
  if (std::isnan(t)) return kNanGrey;
  t = std::clamp(t, 0.0, 1.0) * 8.0;
  const auto i = std::min(static_cast<int>(t), 7);
  const double f = t - i;
  const auto channel = [&](int c) { return kStops[i][c] + f * (kStops[i + 1][c] - kStops[i][c]); };
  return {channel(0), channel(1), channel(2), 1};
}

std::vector<std::pair<std::pair<double, double>, std::pair<double, double>>> contour_segments(const HeatMap& map,
                                                                                             double level) {
  std::vector<std::pair<std::pair<double, double>, std::pair<double, double>>> segments;
  const std::size_t nx = map.x.size(), ny = map.y.size();
  if (nx < 2 || ny < 2 || map.z.size() < nx * ny) return segments;
  const auto z = [&](std::size_t ix, std::size_t iy) { return map.z[iy * nx + ix]; };
  for (std::size_t iy = 0; iy + 1 < ny; ++iy)
    for (std::size_t ix = 0; ix + 1 < nx; ++ix) {
      // Corners counter-clockwise from (ix, iy); edges k joins corner k and k + 1.
      const double cx[4] = {map.x[ix], map.x[ix + 1], map.x[ix + 1], map.x[ix]};
      const double cy[4] = {map.y[iy], map.y[iy], map.y[iy + 1], map.y[iy + 1]};
      const double cz[4] = {z(ix, iy), z(ix + 1, iy), z(ix + 1, iy + 1), z(ix, iy + 1)};
      if (std::isnan(cz[0]) || std::isnan(cz[1]) || std::isnan(cz[2]) || std::isnan(cz[3])) continue;
      std::pair<double, double> crossing[4];
      bool crosses[4] = {false, false, false, false};
      for (int k = 0; k < 4; ++k) {
        const int j = (k + 1) % 4;
        const bool a = cz[k] >= level, b = cz[j] >= level;
        if (a == b) continue;
        const double t = (level - cz[k]) / (cz[j] - cz[k]);
        crossing[k] = {cx[k] + t * (cx[j] - cx[k]), cy[k] + t * (cy[j] - cy[k])};
        crosses[k] = true;
      }
      const int count = crosses[0] + crosses[1] + crosses[2] + crosses[3];
      if (count == 2) {
        int first = -1, second = -1;
        for (int k = 0; k < 4; ++k)
          if (crosses[k]) (first < 0 ? first : second) = k;
        segments.push_back({crossing[first], crossing[second]});
      } else if (count == 4) {
        // Saddle: the centre (mean of the corners) decides which corners the level separates.
        const bool centre_above = (cz[0] + cz[1] + cz[2] + cz[3]) / 4 >= level;
        const bool corner0_above = cz[0] >= level;
        if (centre_above == corner0_above) {
          segments.push_back({crossing[0], crossing[1]});
          segments.push_back({crossing[2], crossing[3]});
        } else {
          segments.push_back({crossing[3], crossing[0]});
          segments.push_back({crossing[1], crossing[2]});
        }
      }
    }
  return segments;
}

std::string render_heat_map(const HeatMap& map, ImageFormat format) {
  Canvas canvas(kWidth, kHeight, format);
  const Font title_font{15, true}, info_font{12, false}, tick_font{12, false}, axis_font{13, false};
  const double top = draw_title_block(canvas, 16, 12, kWidth - 32, map.title, title_font, info_font) + 8;
  const std::size_t nx = map.x.size(), ny = map.y.size();

  const ColourBar colour_bar{map.z_min, map.z_max, map.z_label};
  const double bar_block = colour_bar_width(canvas, colour_bar, tick_font, axis_font);
  const std::vector<double> z_ticks = nice_ticks(map.z_min, map.z_max, 6);

  Axis x_axis{nx ? map.x.front() : 0, nx ? map.x.back() : 1, false, map.x_label};
  Axis y_axis{ny ? map.y.front() : 0, ny ? map.y.back() : 1, false, map.y_label};
  if (!(x_axis.hi > x_axis.lo)) x_axis.hi = x_axis.lo + 1;
  if (!(y_axis.hi > y_axis.lo)) y_axis.hi = y_axis.lo + 1;
  const PlotArea area = layout_plot(canvas, Box{12, top, kWidth - 12 - bar_block, kHeight - top - 10}, x_axis, y_axis,
                                    tick_font, axis_font);
  const Box& b = area.box;
  const double span = map.z_max - map.z_min;
  if (nx > 0 && ny > 0 && map.z.size() >= nx * ny) {
    // One cell per grid point, centred on it: the grid's ends sit half a cell inside the frame's edges.
    std::vector<Colour> cells(nx * ny);
    for (std::size_t iy = 0; iy < ny; ++iy)
      for (std::size_t ix = 0; ix < nx; ++ix)
        cells[(ny - 1 - iy) * nx + ix] = viridis(span > 0 ? (map.z[iy * nx + ix] - map.z_min) / span : 0.5);
    canvas.raster(b.x, b.y, b.width, b.height, static_cast<int>(nx), static_cast<int>(ny), cells);
  }
  // Grid value k sits at the centre of cell k, so the data-to-pixel map runs from the first cell's centre.
  PlotArea cells_area = area;
  const double half_x = nx > 1 ? b.width / (2.0 * static_cast<double>(nx)) : 0;
  const double half_y = ny > 1 ? b.height / (2.0 * static_cast<double>(ny)) : 0;
  cells_area.box = Box{b.x + half_x, b.y + half_y, b.width - 2 * half_x, b.height - 2 * half_y};
  if (map.contours && span > 0)
    for (double level : z_ticks) {
      const double t = (level - map.z_min) / span;
      if (t <= 0 || t >= 1) continue;
      // Light lines over the dark end of viridis, dark over the light end.
      const Colour colour = t < 0.6 ? Colour{1, 1, 1, 0.75} : Colour{0, 0, 0, 0.6};
      for (const auto& [p, q] : contour_segments(map, level))
        canvas.line(cells_area.px(p.first), cells_area.py(p.second), cells_area.px(q.first), cells_area.py(q.second),
                    colour, 1.0);
    }
  // Axes over the cells: frame, ticks and labels (no grid lines across the picture).
  PlotArea ticks_area = cells_area;
  ticks_area.box = cells_area.box;
  canvas.frame(b.x, b.y, b.width, b.height, kBlack);
  for (double v : nice_ticks(x_axis.lo, x_axis.hi, 6)) {
    const double px = cells_area.px(v);
    canvas.line(px, b.y + b.height, px, b.y + b.height + 5, kBlack);
    canvas.text(px, b.y + b.height + 7, tick_label(v, false), tick_font, Align::Centre, Align::Start);
  }
  double label_left = b.x;
  for (double v : nice_ticks(y_axis.lo, y_axis.hi, 6)) {
    const double py = cells_area.py(v);
    canvas.line(b.x - 5, py, b.x, py, kBlack);
    label_left = std::min(label_left, canvas.text(b.x - 8, py, tick_label(v, false), tick_font, Align::End, Align::Centre).x);
  }
  const double x_title_y = b.y + b.height + 7 + canvas.measure("0", tick_font).second + 4;
  canvas.text(b.x + b.width / 2, x_title_y, map.x_label, axis_font, Align::Centre, Align::Start);
  canvas.text(label_left - 4, b.y + b.height / 2, map.y_label, axis_font, Align::Centre, Align::End, kBlack, true);

  // Colour bar, z_min at the bottom, its ticks at the contour levels.
  draw_colour_bar(canvas, b.x + b.width, b.y, b.height, colour_bar, tick_font, axis_font);
  return canvas.finish();
}

}  // namespace fmpc::plot
