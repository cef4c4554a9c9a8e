#include "tools/plot/line_chart.h"

#include <algorithm>
#include <cmath>

namespace fmpc::plot {

std::string render_line_chart(const LineChart& chart, ImageFormat format) {
  Canvas canvas(chart.width, chart.height, format);
  const Font title_font{15, true}, info_font{12, false}, tick_font{12, false}, axis_font{13, false},
      legend_font{12, false};
  const double top = draw_title_block(canvas, 16, 12, chart.width - 32, chart.title, title_font, info_font) + 8;

  // The legend and notes column: as wide as its widest entry, at most a third of the figure.
  double column = 0;
  for (const Series& s : chart.series)
    if (!s.name.empty()) column = std::max(column, 28 + canvas.measure(s.name, legend_font).first);
  for (const std::string& note : chart.notes) column = std::max(column, canvas.measure(note, legend_font).first + 12);
  column = std::min(column, chart.width / 3.0);
  const double bar = chart.colour_bar ? colour_bar_width(canvas, *chart.colour_bar, tick_font, axis_font) : 0;
  const double right = (column > 0 ? column + 20 : 0) + bar;

  const Axis x = chart.round_axes ? rounded(chart.x) : chart.x;
  const Axis y = chart.round_axes ? rounded(chart.y) : chart.y;
  const PlotArea area =
      layout_plot(canvas, Box{12, top, chart.width - 24 - right, chart.height - top - 10}, x, y, tick_font, axis_font);
  draw_axes(canvas, area, tick_font, axis_font);
  const Box& b = area.box;

  const auto points_of = [&](const std::vector<double>& xs, const std::vector<double>& ys) {
    std::vector<std::pair<double, double>> points;
    for (std::size_t k = 0; k < xs.size() && k < ys.size(); ++k)
      if (std::isfinite(xs[k]) && std::isfinite(ys[k])) points.push_back({area.px(xs[k]), area.py(ys[k])});
    return points;
  };
  for (const Series& s : chart.series) {
    if (s.y_lower.size() != s.y.size()) continue;
    std::vector<std::pair<double, double>> band = points_of(s.x, s.y);
    std::vector<std::pair<double, double>> lower = points_of(s.x, s.y_lower);
    band.insert(band.end(), lower.rbegin(), lower.rend());
    Colour fill = s.colour;
    fill.a = 0.25;
    canvas.polygon(band, fill);
  }
  for (const Series& s : chart.series) {
    if (s.line) canvas.polyline(points_of(s.x, s.y), s.colour, s.width, s.dashes);
    if (s.y_lower.size() == s.y.size()) canvas.polyline(points_of(s.x, s.y_lower), s.colour, s.width / 2, {3, 2});
    if (s.markers)
      for (const auto& [px, py] : points_of(s.x, s.y)) canvas.circle(px, py, 2.5, s.colour, s.colour, 0.5);
  }
  for (const VerticalMarker& m : chart.markers) {
    if (!(m.x >= x.lo && m.x <= x.hi)) continue;
    const double px = area.px(m.x);
    canvas.line(px, b.y, px, b.y + b.height, m.colour, 1.2, {5, 3});
    if (m.label.empty()) continue;
    // Inside the plot at the top, on whichever side of the line has room.
    const double w = canvas.measure(m.label, legend_font).first;
    const bool left = px + 4 + w > b.x + b.width;
    Colour background = kWhite;
    background.a = 0.85;
    const double lx = left ? px - 4 - w : px + 4;
    canvas.rectangle(lx - 1, b.y + 3, w + 2, legend_font.size + 4, background);
    canvas.text(lx, b.y + 3, m.label, legend_font, Align::Start, Align::Start, m.colour);
  }

  if (chart.colour_bar) draw_colour_bar(canvas, b.x + b.width, b.y, b.height, *chart.colour_bar, tick_font, axis_font);

  // Legend and notes to the right of the plot.
  double ly = b.y;
  const double lx = chart.width - column - 10;
  for (const Series& s : chart.series) {
    if (s.name.empty()) continue;
    if (s.y_lower.size() == s.y.size()) {
      Colour fill = s.colour;
      fill.a = 0.25;
      canvas.rectangle(lx, ly + 3, 20, 12, fill);
    }
    if (s.line) canvas.line(lx, ly + 9, lx + 20, ly + 9, s.colour, s.width, s.dashes);
    else canvas.circle(lx + 10, ly + 9, 3, s.colour, s.colour, 0.5);
    Font font = legend_font;
    const double w = canvas.measure(s.name, font).first;
    if (w > column - 28) font.size = std::max(8.0, font.size * (column - 28) / w);
    ly += canvas.text(lx + 28, ly + 9, s.name, font, Align::Start, Align::Centre).height + 6;
  }
  if (!chart.notes.empty()) {
    ly += 10;
    for (const std::string& note : chart.notes) {
      Font font = legend_font;
      const double w = canvas.measure(note, font).first;
      if (w > column) font.size = std::max(8.0, font.size * column / w);
      ly += canvas.text(lx, ly, note, font, Align::Start, Align::Start, kTextGrey).height + 3;
    }
  }
  return canvas.finish();
}

}  // namespace fmpc::plot
