#pragma once
// A drawing surface for fmpc's figures: cairo (vector graphics, anti-aliased, PNG and SVG output) with pango
// (UTF-8 text shaped with the system's fonts: "µm", "E = 9.8 kPa", "σ" all render). Debian: libcairo2-dev,
// libpango1.0-dev, fonts-dejavu-core (README says why). Only tools/ draw pictures.
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace fmpc::plot {

enum class ImageFormat { Png, Svg };

// SVG for a path ending in ".svg" (any case), PNG otherwise.
ImageFormat image_format_for(const std::string& path);

struct Colour {
  double r = 0, g = 0, b = 0, a = 1;
};

inline constexpr Colour kBlack{0, 0, 0, 1};
inline constexpr Colour kWhite{1, 1, 1, 1};
inline constexpr Colour kGridGrey{0.88, 0.88, 0.88, 1};
inline constexpr Colour kTextGrey{0.35, 0.35, 0.35, 1};

// Tableau 10 (matplotlib's default cycle): distinguishable, also in print; index wraps.
Colour categorical_colour(std::size_t index);

struct Font {
  double size = 12;  // pixels
  bool bold = false;
};

struct Box {
  double x = 0, y = 0, width = 0, height = 0;
  bool overlaps(const Box& other, double margin = 0) const;
  bool inside(const Box& other) const;
};

enum class Align { Start, Centre, End };

class Canvas {
 public:
  Canvas(int width, int height, ImageFormat format);
  ~Canvas();
  Canvas(const Canvas&) = delete;
  Canvas& operator=(const Canvas&) = delete;

  int width() const { return width_; }
  int height() const { return height_; }

  // Size of `text` as drawn (logical extents), unrotated.
  std::pair<double, double> measure(const std::string& text, const Font& font) const;
  // Draws `text` anchored at (x, y): `horizontal` and `vertical` say which part of the text's box sits there.
  // `upright` turns it 90 degrees counter-clockwise (vertical axis titles). Returns the box it covers.
  Box text(double x, double y, const std::string& text, const Font& font, Align horizontal, Align vertical,
           Colour colour = kBlack, bool upright = false);

  void line(double x0, double y0, double x1, double y1, Colour colour, double width = 1,
            const std::vector<double>& dashes = {});
  void polyline(const std::vector<std::pair<double, double>>& points, Colour colour, double width = 1.5,
                const std::vector<double>& dashes = {});
  // A closed polygon filled with `fill` (no outline).
  void polygon(const std::vector<std::pair<double, double>>& points, Colour fill);
  void rectangle(double x, double y, double width, double height, Colour fill);
  void frame(double x, double y, double width, double height, Colour colour, double line_width = 1);
  void circle(double x, double y, double radius, Colour fill, Colour outline, double line_width = 1);
  // An image of `columns` x `rows` colours (row 0 at the top) stretched over the box, without smoothing.
  void raster(double x, double y, double width, double height, int columns, int rows,
              const std::vector<Colour>& cells);

  // The finished file: PNG or SVG bytes. The canvas cannot be drawn on afterwards.
  std::string finish();

 private:
  // Filled when line_width is 0, else outlined.
  void draw_rectangle(double x, double y, double width, double height, Colour colour, double line_width);
  struct State;
  std::unique_ptr<State> state_;
  int width_;
  int height_;
};

}  // namespace fmpc::plot
