#include "tools/lsp/text_positions.h"

#include <algorithm>

namespace fmpc::lsp {

TextPositions::TextPositions(const std::string& text, PositionEncoding encoding) : text_(text), encoding_(encoding) {
  line_starts_.push_back(0);
  for (std::size_t i = 0; i < text.size(); ++i)
    if (text[i] == '\n') line_starts_.push_back(i + 1);
}

std::size_t TextPositions::line_start(int line) const {
  if (line < 0) return 0;
  const auto index = static_cast<std::size_t>(line);
  return index < line_starts_.size() ? line_starts_[index] : text_.size();
}

std::size_t TextPositions::line_end(int line) const {
  std::size_t end = line_start(line + 1);
  if (static_cast<std::size_t>(line) + 1 < line_starts_.size()) --end;  // the \n
  if (end > line_start(line) && text_[end - 1] == '\r') --end;
  return end;
}

Position TextPositions::at_offset(std::size_t offset) const {
  offset = std::min(offset, text_.size());
  const auto next = std::upper_bound(line_starts_.begin(), line_starts_.end(), offset);
  const auto line = static_cast<std::size_t>(next - line_starts_.begin()) - 1;
  Position position;
  position.line = static_cast<int>(line);
  if (encoding_ == PositionEncoding::Utf8) {
    position.character = static_cast<int>(offset - line_starts_[line]);
    return position;
  }
  // UTF-16 code units: one per code point, two for those above U+FFFF (4-byte UTF-8 sequences).
  int units = 0;
  for (std::size_t i = line_starts_[line]; i < offset; ++i) {
    const auto byte = static_cast<unsigned char>(text_[i]);
    if ((byte & 0xC0) == 0x80) continue;
    units += byte >= 0xF0 ? 2 : 1;
  }
  position.character = units;
  return position;
}

Position TextPositions::at(int line, int column) const {
  if (line < 1) return Position{};
  const std::size_t start = line_start(line - 1);
  const std::size_t offset = start + static_cast<std::size_t>(std::max(column, 1) - 1);
  return at_offset(std::min(offset, std::max(start, line_start(line))));
}

std::size_t TextPositions::offset(const Position& position) const {
  if (position.line < 0) return 0;
  if (static_cast<std::size_t>(position.line) >= line_starts_.size()) return text_.size();
  const std::size_t start = line_start(position.line);
  const std::size_t end = line_end(position.line);
  if (position.character <= 0) return start;
  if (encoding_ == PositionEncoding::Utf8)
    return std::min(end, start + static_cast<std::size_t>(position.character));
  int units = 0;
  std::size_t i = start;
  while (i < end && units < position.character) {
    const auto byte = static_cast<unsigned char>(text_[i]);
    units += byte >= 0xF0 ? 2 : 1;
    ++i;
    while (i < end && (static_cast<unsigned char>(text_[i]) & 0xC0) == 0x80) ++i;
  }
  return i;
}

std::pair<Position, Position> TextPositions::range(const SourceRange& range) const {
  if (!range.valid()) return {Position{}, Position{}};
  const Position start = at(range.line, range.column);
  const int end_line = range.end_line > 0 ? range.end_line : range.line;
  const int end_column = range.end_line > 0 ? range.end_column : range.column;
  Position end = at(end_line, end_column);
  if (end.line < start.line || (end.line == start.line && end.character < start.character)) end = start;
  return {start, end};
}

}  // namespace fmpc::lsp
