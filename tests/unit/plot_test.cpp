// Pictures (tools/plot/, cairo and pango): ticks and log axes, contours, heat-map colours read back from the PNG,
// trade-plot labels that never overlap or leave the plot, SVG output, and figures of every kind that decode.
#include <cairo.h>
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "tools/plot/axes.h"
#include "tools/plot/heat_map.h"
#include "tools/plot/line_chart.h"
#include "tools/plot/pareto_plot.h"
#include "tools/plot/rule_view.h"

using namespace fmpc::plot;

namespace {

struct Decoded {
  int width = 0;
  int height = 0;
  std::vector<std::uint32_t> pixels;  // 0x00RRGGBB
  std::uint32_t at(int x, int y) const { return pixels[static_cast<std::size_t>(y) * width + x] & 0xFFFFFFu; }
};

struct PngReader {
  const std::string* bytes;
  std::size_t at = 0;
};

cairo_status_t read_png_bytes(void* closure, unsigned char* data, unsigned int length) {
  auto* reader = static_cast<PngReader*>(closure);
  if (reader->at + length > reader->bytes->size()) return CAIRO_STATUS_READ_ERROR;
  std::memcpy(data, reader->bytes->data() + reader->at, length);
  reader->at += length;
  return CAIRO_STATUS_SUCCESS;
}

// Decodes a PNG with cairo's reader (libpng): the bytes must be a valid PNG.
Decoded decode(const std::string& png) {
  PngReader reader{&png};
  cairo_surface_t* surface = cairo_image_surface_create_from_png_stream(read_png_bytes, &reader);
  REQUIRE(cairo_surface_status(surface) == CAIRO_STATUS_SUCCESS);
  Decoded image;
  image.width = cairo_image_surface_get_width(surface);
  image.height = cairo_image_surface_get_height(surface);
  const int stride = cairo_image_surface_get_stride(surface);
  const unsigned char* data = cairo_image_surface_get_data(surface);
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      std::uint32_t pixel;
      std::memcpy(&pixel, data + static_cast<std::ptrdiff_t>(y) * stride + 4 * x, 4);
      image.pixels.push_back(pixel);
    }
  cairo_surface_destroy(surface);
  return image;
}

std::uint32_t rgb_of(Colour c) {
  const auto byte = [](double v) { return static_cast<std::uint32_t>(std::lround(v * 255)); };
  return (byte(c.r) << 16) | (byte(c.g) << 8) | byte(c.b);
}

bool close_colour(std::uint32_t a, std::uint32_t b, int tolerance = 2) {
  for (int shift : {0, 8, 16})
    if (std::abs(static_cast<int>((a >> shift) & 0xFF) - static_cast<int>((b >> shift) & 0xFF)) > tolerance)
      return false;
  return true;
}

}  // namespace

TEST_CASE("ticks: round linear steps, decades on log axes, never a 0 on a log axis", "[plot]") {
  CHECK(nice_ticks(0, 75, 6) == std::vector<double>{0, 10, 20, 30, 40, 50, 60, 70});
  CHECK(nice_ticks(5.3, 22.9, 6) == std::vector<double>{6, 8, 10, 12, 14, 16, 18, 20, 22});
  CHECK(nice_ticks(3, 3, 6) == std::vector<double>{3});
  CHECK(nice_ticks(0, std::numeric_limits<double>::infinity(), 6) == std::vector<double>{0});
  for (double v : nice_ticks(-0.3, 0.3, 6)) CHECK(tick_label(v, false) != "-0");
  CHECK(log_ticks(1e-4, 1e2) == std::vector<double>{1e-4, 1e-3, 1e-2, 1e-1, 1, 10, 100});
  CHECK(log_ticks(2, 30).size() >= 2);
  CHECK(log_ticks(0, 10).empty());
  CHECK(tick_label(1e-3, true) == "10⁻³");
  CHECK(tick_label(1e6, true) == "10⁶");
  CHECK(tick_label(1, true) == "1");
  CHECK(tick_label(10, true) == "10");
  // Seeded: every log tick inside the range, positive, and in increasing order.
  std::mt19937 random(7);
  std::uniform_real_distribution<double> exponent(-12, 12);
  for (int k = 0; k < 2000; ++k) {
    double a = std::pow(10, exponent(random)), b = std::pow(10, exponent(random));
    if (a > b) std::swap(a, b);
    const std::vector<double> ticks = log_ticks(a, b);
    for (std::size_t i = 0; i < ticks.size(); ++i) {
      CHECK(ticks[i] > 0);
      CHECK(ticks[i] >= a * (1 - 1e-9));
      CHECK(ticks[i] <= b * (1 + 1e-9));
      if (i) CHECK(ticks[i] > ticks[i - 1]);
    }
    const Axis r = rounded(Axis{a, b, true, ""});
    CHECK(r.lo <= a);
    CHECK(r.hi >= b);
    CHECK(log_ticks(r.lo, r.hi).size() >= 2);
  }
}

TEST_CASE("viridis ends and NaN", "[plot]") {
  CHECK(rgb_of(viridis(0.0)) == 0x440154u);
  CHECK(rgb_of(viridis(1.0)) == 0xFDE725u);
  CHECK(rgb_of(viridis(-3.0)) == rgb_of(viridis(0.0)));
  CHECK(rgb_of(viridis(7.0)) == rgb_of(viridis(1.0)));
  CHECK(rgb_of(viridis(std::nan(""))) == rgb_of(Colour{0.6, 0.6, 0.6, 1}));
}

TEST_CASE("contours of a plane are straight lines at the level", "[plot]") {
  HeatMap map;
  map.x = {0, 1, 2, 3};
  map.y = {0, 1, 2};
  for (double y : map.y)
    for (double x : map.x) map.z.push_back(x + 0 * y);  // z = x
  const auto segments = contour_segments(map, 1.5);
  REQUIRE(segments.size() == 2);  // one per row of cells
  for (const auto& [p, q] : segments) {
    CHECK(p.first == Approx(1.5));
    CHECK(q.first == Approx(1.5));
  }
  CHECK(contour_segments(map, 7).empty());
  map.z[0] = std::nan("");
  CHECK(contour_segments(map, 0.5).size() == 1);  // of the two crossing cells, one has a NaN corner
  // A saddle gives two segments, not four.
  HeatMap saddle;
  saddle.x = {0, 1};
  saddle.y = {0, 1};
  saddle.z = {1, 0, 0, 1};
  CHECK(contour_segments(saddle, 0.5).size() == 2);
}

TEST_CASE("a heat map colours each grid cell by its value on the shared scale", "[plot]") {
  HeatMap map;
  map.x = {0, 1};
  map.y = {0, 1};
  map.z = {0.0, 1.0, 2.0, std::nan("")};  // row 0 (bottom): 0, 1; row 1 (top): 2, NaN
  map.z_min = 0;
  map.z_max = 4;  // a wider scale than the data: 2 is mid-scale
  map.contours = false;
  map.x_label = "x (µm)";
  map.y_label = "y";
  map.z_label = "z (kPa)";
  map.title = {"a title", "fixed: w = 3 kPa"};
  const Decoded image = decode(render_heat_map(map, ImageFormat::Png));
  CHECK(image.width == 760);
  CHECK(image.height == 600);
  // Find the plot area: the largest run of the bottom-left cell's colour along the middle of the lower half.
  const std::uint32_t bottom_left = rgb_of(viridis(0.0));
  int left = -1, right = -1, row = -1;
  for (int y = image.height / 2; y < image.height && row < 0; ++y)
    for (int x = 0; x < image.width; ++x)
      if (image.at(x, y) == bottom_left) {
        row = y;
        left = x;
        while (x < image.width && image.at(x, y) == bottom_left) ++x;
        right = x;
        break;
      }
  REQUIRE(row > 0);
  const int cell = right - left;  // one cell's width
  CHECK(close_colour(image.at(left + cell + cell / 2, row), rgb_of(viridis(0.25))));
  // Up one cell: find the top row's colours above.
  int up = row;
  while (up > 0 && image.at(left + cell / 2, up) == bottom_left) --up;
  CHECK(close_colour(image.at(left + cell / 2, up - 5), rgb_of(viridis(0.5))));
  CHECK(close_colour(image.at(left + cell + cell / 2, up - 5), rgb_of(viridis(std::nan("")))));
}

TEST_CASE("trade-plot labels never overlap each other or a marker, and stay inside", "[plot]") {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> exponent(0, 1);
  for (int trial = 0; trial < 20; ++trial) {
    TradePlot plot;
    plot.error_unit = "kPa";
    plot.title = {"trial " + std::to_string(trial)};
    const int n = 3 + trial;
    for (int k = 0; k < n; ++k)
      plot.points.push_back({"variant number " + std::to_string(k), std::pow(10, 3 + 4 * exponent(random)),
                             k % 5 == 0 ? 0.0 : std::pow(10, -6 + 5 * exponent(random)),
                             k % 3 == 0 ? "table" : "compiled C++"});
    LabelPlacement placement;
    const Decoded image = decode(render_trade_plot(plot, ImageFormat::Png, &placement));
    CHECK(image.width == 860);
    REQUIRE(placement.boxes.size() == plot.points.size());
    std::size_t placed = 0;
    for (std::size_t i = 0; i < placement.boxes.size(); ++i) {
      if (!placement.placed[i]) continue;
      ++placed;
      const Box& a = placement.boxes[i];
      CHECK(a.x >= 0);
      CHECK(a.y >= 0);
      CHECK(a.x + a.width <= image.width);
      CHECK(a.y + a.height <= image.height);
      for (std::size_t j = i + 1; j < placement.boxes.size(); ++j)
        if (placement.placed[j]) CHECK_FALSE(a.overlaps(placement.boxes[j]));
    }
    CHECK(placed > 0);
  }
  CHECK(decode(render_trade_plot({}, ImageFormat::Png)).width == 860);  // no points: axes only
}

TEST_CASE("SVG output is an SVG document", "[plot]") {
  LineChart chart;
  chart.title = {"terms of 'x' (µm)"};
  chart.x = Axis{0, 10, false, "x (µm)"};
  chart.y = Axis{0, 1, false, "degree of membership"};
  chart.series.push_back(Series{"low", {0, 5, 10}, {1, 0.5, 0}, {}, categorical_colour(0), 2, {}, false});
  const std::string svg = render_line_chart(chart, ImageFormat::Svg);
  CHECK(svg.rfind("<?xml", 0) == 0);
  CHECK(svg.find("<svg") != std::string::npos);
  CHECK(svg.find("</svg>") != std::string::npos);
  CHECK(image_format_for("a/b.SVG") == ImageFormat::Svg);
  CHECK(image_format_for("a/b.png") == ImageFormat::Png);
  CHECK(image_format_for("svg") == ImageFormat::Png);
}

TEST_CASE("a line chart draws its curve, its band and text in anti-aliased colour", "[plot]") {
  LineChart chart;
  chart.title = {"membership functions", "E = 9.8 kPa, σ ≈ 0.2 µm"};
  chart.x = Axis{0, 10, false, "x (µm)"};
  chart.y = Axis{0, 1, false, "degree of membership"};
  Series band{"type-2", {0, 5, 10}, {0.2, 1, 0.2}, {0.1, 0.6, 0.1}, categorical_colour(1), 2, {}, false};
  chart.series.push_back(band);
  chart.notes = {"a note"};
  const Decoded image = decode(render_line_chart(chart, ImageFormat::Png));
  CHECK(image.width == 760);
  CHECK(image.height == 520);
  std::size_t grey_levels = 0, curve = 0;
  const std::uint32_t orange = rgb_of(categorical_colour(1));
  for (std::uint32_t p : image.pixels) {
    const std::uint32_t c = p & 0xFFFFFFu;
    const int r = c >> 16 & 0xFF, g = c >> 8 & 0xFF, b = c & 0xFF;
    if (r == g && g == b && r > 0 && r < 255) ++grey_levels;  // anti-aliased text and lines
    if (close_colour(c, orange, 8)) ++curve;
  }
  CHECK(grey_levels > 200);
  CHECK(curve > 100);
}

TEST_CASE("a rule view has one row per rule plus the aggregate", "[plot]") {
  RuleView view;
  view.title = {"rules"};
  view.input_titles = {"x = 3"};
  view.output_titles = {"z = 0.4 kPa"};
  view.input_ranges = {{0, 10}};
  view.output_ranges = {{0, 1}};
  for (int r = 0; r < 12; ++r) {
    view.rule_titles.push_back("r" + std::to_string(r + 1) + ": 0.5");
    RulePanel in;
    in.present = r % 2 == 0;
    in.x = {0, 5, 10};
    in.membership = {0, 1, 0};
    in.filled = {0, 0.5, 0};
    in.grade = 0.5;
    in.marker = 3;
    RulePanel out = in;
    out.marker = std::nan("");
    view.inputs.push_back({in});
    view.outputs.push_back({out});
  }
  RulePanel aggregate;
  aggregate.present = true;
  aggregate.x = {0, 0.5, 1};
  aggregate.membership = aggregate.filled = {0.2, 0.5, 0.2};
  aggregate.marker = 0.4;
  view.aggregate = {aggregate};
  const Decoded small = decode(render_rule_view(view, ImageFormat::Png));
  view.rule_titles.resize(2);
  view.inputs.resize(2);
  view.outputs.resize(2);
  const Decoded two = decode(render_rule_view(view, ImageFormat::Png));
  CHECK(small.height > two.height);  // the figure grows with the rules
  CHECK(two.width >= 560);
}

TEST_CASE("trade plot: unlabelled points get no number, a required error its line and legend entry", "[plot]") {
  // fmpc trade clears the labels of the points off the Pareto front: they are drawn, never numbered (the legend once
  // showed an empty "1:" entry for them). --max-error E is a horizontal line named in the legend.
  TradePlot plot;
  plot.points = {{"fast", 1000.0, 0.5, "springs"}, {"", 100.0, 0.6, "springs"}, {"accurate", 10.0, 0.01, "FEM"},
                 {"", 5.0, 0.02, "FEM"}};
  plot.error_bound = 0.05;
  plot.error_bound_label = "--max-error 0.05";
  LabelPlacement placement;
  render_trade_plot(plot, ImageFormat::Png, &placement);
  CHECK_FALSE(placement.placed[1]);
  CHECK_FALSE(placement.placed[3]);
  CHECK(placement.legend ==
        std::vector<std::string>{"springs", "FEM", "Pareto front", "on the front", "--max-error 0.05"});
  plot.error_bound = 0.0;
  render_trade_plot(plot, ImageFormat::Png, &placement);
  CHECK(placement.legend == std::vector<std::string>{"springs", "FEM", "Pareto front", "on the front"});
}
