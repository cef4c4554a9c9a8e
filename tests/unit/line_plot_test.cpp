// tools/plot/line_plot.h: the figure's size with and without a legend, and every curve drawn in its colour.
#include <catch2/catch.hpp>

#include "tools/plot/line_plot.h"

namespace {

using fmpc::plot::LinePlot;
using fmpc::plot::LineSeries;
using fmpc::plot::Rgb;
using fmpc::plot::RgbImage;

std::size_t count_colour(const RgbImage& image, Rgb colour) {
  std::size_t count = 0;
  for (int y = 0; y < image.height(); ++y)
    for (int x = 0; x < image.width(); ++x) count += image.at(x, y) == colour ? 1 : 0;
  return count;
}

}  // namespace

TEST_CASE("line plot: one curve, no legend; several curves, a legend below the axes", "[plot]") {
  LineSeries rising{"rising", {0.0, 1.0, 2.0}, {0.0, 1.0, 4.0}, fmpc::plot::series_colour(0)};
  LineSeries falling{"falling", {0.0, 2.0}, {3.0, -1.0}, fmpc::plot::series_colour(1)};
  LineSeries flat{"flat", {0.5, 1.5}, {2.0, 2.0}, fmpc::plot::series_colour(2)};
  const RgbImage one = fmpc::plot::render_line_plot({"one", "x", "y", {rising}});
  CHECK(one.width() == 640);
  CHECK(one.height() == 480);
  CHECK(count_colour(one, rising.colour) > 500);  // a 3-pixel line across the plot area
  const RgbImage three = fmpc::plot::render_line_plot({"three", "x", "y", {rising, falling, flat}});
  CHECK(three.height() == 480 + 2 * (7 + 6) + 10);  // two legend rows of 7-pixel text
  for (const auto& series : {rising, falling, flat}) {
    INFO(series.label);
    CHECK(count_colour(three, series.colour) > 16 * 3);  // the curve and its legend mark
  }
  // Legend marks lie below the axes: the falling curve's colour appears under y = 480.
  bool below = false;
  for (int y = 480; y < three.height(); ++y)
    for (int x = 0; x < three.width(); ++x) below = below || three.at(x, y) == falling.colour;
  CHECK(below);
  CHECK_FALSE(fmpc::plot::series_colour(0) == fmpc::plot::series_colour(1));
  CHECK(fmpc::plot::series_colour(8) == fmpc::plot::series_colour(0));
}
