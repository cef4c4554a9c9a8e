#include "tools/plot/pareto_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "tools/plot/bitmap_font.h"

namespace fmpc::plot {

namespace {

constexpr int kWidth = 720;
constexpr int kHeight = 540;
constexpr int kLeft = 110;
constexpr int kTop = 70;
constexpr int kAreaWidth = 560;
constexpr int kAreaHeight = 380;
const Rgb kBlack{0, 0, 0};
const Rgb kGrey{200, 200, 200};
const Rgb kFront{200, 40, 40};
const Rgb kPoint{30, 90, 180};

// Bresenham's line (integer, all octants).
void draw_line(RgbImage& image, int x0, int y0, int x1, int y1, Rgb colour) {
  const int dx = std::abs(x1 - x0), dy = -std::abs(y1 - y0);
  const int sx = x0 < x1 ? 1 : -1, sy = y0 < y1 ? 1 : -1;
  int error = dx + dy;
  while (true) {
    image.set(x0, y0, colour);
    if (x0 == x1 && y0 == y1) return;
    const int twice = 2 * error;
    if (twice >= dy) {
      error += dy;
      x0 += sx;
    }
    if (twice <= dx) {
      error += dx;
      y0 += sy;
    }
  }
}

std::string power_of_ten(int exponent) {
  char text[16];
  std::snprintf(text, sizeof text, "1e%d", exponent);
  return text;
}

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

RgbImage render_trade_plot(const TradePlot& plot) {
  RgbImage image(kWidth, kHeight, Rgb{255, 255, 255});
  // Decades spanning the data; errors of 0 sit on the floor, one decade below the smallest non-zero error.
  double speed_lo = 1e300, speed_hi = 0, error_lo = 1e300, error_hi = 0;
  for (const TradePoint& p : plot.points) {
    speed_lo = std::min(speed_lo, p.evaluations_per_second);
    speed_hi = std::max(speed_hi, p.evaluations_per_second);
    if (p.max_error > 0) {
      error_lo = std::min(error_lo, p.max_error);
      error_hi = std::max(error_hi, p.max_error);
    }
  }
  if (!(speed_hi > 0)) speed_lo = speed_hi = 1;
  if (!(error_hi > 0)) error_lo = error_hi = 1;
  const int x_lo = static_cast<int>(std::floor(std::log10(speed_lo)));
  const int x_hi = std::max(x_lo + 1, static_cast<int>(std::ceil(std::log10(speed_hi))));
  const int y_lo = static_cast<int>(std::floor(std::log10(error_lo))) - 1;
  const int y_hi = std::max(y_lo + 1, static_cast<int>(std::ceil(std::log10(error_hi))));
  const auto px = [&](double speed) {
    return kLeft + static_cast<int>(std::lround((std::log10(speed) - x_lo) / (x_hi - x_lo) * kAreaWidth));
  };
  const auto py = [&](double error) {
    const double decade = error > 0 ? std::max(std::log10(error), static_cast<double>(y_lo)) : y_lo;
    return kTop + kAreaHeight - static_cast<int>(std::lround((decade - y_lo) / (y_hi - y_lo) * kAreaHeight));
  };

  for (int e = x_lo; e <= x_hi; ++e) {
    const int x = kLeft + (e - x_lo) * kAreaWidth / (x_hi - x_lo);
    draw_line(image, x, kTop, x, kTop + kAreaHeight, kGrey);
    const std::string label = power_of_ten(e);
    draw_text(image, x - text_width(label, 2) / 2, kTop + kAreaHeight + 8, label, kBlack, 2);
  }
  for (int e = y_lo; e <= y_hi; ++e) {
    const int y = kTop + kAreaHeight - (e - y_lo) * kAreaHeight / (y_hi - y_lo);
    draw_line(image, kLeft, y, kLeft + kAreaWidth, y, kGrey);
    const std::string label = e == y_lo ? "0" : power_of_ten(e);
    draw_text(image, kLeft - 8 - text_width(label, 2), y - text_height(2) / 2, label, kBlack, 2);
  }
  draw_line(image, kLeft, kTop + kAreaHeight, kLeft + kAreaWidth, kTop + kAreaHeight, kBlack);
  draw_line(image, kLeft, kTop, kLeft, kTop + kAreaHeight, kBlack);
  const std::string& x_label = plot.speed_label;
  draw_text(image, kLeft + (kAreaWidth - text_width(x_label, 2)) / 2, kTop + kAreaHeight + 34, x_label, kBlack, 2);
  const std::string y_label = "max error" + (plot.error_unit.empty() ? "" : " (" + plot.error_unit + ")");
  draw_text(image, 20, kTop + (kAreaHeight + text_width(y_label, 2)) / 2, y_label, kBlack, 2, true);
  for (std::size_t line = 0; line < plot.title.size(); ++line)
    draw_text(image, kLeft, 14 + static_cast<int>(line) * 20, plot.title[line], kBlack, 2);

  const std::vector<std::size_t> front = pareto_front(plot.points);
  for (std::size_t k = 0; k + 1 < front.size(); ++k) {
    const TradePoint& a = plot.points[front[k]];
    const TradePoint& b = plot.points[front[k + 1]];
    draw_line(image, px(a.evaluations_per_second), py(a.max_error), px(b.evaluations_per_second),
              py(b.max_error), kFront);
  }
  for (std::size_t i = 0; i < plot.points.size(); ++i) {
    const TradePoint& p = plot.points[i];
    const bool on_front = std::find(front.begin(), front.end(), i) != front.end();
    const int x = px(p.evaluations_per_second), y = py(p.max_error);
    image.fill_rect(x - 3, y - 3, 7, 7, on_front ? kFront : kPoint);
    draw_text(image, x + 6, y - 10 - static_cast<int>(i % 2) * 10, p.label, kBlack, 1);
  }
  return image;
}

}  // namespace fmpc::plot
