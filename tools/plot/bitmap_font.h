#pragma once
// Text for figures: the classic 5x7 dot-matrix font (printable ASCII), drawn at an integer scale.
#include <string>

#include "tools/plot/png_image.h"

namespace fmpc::plot {

// Width in pixels of `text` at `scale`: 6 columns per character (5 dots and a gap), minus the last gap.
int text_width(const std::string& text, int scale);
inline int text_height(int scale) { return 7 * scale; }

// Draws `text` with its top-left corner at (x, y). `upward` turns it 90 degrees counter-clockwise (for vertical
// axis labels): it then starts at (x, y) as its bottom-left corner and runs up. Characters outside printable
// ASCII draw as '?'.
void draw_text(RgbImage& image, int x, int y, const std::string& text, Rgb colour, int scale, bool upward = false);

}  // namespace fmpc::plot
