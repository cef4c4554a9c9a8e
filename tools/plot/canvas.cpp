#include "tools/plot/canvas.h"

#include <cairo-svg.h>
#include <cairo.h>
#include <pango/pangocairo.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <stdexcept>

namespace fmpc::plot {

namespace {

cairo_status_t append_bytes(void* closure, const unsigned char* data, unsigned int length) {
  static_cast<std::string*>(closure)->append(reinterpret_cast<const char*>(data), length);
  return CAIRO_STATUS_SUCCESS;
}

// DejaVu Sans (fonts-dejavu-core) covers Latin, Greek and the symbols units use; fontconfig falls back for the rest.
constexpr const char* kFontFamily = "DejaVu Sans";

}  // namespace

ImageFormat image_format_for(const std::string& path) {
  if (path.size() < 4) return ImageFormat::Png;
  std::string end = path.substr(path.size() - 4);
  for (char& c : end) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return end == ".svg" ? ImageFormat::Svg : ImageFormat::Png;
}

Colour categorical_colour(std::size_t index) {
  static constexpr Colour kColours[] = {
      {0.122, 0.467, 0.706, 1}, {1.000, 0.498, 0.055, 1}, {0.173, 0.627, 0.173, 1}, {0.839, 0.153, 0.157, 1},
      {0.580, 0.404, 0.741, 1}, {0.549, 0.337, 0.294, 1}, {0.890, 0.467, 0.761, 1}, {0.498, 0.498, 0.498, 1},
      {0.737, 0.741, 0.133, 1}, {0.090, 0.745, 0.812, 1}};
  return kColours[index % 10];
}

bool Box::overlaps(const Box& other, double margin) const {
  return x < other.x + other.width + margin && other.x < x + width + margin && y < other.y + other.height + margin &&
         other.y < y + height + margin;
}

bool Box::inside(const Box& other) const {
  return x >= other.x && y >= other.y && x + width <= other.x + other.width && y + height <= other.y + other.height;
}

struct Canvas::State {
  ImageFormat format;
  std::string svg_bytes;
  cairo_surface_t* surface = nullptr;
  cairo_t* cr = nullptr;
  PangoLayout* layout = nullptr;
  bool finished = false;
};

Canvas::Canvas(int width, int height, ImageFormat format)
    : state_(std::make_unique<State>()), width_(width), height_(height) {
  state_->format = format;
  if (format == ImageFormat::Svg)
    state_->surface = cairo_svg_surface_create_for_stream(append_bytes, &state_->svg_bytes, width, height);
  else
    state_->surface = cairo_image_surface_create(CAIRO_FORMAT_RGB24, width, height);
  if (cairo_surface_status(state_->surface) != CAIRO_STATUS_SUCCESS)
    throw std::runtime_error("cairo cannot create a " + std::to_string(width) + " x " + std::to_string(height) +
                             " surface");
  state_->cr = cairo_create(state_->surface);
  state_->layout = pango_cairo_create_layout(state_->cr);
  cairo_set_source_rgb(state_->cr, 1, 1, 1);
  cairo_paint(state_->cr);
}

Canvas::~Canvas() {
  if (state_->layout) g_object_unref(state_->layout);
  if (state_->cr) cairo_destroy(state_->cr);
  if (state_->surface) cairo_surface_destroy(state_->surface);
}

namespace {

void set_font(PangoLayout* layout, const Font& font) {
  PangoFontDescription* description = pango_font_description_new();
  pango_font_description_set_family(description, kFontFamily);
  pango_font_description_set_absolute_size(description, font.size * PANGO_SCALE);
  pango_font_description_set_weight(description, font.bold ? PANGO_WEIGHT_BOLD : PANGO_WEIGHT_NORMAL);
  pango_layout_set_font_description(layout, description);
  pango_font_description_free(description);
}

void set_colour(cairo_t* cr, Colour c) { cairo_set_source_rgba(cr, c.r, c.g, c.b, c.a); }

}  // namespace

std::pair<double, double> Canvas::measure(const std::string& text, const Font& font) const {
  set_font(state_->layout, font);
  pango_layout_set_text(state_->layout, text.c_str(), -1);
  int w = 0, h = 0;
  pango_layout_get_pixel_size(state_->layout, &w, &h);
  return {static_cast<double>(w), static_cast<double>(h)};
}

Box Canvas::text(double x, double y, const std::string& text, const Font& font, Align horizontal, Align vertical,
                 Colour colour, bool upright) {
  const auto [w, h] = measure(text, font);  // also sets the layout's text and font
  const auto offset = [](Align align, double size) {
    return align == Align::Start ? 0.0 : align == Align::Centre ? -size / 2 : -size;
  };
  cairo_t* cr = state_->cr;
  cairo_save(cr);
  set_colour(cr, colour);
  Box box;
  if (upright) {
    // Rotated: the text's width runs up the page; `horizontal` aligns along it (Start = bottom).
    const double along = offset(horizontal, w), across = offset(vertical, h);
    cairo_translate(cr, x, y);
    cairo_rotate(cr, -M_PI / 2);
    cairo_move_to(cr, along, across);
    box = Box{x + across, y - along - w, h, w};
  } else {
    const double dx = offset(horizontal, w), dy = offset(vertical, h);
    cairo_move_to(cr, x + dx, y + dy);
    box = Box{x + dx, y + dy, w, h};
  }
  pango_cairo_update_layout(cr, state_->layout);
  pango_cairo_show_layout(cr, state_->layout);
  cairo_new_path(cr);
  cairo_restore(cr);
  return box;
}

void Canvas::line(double x0, double y0, double x1, double y1, Colour colour, double width,
                  const std::vector<double>& dashes) {
  polyline({{x0, y0}, {x1, y1}}, colour, width, dashes);
}

void Canvas::polyline(const std::vector<std::pair<double, double>>& points, Colour colour, double width,
                      const std::vector<double>& dashes) {
  if (points.size() < 2) return;
  cairo_t* cr = state_->cr;
  cairo_save(cr);
  set_colour(cr, colour);
  cairo_set_line_width(cr, width);
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
  if (!dashes.empty()) cairo_set_dash(cr, dashes.data(), static_cast<int>(dashes.size()), 0);
  cairo_move_to(cr, points.front().first, points.front().second);
  for (std::size_t k = 1; k < points.size(); ++k) cairo_line_to(cr, points[k].first, points[k].second);
  cairo_stroke(cr);
  cairo_restore(cr);
}

void Canvas::polygon(const std::vector<std::pair<double, double>>& points, Colour fill) {
  if (points.size() < 3) return;
  cairo_t* cr = state_->cr;
  cairo_save(cr);
  set_colour(cr, fill);
  cairo_move_to(cr, points.front().first, points.front().second);
  for (std::size_t k = 1; k < points.size(); ++k) cairo_line_to(cr, points[k].first, points[k].second);
  cairo_close_path(cr);
  cairo_fill(cr);
  cairo_restore(cr);
}

void Canvas::rectangle(double x, double y, double width, double height, Colour fill) {
  draw_rectangle(x, y, width, height, fill, 0);
}

void Canvas::frame(double x, double y, double width, double height, Colour colour, double line_width) {
  draw_rectangle(x, y, width, height, colour, line_width);
}

void Canvas::draw_rectangle(double x, double y, double width, double height, Colour colour, double line_width) {
  cairo_t* cr = state_->cr;
  cairo_save(cr);
  set_colour(cr, colour);
  cairo_new_path(cr);
  cairo_rectangle(cr, x, y, width, height);
  if (line_width > 0) {
    cairo_set_line_width(cr, line_width);
    cairo_stroke(cr);
  } else {
    cairo_fill(cr);
  }
  cairo_restore(cr);
}

void Canvas::circle(double x, double y, double radius, Colour fill, Colour outline, double line_width) {
  cairo_t* cr = state_->cr;
  cairo_save(cr);
  cairo_new_path(cr);  // pango leaves a current point: without this the arc would start with a line from it
  cairo_arc(cr, x, y, radius, 0, 2 * M_PI);
  set_colour(cr, fill);
  cairo_fill_preserve(cr);
  set_colour(cr, outline);
  cairo_set_line_width(cr, line_width);
  cairo_stroke(cr);
  cairo_restore(cr);
}

void Canvas::raster(double x, double y, double width, double height, int columns, int rows,
                    const std::vector<Colour>& cells) {
  if (columns <= 0 || rows <= 0 || cells.size() < static_cast<std::size_t>(columns) * static_cast<std::size_t>(rows))
    return;
  cairo_surface_t* image = cairo_image_surface_create(CAIRO_FORMAT_RGB24, columns, rows);
  cairo_surface_flush(image);
  unsigned char* data = cairo_image_surface_get_data(image);
  const int stride = cairo_image_surface_get_stride(image);
  const auto byte = [](double v) { return static_cast<std::uint32_t>(std::lround(std::clamp(v, 0.0, 1.0) * 255)); };
  for (int r = 0; r < rows; ++r) {
    auto* row = reinterpret_cast<std::uint32_t*>(data + static_cast<std::ptrdiff_t>(r) * stride);
    for (int c = 0; c < columns; ++c) {
      const Colour& colour = cells[static_cast<std::size_t>(r) * static_cast<std::size_t>(columns) +
                                   static_cast<std::size_t>(c)];
      row[c] = (byte(colour.r) << 16) | (byte(colour.g) << 8) | byte(colour.b);
    }
  }
  cairo_surface_mark_dirty(image);
  cairo_t* cr = state_->cr;
  cairo_save(cr);
  cairo_rectangle(cr, x, y, width, height);
  cairo_clip(cr);
  cairo_translate(cr, x, y);
  cairo_scale(cr, width / columns, height / rows);
  cairo_set_source_surface(cr, image, 0, 0);
  cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_NEAREST);
  cairo_paint(cr);
  cairo_restore(cr);
  cairo_surface_destroy(image);
}

std::string Canvas::finish() {
  if (state_->finished) throw std::logic_error("Canvas::finish called twice");
  state_->finished = true;
  g_object_unref(state_->layout);
  state_->layout = nullptr;
  cairo_destroy(state_->cr);
  state_->cr = nullptr;
  std::string bytes;
  if (state_->format == ImageFormat::Svg) {
    cairo_surface_finish(state_->surface);
    bytes = std::move(state_->svg_bytes);
  } else {
    cairo_surface_write_to_png_stream(state_->surface, append_bytes, &bytes);
  }
  cairo_surface_destroy(state_->surface);
  state_->surface = nullptr;
  return bytes;
}

}  // namespace fmpc::plot
