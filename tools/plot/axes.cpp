#include "tools/plot/axes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "diagnostics/number_format.h"

namespace fmpc::plot {

std::vector<double> nice_ticks(double lo, double hi, int count) {
  std::vector<double> ticks;
  if (!(hi > lo) || !std::isfinite(lo) || !std::isfinite(hi) || count < 1) {
    if (std::isfinite(lo)) ticks.push_back(lo);
    return ticks;
  }
  const double raw = (hi - lo) / count;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  // The round step nearest to the raw one on a log scale.
  double step = magnitude;
  for (double m : {2.0, 5.0, 10.0})
    if (std::fabs(std::log(m * magnitude / raw)) < std::fabs(std::log(step / raw))) step = m * magnitude;
  const double first = std::ceil(lo / step - 1e-9) * step;
  for (int k = 0;; ++k) {
    double v = first + k * step;
    if (v > hi + step * 1e-9) break;
    if (std::fabs(v) < step * 1e-9) v = 0.0;  // no "-0" or "1e-17" for zero
    ticks.push_back(v);
  }
  return ticks;
}

std::vector<double> log_ticks(double lo, double hi) {
  std::vector<double> ticks;
  if (!(lo > 0) || !(hi >= lo) || !std::isfinite(hi)) return ticks;
  const int first = static_cast<int>(std::ceil(std::log10(lo) - 1e-9));
  const int last = static_cast<int>(std::floor(std::log10(hi) + 1e-9));
  const int step = std::max(1, (last - first) / 8);  // at most about 9 labelled decades
  for (int e = first; e <= last; e += step) ticks.push_back(std::pow(10.0, e));
  if (ticks.size() >= 2) return ticks;
  ticks.clear();
  for (int e = first - 1; e <= last; ++e)
    for (double m : {1.0, 2.0, 5.0}) {
      const double v = m * std::pow(10.0, e);
      if (v >= lo * (1 - 1e-9) && v <= hi * (1 + 1e-9)) ticks.push_back(v);
    }
  return ticks;
}

std::string tick_label(double value, bool log) {
  if (log) {
    const double exponent = std::log10(value);
    if (std::fabs(exponent - std::round(exponent)) < 1e-9) {
      static const char* const kSuperscripts[] = {"⁰", "¹", "²", "³", "⁴", "⁵", "⁶", "⁷", "⁸", "⁹"};
      const int e = static_cast<int>(std::lround(exponent));
      if (e == 0) return "1";
      if (e == 1) return "10";
      std::string text = "10";
      if (e < 0) text += "⁻";
      for (char digit : std::to_string(std::abs(e))) text += kSuperscripts[digit - '0'];
      return text;
    }
  }
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", value);
  return text;
}

Axis rounded(Axis axis) {
  if (axis.log) {
    axis.lo = std::pow(10.0, std::floor(std::log10(axis.lo) + 1e-9));
    axis.hi = std::pow(10.0, std::ceil(std::log10(axis.hi) - 1e-9));
    if (!(axis.hi > axis.lo)) axis.hi = axis.lo * 10;
    return axis;
  }
  if (!(axis.hi > axis.lo)) {
    const double pad = axis.lo == 0 ? 1.0 : std::fabs(axis.lo) * 0.1;
    axis.lo -= pad;
    axis.hi += pad;
  }
  const std::vector<double> ticks = nice_ticks(axis.lo, axis.hi, 6);
  if (ticks.size() >= 2) {
    const double step = ticks[1] - ticks[0];
    axis.lo = std::min(axis.lo, std::floor(axis.lo / step + 1e-9) * step);
    axis.hi = std::max(axis.hi, std::ceil(axis.hi / step - 1e-9) * step);
  }
  return axis;
}

namespace {

std::vector<double> ticks_of(const Axis& axis) {
  return axis.log ? log_ticks(axis.lo, axis.hi) : nice_ticks(axis.lo, axis.hi, 6);
}

double fraction(const Axis& axis, double value) {
  if (axis.log) return (std::log10(value) - std::log10(axis.lo)) / (std::log10(axis.hi) - std::log10(axis.lo));
  return (value - axis.lo) / (axis.hi - axis.lo);
}

constexpr double kTickLength = 5;
constexpr double kGap = 6;

}  // namespace

double PlotArea::px(double value) const { return box.x + fraction(x, value) * box.width; }
double PlotArea::py(double value) const { return box.y + box.height - fraction(y, value) * box.height; }

PlotArea layout_plot(Canvas& canvas, const Box& available, const Axis& x, const Axis& y, const Font& tick_font,
                     const Font& title_font) {
  double y_label_width = 0, x_label_height = 0, x_label_half = 0;
  for (double v : ticks_of(y)) y_label_width = std::max(y_label_width, canvas.measure(tick_label(v, y.log), tick_font).first);
  for (double v : ticks_of(x)) {
    const auto [w, h] = canvas.measure(tick_label(v, x.log), tick_font);
    x_label_height = std::max(x_label_height, h);
    x_label_half = std::max(x_label_half, w / 2);
  }
  const double y_title = y.title.empty() ? 0 : canvas.measure(y.title, title_font).second + kGap;
  const double x_title = x.title.empty() ? 0 : canvas.measure(x.title, title_font).second + kGap;
  const double left = y_title + y_label_width + kTickLength + kGap;
  const double bottom = x_title + x_label_height + kTickLength + kGap;
  PlotArea area;
  area.x = x;
  area.y = y;
  area.box = Box{available.x + left, available.y + tick_font.size / 2 + 2,
                 available.width - left - x_label_half - 2, available.height - bottom - tick_font.size / 2 - 2};
  return area;
}

void draw_axes(Canvas& canvas, const PlotArea& area, const Font& tick_font, const Font& title_font, bool x_labels) {
  const Box& b = area.box;
  const std::vector<double> x_ticks = ticks_of(area.x), y_ticks = ticks_of(area.y);
  for (double v : x_ticks) canvas.line(area.px(v), b.y, area.px(v), b.y + b.height, kGridGrey);
  for (double v : y_ticks) canvas.line(b.x, area.py(v), b.x + b.width, area.py(v), kGridGrey);
  canvas.frame(b.x, b.y, b.width, b.height, kBlack);
  double label_bottom = b.y + b.height;
  for (double v : x_labels ? x_ticks : std::vector<double>{}) {
    canvas.line(area.px(v), b.y + b.height, area.px(v), b.y + b.height + kTickLength, kBlack);
    const Box label = canvas.text(area.px(v), b.y + b.height + kTickLength + 2, tick_label(v, area.x.log), tick_font,
                                  Align::Centre, Align::Start);
    label_bottom = std::max(label_bottom, label.y + label.height);
  }
  double label_left = b.x;
  for (double v : y_ticks) {
    canvas.line(b.x - kTickLength, area.py(v), b.x, area.py(v), kBlack);
    const Box label = canvas.text(b.x - kTickLength - 3, area.py(v), tick_label(v, area.y.log), tick_font, Align::End,
                                  Align::Centre);
    label_left = std::min(label_left, label.x);
  }
  if (x_labels && !area.x.title.empty())
    canvas.text(b.x + b.width / 2, label_bottom + kGap / 2, area.x.title, title_font, Align::Centre, Align::Start);
  if (!area.y.title.empty())
    canvas.text(label_left - kGap / 2, b.y + b.height / 2, area.y.title, title_font, Align::Centre, Align::End, kBlack,
                true);
}

double draw_title_block(Canvas& canvas, double x, double y, double width, const std::vector<std::string>& lines,
                        const Font& first_line, const Font& other_lines) {
  for (std::size_t k = 0; k < lines.size(); ++k) {
    Font font = k == 0 ? first_line : other_lines;
    // Shrink a long line to fit rather than clip it; below 8 px it would not be readable, so it wraps instead.
    double w = canvas.measure(lines[k], font).first;
    if (w > width) font.size = std::max(8.0, font.size * width / w);
    w = canvas.measure(lines[k], font).first;
    const Colour colour = k == 0 ? kBlack : kTextGrey;
    if (w <= width) {
      y += canvas.text(x, y, lines[k], font, Align::Start, Align::Start, colour).height + 2;
      continue;
    }
    // Wrap at spaces.
    std::string line;
    std::size_t start = 0;
    const std::string& text = lines[k];
    while (start < text.size()) {
      std::size_t end = text.find(' ', start);
      if (end == std::string::npos) end = text.size();
      const std::string word = text.substr(start, end - start);
      const std::string candidate = line.empty() ? word : line + " " + word;
      if (!line.empty() && canvas.measure(candidate, font).first > width) {
        y += canvas.text(x, y, line, font, Align::Start, Align::Start, colour).height + 2;
        line = word;
      } else {
        line = candidate;
      }
      start = end + 1;
    }
    if (!line.empty()) y += canvas.text(x, y, line, font, Align::Start, Align::Start, colour).height + 2;
  }
  return y;
}

}  // namespace fmpc::plot
