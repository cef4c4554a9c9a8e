#include "tools/plot/pareto_plot.h"

#include <algorithm>
#include <cmath>
#include <map>

#include "tools/plot/axes.h"

namespace fmpc::plot {

namespace {

constexpr int kWidth = 860;
constexpr int kHeight = 600;
constexpr double kExactStrip = 34;  // height of the "0 (exact)" strip below the log axis
constexpr double kMarker = 5;
const Colour kFront{0.84, 0.15, 0.16, 1};
const Colour kBound{0.2, 0.45, 0.2, 1};  // the required error's line

}  // namespace

std::vector<std::size_t> pareto_front(const std::vector<TradePoint>& points) {
  std::vector<std::size_t> front;
  for (std::size_t i = 0; i < points.size(); ++i) {
    bool dominated = false;
    for (std::size_t j = 0; j < points.size() && !dominated; ++j) {
      if (i == j) continue;
      const TradePoint& a = points[j];
      const TradePoint& b = points[i];
      dominated = a.evaluations_per_second >= b.evaluations_per_second && a.max_error <= b.max_error &&
                  (a.evaluations_per_second > b.evaluations_per_second || a.max_error < b.max_error);
    }
    if (!dominated) front.push_back(i);
  }
  std::sort(front.begin(), front.end(), [&](std::size_t a, std::size_t b) {
    return points[a].evaluations_per_second < points[b].evaluations_per_second;
  });
  return front;
}

std::string render_trade_plot(const TradePlot& plot, ImageFormat format, LabelPlacement* placement) {
  Canvas canvas(kWidth, kHeight, format);
  const Font title_font{15, true}, info_font{12, false}, tick_font{12, false}, axis_font{13, false},
      label_font{11, false}, legend_font{12, false};
  const double top = draw_title_block(canvas, 16, 12, kWidth - 32, plot.title, title_font, info_font) + 8;

  // Legend groups in order of first appearance, each with a colour.
  std::vector<std::string> kinds;
  for (const TradePoint& p : plot.points) {
    const std::string kind = p.kind.empty() ? "other" : p.kind;
    if (std::find(kinds.begin(), kinds.end(), kind) == kinds.end()) kinds.push_back(kind);
  }
  const auto colour_of = [&](const TradePoint& p) {
    const std::string kind = p.kind.empty() ? "other" : p.kind;
    return categorical_colour(static_cast<std::size_t>(std::find(kinds.begin(), kinds.end(), kind) - kinds.begin()));
  };
  const double legend_width = 200;

  double speed_lo = 1e300, speed_hi = 0, error_lo = 1e300, error_hi = 0;
  bool any_exact = false;
  for (const TradePoint& p : plot.points) {
    speed_lo = std::min(speed_lo, p.evaluations_per_second);
    speed_hi = std::max(speed_hi, p.evaluations_per_second);
    if (p.max_error > 0) {
      error_lo = std::min(error_lo, p.max_error);
      error_hi = std::max(error_hi, p.max_error);
    } else {
      any_exact = true;
    }
  }
  if (!(speed_hi > 0)) speed_lo = speed_hi = 1;
  if (plot.error_bound > 0) {
    error_lo = std::min(error_lo, plot.error_bound);
    error_hi = std::max(error_hi, plot.error_bound);
  }
  if (!(error_hi > 0)) error_lo = error_hi = 1;
  // Half a decade of room around the data so that markers and labels stay inside the frame.
  const Axis x_axis = rounded(Axis{speed_lo / 3, speed_hi * 3, true, plot.speed_label});
  const Axis y_axis = rounded(Axis{error_lo / 3, error_hi * 3, true,
                                   "max error" + (plot.error_unit.empty() ? "" : " (" + plot.error_unit + ")")});
  const double strip = any_exact ? kExactStrip : 0;
  PlotArea area = layout_plot(canvas, Box{12, top, kWidth - 12 - legend_width - 16, kHeight - top - 10 - strip},
                              x_axis, y_axis, tick_font, axis_font);
  // The strip for exact variants sits below the log area, inside the frame, with its own label; the x tick labels
  // move below it.
  const Box log_box = area.box;
  PlotArea drawn = area;
  drawn.box.height += strip;
  draw_axes(canvas, area, tick_font, axis_font, !any_exact);
  if (any_exact) {
    // The x tick labels and title go below the strip.
    const double strip_top = log_box.y + log_box.height;
    canvas.rectangle(log_box.x, strip_top, log_box.width, strip, Colour{0.96, 0.96, 0.96, 1});
    canvas.line(log_box.x, strip_top, log_box.x + log_box.width, strip_top, kBlack, 1, {4, 3});
    canvas.frame(log_box.x, log_box.y, log_box.width, log_box.height + strip, kBlack);
    canvas.text(log_box.x - 8, strip_top + strip / 2, "0 (exact)", tick_font, Align::End, Align::Centre);
    double label_bottom = strip_top + strip;
    for (double v : log_ticks(x_axis.lo, x_axis.hi)) {
      const double px = area.px(v);
      canvas.line(px, strip_top + strip, px, strip_top + strip + 5, kBlack);
      const Box b = canvas.text(px, strip_top + strip + 7, tick_label(v, true), tick_font, Align::Centre, Align::Start);
      label_bottom = std::max(label_bottom, b.y + b.height);
    }
    canvas.text(log_box.x + log_box.width / 2, label_bottom + 3, x_axis.title, axis_font, Align::Centre, Align::Start);
  }
  const auto point_xy = [&](const TradePoint& p) {
    const double x = area.px(p.evaluations_per_second);
    const double y = p.max_error > 0 ? area.py(p.max_error) : log_box.y + log_box.height + strip / 2;
    return std::pair<double, double>{x, y};
  };

  if (plot.error_bound > 0) {
    const double y = area.py(plot.error_bound);
    canvas.line(log_box.x, y, log_box.x + log_box.width, y, kBound, 1.5, {2, 3});
  }
  const std::vector<std::size_t> front = pareto_front(plot.points);
  std::vector<std::pair<double, double>> front_line;
  for (std::size_t i : front) front_line.push_back(point_xy(plot.points[i]));
  canvas.polyline(front_line, kFront, 2, {6, 4});

  // Labels: for each point, the first of eight positions around it whose box stays inside the plot and overlaps no
  // marker and no label placed before; points are taken from the most crowded first so that they get the choice.
  LabelPlacement local;
  LabelPlacement& labels = placement ? *placement : local;
  labels.boxes.assign(plot.points.size(), Box{});
  labels.placed.assign(plot.points.size(), false);
  std::vector<Box> markers;
  for (const TradePoint& p : plot.points) {
    const auto [x, y] = point_xy(p);
    markers.push_back(Box{x - kMarker - 1, y - kMarker - 1, 2 * kMarker + 2, 2 * kMarker + 2});
  }
  std::vector<Box> taken;
  const Box inside = drawn.box;
  for (std::size_t i = 0; i < plot.points.size(); ++i) {
    if (plot.points[i].label.empty()) continue;  // unlabelled on purpose: neither placed nor numbered
    const auto [x, y] = point_xy(plot.points[i]);
    const auto [w, h] = canvas.measure(plot.points[i].label, label_font);
    const double d = kMarker + 3;
    const Box candidates[] = {{x + d, y - h / 2, w, h},         {x - d - w, y - h / 2, w, h},
                              {x - w / 2, y - d - h, w, h},     {x - w / 2, y + d, w, h},
                              {x + d, y - d - h, w, h},         {x - d - w, y - d - h, w, h},
                              {x + d, y + d, w, h},             {x - d - w, y + d, w, h}};
    for (const Box& candidate : candidates) {
      if (!candidate.inside(inside)) continue;
      bool clear = true;
      for (const Box& m : markers) clear = clear && !candidate.overlaps(m);
      for (const Box& t : taken) clear = clear && !candidate.overlaps(t, 2);
      if (!clear) continue;
      labels.boxes[i] = candidate;
      labels.placed[i] = true;
      taken.push_back(candidate);
      break;
    }
  }
  // Markers, then labels (or numbers, listed in the legend).
  int numbered = 0;
  std::vector<std::pair<int, std::size_t>> numbers;
  for (std::size_t i = 0; i < plot.points.size(); ++i) {
    const auto [x, y] = point_xy(plot.points[i]);
    const bool on_front = std::find(front.begin(), front.end(), i) != front.end();
    canvas.circle(x, y, kMarker, colour_of(plot.points[i]), on_front ? kFront : kBlack, on_front ? 2 : 0.8);
    if (labels.placed[i]) {
      canvas.text(labels.boxes[i].x, labels.boxes[i].y, plot.points[i].label, label_font, Align::Start, Align::Start);
    } else if (!plot.points[i].label.empty()) {
      numbers.push_back({++numbered, i});
      canvas.text(x + kMarker + 1, y - kMarker - 1, std::to_string(numbered), label_font, Align::Start, Align::End);
    }
  }

  // Legend: the kinds, the front, the required error, then any numbered labels.
  double ly = log_box.y;
  const double lx = kWidth - legend_width - 8;
  labels.legend.clear();
  const auto entry = [&](const std::string& text) {
    labels.legend.push_back(text);
    ly += canvas.text(lx + 20, ly + 8, text, legend_font, Align::Start, Align::Centre).height + 6;
  };
  for (std::size_t k = 0; k < kinds.size(); ++k) {
    canvas.circle(lx + 8, ly + 8, kMarker, categorical_colour(k), kBlack, 0.8);
    entry(kinds[k]);
  }
  canvas.line(lx, ly + 8, lx + 16, ly + 8, kFront, 2, {6, 4});
  entry("Pareto front");
  canvas.circle(lx + 8, ly + 8, kMarker, kWhite, kFront, 2);
  entry("on the front");
  if (plot.error_bound > 0) {
    canvas.line(lx, ly + 8, lx + 16, ly + 8, kBound, 1.5, {2, 3});
    entry(plot.error_bound_label);
  }
  ly += 4;
  for (const auto& [number, index] : numbers) {
    const std::string text = std::to_string(number) + ": " + plot.points[index].label;
    labels.legend.push_back(text);
    Font font = label_font;
    const double w = canvas.measure(text, font).first;
    if (w > legend_width) font.size = std::max(8.0, font.size * legend_width / w);
    ly += canvas.text(lx, ly, text, font, Align::Start, Align::Start).height + 3;
  }
  return canvas.finish();
}

}  // namespace fmpc::plot
