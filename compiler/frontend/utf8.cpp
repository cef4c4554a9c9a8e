#include "compiler/frontend/utf8.h"

#include <algorithm>

namespace fmpc {

std::size_t first_invalid_utf8(std::string_view text) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  std::size_t i = 0;
  while (i < text.size()) {
    const unsigned char lead = byte(i);
    std::size_t length = 0;
    // The range of the second byte depends on the lead; the later ones are always 80-BF.
    unsigned char low = 0x80, high = 0xBF;
    if (lead < 0x80) {
      length = 1;
    } else if (lead >= 0xC2 && lead <= 0xDF) {
      length = 2;
    } else if (lead >= 0xE0 && lead <= 0xEF) {
      length = 3;
      if (lead == 0xE0) low = 0xA0;   // overlong
      if (lead == 0xED) high = 0x9F;  // surrogates
    } else if (lead >= 0xF0 && lead <= 0xF4) {
      length = 4;
      if (lead == 0xF0) low = 0x90;   // overlong
      if (lead == 0xF4) high = 0x8F;  // above U+10FFFF
    } else {
      return i;
    }
    if (text.size() - i < length) return i;
    if (length > 1 && (byte(i + 1) < low || byte(i + 1) > high)) return i;
    for (std::size_t k = 2; k < length; ++k)
      if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return i;
    i += length;
  }
  return std::string_view::npos;
}

bool report_invalid_utf8(const std::string& path, std::string_view text, DiagnosticList& diagnostics) {
  const std::size_t bad_byte = first_invalid_utf8(text);
  if (bad_byte == std::string_view::npos) return false;
  SourceRange range;
  range.file = path;
  range.line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<long>(bad_byte), '\n'));
  const std::size_t line_start = text.rfind('\n', bad_byte == 0 ? 0 : bad_byte - 1);
  range.column =
      static_cast<int>(bad_byte - (line_start == std::string_view::npos || bad_byte == 0 ? 0 : line_start + 1)) + 1;
  range.end_line = range.line;
  range.end_column = range.column + 1;
  diagnostics.error(range, "the file is not valid UTF-8 here", {"save the file as UTF-8"});
  return true;
}

std::string valid_utf8(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (std::size_t bad = first_invalid_utf8(text); bad != std::string_view::npos; bad = first_invalid_utf8(text)) {
    out.append(text.substr(0, bad));
    out.append("\xEF\xBF\xBD");
    text.remove_prefix(bad + 1);
  }
  out.append(text);
  return out;
}

bool starts_with_byte_order_mark(std::string_view text) { return text.substr(0, 3) == "\xEF\xBB\xBF"; }

std::string blank_byte_order_mark(std::string text) {
  if (starts_with_byte_order_mark(text)) text.replace(0, 3, "   ");
  return text;
}

}  // namespace fmpc
