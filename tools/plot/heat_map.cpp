#include "tools/plot/heat_map.h"

#include <algorithm>
#include <cmath>

#include "diagnostics/number_format.h"
#include "tools/plot/bitmap_font.h"

namespace fmpc::plot {

namespace {

constexpr Rgb kWhite{255, 255, 255};
constexpr Rgb kBlack{0, 0, 0};
constexpr Rgb kGrey{160, 160, 160};
constexpr int kScale = 2;  // text scale: 10 x 14 pixel characters
constexpr int kWidth = 640;
constexpr int kHeight = 540;
constexpr int kBarLeft = kPlotLeft + kPlotSize + 24;
constexpr int kBarWidth = 22;

// Index of the grid cell that pixel offset `p` (0 .. size-1) of the plot area falls in.
std::size_t cell_of(int p, std::size_t cells) {
  const auto index = static_cast<std::size_t>(static_cast<double>(p) * static_cast<double>(cells) / kPlotSize);
  return std::min(index, cells - 1);
}

std::string tick_text(double value) { return format_number(std::fabs(value) < 1e-12 ? 0.0 : value); }

}  // namespace

Rgb viridis(double t) {
  // Nine samples of matplotlib's viridis table (_cm_listed.py, entries 0, 32, ..., 255), linearly interpolated.
  static constexpr double kStops[9][3] = {
      {0.267004, 0.004874, 0.329415}, {0.277018, 0.185228, 0.489898}, {0.229739, 0.322361, 0.545706},
      {0.172719, 0.448791, 0.557885}, {0.127568, 0.566949, 0.550556}, {0.157851, 0.683765, 0.501686},
      {0.369214, 0.788888, 0.382914}, {0.678489, 0.863742, 0.189503}, {0.993248, 0.906157, 0.143936}};
  if (std::isnan(t)) return kGrey;
  t = std::clamp(t, 0.0, 1.0) * 8.0;
  const auto i = std::min(static_cast<int>(t), 7);
  const double f = t - i;
  auto channel = [&](int c) {
    const double v = kStops[i][c] + f * (kStops[i + 1][c] - kStops[i][c]);
    return static_cast<std::uint8_t>(std::lround(v * 255.0));
  };
  return {channel(0), channel(1), channel(2)};
}

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
    const double v = first + k * step;
    if (v > hi + step * 1e-9) break;
    ticks.push_back(v);
  }
  return ticks;
}

RgbImage render_heat_map(const HeatMap& map) {
  RgbImage image(kWidth, kHeight, kWhite);
  const std::size_t nx = map.x.size(), ny = map.y.size();
  const double span = map.z_max - map.z_min;
  auto colour_of = [&](double z) { return viridis(span > 0 ? (z - map.z_min) / span : 0.5); };

  // Cells: grid row 0 at the bottom.
  if (nx > 0 && ny > 0 && map.z.size() >= nx * ny)
    for (int py = 0; py < kPlotSize; ++py) {
      const std::size_t iy = cell_of(kPlotSize - 1 - py, ny);
      for (int px = 0; px < kPlotSize; ++px)
        image.set(kPlotLeft + px, kPlotTop + py, colour_of(map.z[iy * nx + cell_of(px, nx)]));
    }
  // Frame.
  image.fill_rect(kPlotLeft - 1, kPlotTop - 1, kPlotSize + 2, 1, kBlack);
  image.fill_rect(kPlotLeft - 1, kPlotTop + kPlotSize, kPlotSize + 2, 1, kBlack);
  image.fill_rect(kPlotLeft - 1, kPlotTop - 1, 1, kPlotSize + 2, kBlack);
  image.fill_rect(kPlotLeft + kPlotSize, kPlotTop - 1, 1, kPlotSize + 2, kBlack);

  const int char_h = text_height(kScale);
  // Axis ticks: grid values map to pixel centres of their cells' span, i.e. linearly from the first to the last.
  if (nx > 1) {
    const double x0 = map.x.front(), x1 = map.x.back();
    for (double v : nice_ticks(x0, x1, 6)) {
      const int px = kPlotLeft + static_cast<int>(std::lround((v - x0) / (x1 - x0) * (kPlotSize - 1)));
      image.fill_rect(px, kPlotTop + kPlotSize, 1, 6, kBlack);
      const std::string label = tick_text(v);
      draw_text(image, px - text_width(label, kScale) / 2, kPlotTop + kPlotSize + 10, label, kBlack, kScale);
    }
  }
  if (ny > 1) {
    const double y0 = map.y.front(), y1 = map.y.back();
    for (double v : nice_ticks(y0, y1, 6)) {
      const int py = kPlotTop + kPlotSize - 1 - static_cast<int>(std::lround((v - y0) / (y1 - y0) * (kPlotSize - 1)));
      image.fill_rect(kPlotLeft - 7, py, 6, 1, kBlack);
      const std::string label = tick_text(v);
      draw_text(image, kPlotLeft - 10 - text_width(label, kScale), py - char_h / 2, label, kBlack, kScale);
    }
  }
  draw_text(image, kPlotLeft + (kPlotSize - text_width(map.x_label, kScale)) / 2, kPlotTop + kPlotSize + 34,
            map.x_label, kBlack, kScale);
  draw_text(image, 12, kPlotTop + (kPlotSize + text_width(map.y_label, kScale)) / 2, map.y_label, kBlack, kScale,
            true);
  for (std::size_t line = 0; line < map.title.size(); ++line)
    draw_text(image, 12, 10 + static_cast<int>(line) * (char_h + 6), map.title[line], kBlack, kScale);

  // Colour bar, z_min at the bottom.
  for (int py = 0; py < kPlotSize; ++py) {
    const double t = 1.0 - static_cast<double>(py) / (kPlotSize - 1);
    image.fill_rect(kBarLeft, kPlotTop + py, kBarWidth, 1, viridis(t));
  }
  image.fill_rect(kBarLeft - 1, kPlotTop - 1, kBarWidth + 2, 1, kBlack);
  image.fill_rect(kBarLeft - 1, kPlotTop + kPlotSize, kBarWidth + 2, 1, kBlack);
  image.fill_rect(kBarLeft - 1, kPlotTop - 1, 1, kPlotSize + 2, kBlack);
  image.fill_rect(kBarLeft + kBarWidth, kPlotTop - 1, 1, kPlotSize + 2, kBlack);
  if (span > 0)
    for (double v : nice_ticks(map.z_min, map.z_max, 6)) {
      const int py = kPlotTop + kPlotSize - 1 - static_cast<int>(std::lround((v - map.z_min) / span * (kPlotSize - 1)));
      image.fill_rect(kBarLeft + kBarWidth, py, 5, 1, kBlack);
      draw_text(image, kBarLeft + kBarWidth + 8, py - char_h / 2, tick_text(v), kBlack, kScale);
    }
  draw_text(image, kWidth - 22, kPlotTop + (kPlotSize + text_width(map.z_label, kScale)) / 2, map.z_label, kBlack,
            kScale, true);
  return image;
}

}  // namespace fmpc::plot
