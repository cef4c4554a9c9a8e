#include "tools/plot/rule_view.h"

#include <algorithm>

#include "tools/plot/axes.h"

namespace fmpc::plot {

namespace {

constexpr double kCellWidth = 150;
constexpr double kCellHeight = 34;
constexpr double kGap = 6;
const Colour kInputFill{0.99, 0.82, 0.30, 0.85};
const Colour kOutputFill{0.25, 0.50, 0.85, 0.80};
const Colour kValueRed{0.84, 0.15, 0.16, 1};

void draw_panel(Canvas& canvas, const Box& box, const RulePanel& panel, std::pair<double, double> range,
                bool is_input, const Font& small) {
  canvas.rectangle(box.x, box.y, box.width, box.height, Colour{0.98, 0.98, 0.98, 1});
  canvas.frame(box.x, box.y, box.width, box.height, Colour{0.6, 0.6, 0.6, 1}, 0.8);
  if (!panel.present) return;
  const double span = range.second > range.first ? range.second - range.first : 1;
  const auto px = [&](double x) { return box.x + (x - range.first) / span * box.width; };
  const auto py = [&](double mu) { return box.y + box.height - 2 - std::clamp(mu, 0.0, 1.0) * (box.height - 4); };
  const auto curve = [&](const std::vector<double>& mu) {
    std::vector<std::pair<double, double>> points;
    for (std::size_t k = 0; k < panel.x.size() && k < mu.size(); ++k) points.push_back({px(panel.x[k]), py(mu[k])});
    return points;
  };
  if (panel.filled.size() == panel.x.size() && !panel.x.empty()) {
    std::vector<std::pair<double, double>> area = curve(panel.filled);
    area.push_back({px(panel.x.back()), py(0)});
    area.push_back({px(panel.x.front()), py(0)});
    canvas.polygon(area, is_input ? kInputFill : kOutputFill);
  }
  canvas.polyline(curve(panel.membership), kBlack, 1);
  for (const auto& [x, height] : panel.stems)
    if (std::isfinite(x) && std::isfinite(height)) canvas.line(px(x), py(0), px(x), py(height), kOutputFill, 2);
  if (!is_input && panel.filled.empty() && std::isfinite(panel.marker) && std::isfinite(panel.grade)) {
    // Sugeno: a stem at the rule's output, as tall as its weight.
    canvas.line(px(panel.marker), py(0), px(panel.marker), py(panel.grade), kOutputFill, 3);
  } else if (std::isfinite(panel.marker)) {
    canvas.line(px(panel.marker), box.y, px(panel.marker), box.y + box.height, kValueRed, 1.2);
  }
  if (is_input && std::isfinite(panel.grade)) {
    char text[32];
    std::snprintf(text, sizeof text, "%.3g", panel.grade);
    canvas.text(box.x + box.width - 3, box.y + 1, text, small, Align::End, Align::Start, kTextGrey);
  }
}

}  // namespace

std::string render_rule_view(const RuleView& view, ImageFormat format) {
  const std::size_t rules = view.rule_titles.size();
  const std::size_t n_in = view.input_titles.size(), n_out = view.output_titles.size();
  const Font title_font{15, true}, info_font{12, false}, header_font{12, true}, small{10, false};
  // Measure first: the rule-name column and the header's height.
  Canvas probe(10, 10, ImageFormat::Png);
  double name_width = probe.measure(view.aggregate_title, info_font).first;
  for (const std::string& t : view.rule_titles) name_width = std::max(name_width, probe.measure(t, info_font).first);
  name_width += 12;
  const double columns_width = static_cast<double>(n_in + n_out) * (kCellWidth + kGap) + 14;
  const int width = static_cast<int>(std::max(560.0, 16 + name_width + columns_width + 16));
  const double header = 2 * probe.measure("Ag", header_font).second + 8;
  double title_height = 12;
  for (std::size_t k = 0; k < view.title.size(); ++k) title_height += probe.measure(view.title[k], k ? info_font : title_font).second + 2;
  const int height = static_cast<int>(title_height + 8 + header + static_cast<double>(rules + 1) * (kCellHeight + kGap) +
                                      14 + 40);

  Canvas canvas(width, height, format);
  const double top = draw_title_block(canvas, 16, 12, width - 32, view.title, title_font, info_font) + 8;
  const double grid_x = 16 + name_width;
  const auto column_x = [&](std::size_t c) {
    // A wider gap between the inputs and the outputs.
    return grid_x + static_cast<double>(c) * (kCellWidth + kGap) + (c >= n_in ? 14 : 0);
  };
  for (std::size_t c = 0; c < n_in + n_out; ++c) {
    const std::string& t = c < n_in ? view.input_titles[c] : view.output_titles[c - n_in];
    Font font = header_font;
    const double w = canvas.measure(t, font).first;
    if (w > kCellWidth) font.size = std::max(8.0, font.size * kCellWidth / w);
    canvas.text(column_x(c) + kCellWidth / 2, top + header - 4, t, font, Align::Centre, Align::End);
  }
  const double rows_top = top + header;
  for (std::size_t r = 0; r <= rules; ++r) {
    const double y = rows_top + static_cast<double>(r) * (kCellHeight + kGap) + (r == rules ? 8 : 0);
    const std::string& name = r < rules ? view.rule_titles[r] : view.aggregate_title;
    canvas.text(grid_x - 8, y + kCellHeight / 2, name, r < rules ? info_font : header_font, Align::End, Align::Centre);
    for (std::size_t c = 0; c < n_in + n_out; ++c) {
      const Box box{column_x(c), y, kCellWidth, kCellHeight};
      if (r < rules) {
        if (c < n_in) draw_panel(canvas, box, view.inputs[r][c], view.input_ranges[c], true, small);
        else draw_panel(canvas, box, view.outputs[r][c - n_in], view.output_ranges[c - n_in], false, small);
      } else if (c >= n_in && c - n_in < view.aggregate.size()) {
        draw_panel(canvas, box, view.aggregate[c - n_in], view.output_ranges[c - n_in], false, small);
      }
    }
  }
  // The range of each column under the last row.
  const double bottom = rows_top + static_cast<double>(rules + 1) * (kCellHeight + kGap) + 8;
  for (std::size_t c = 0; c < n_in + n_out; ++c) {
    const auto& range = c < n_in ? view.input_ranges[c] : view.output_ranges[c - n_in];
    canvas.text(column_x(c), bottom, tick_label(range.first, false), small, Align::Start, Align::Start, kTextGrey);
    canvas.text(column_x(c) + kCellWidth, bottom, tick_label(range.second, false), small, Align::End, Align::Start,
                kTextGrey);
  }
  return canvas.finish();
}

}  // namespace fmpc::plot
