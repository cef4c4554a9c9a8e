#pragma once
// Positions in an open document: fmpc's SourceRange (1-based lines, byte columns) against LSP's Position (0-based
// line, `character` in the negotiated encoding: UTF-16 code units by default, UTF-8 bytes when the client offers
// them; LSP 3.17, "Position" and "PositionEncodingKind"). Lines end at \n (a \r before it belongs to the line end).
#include <cstddef>
#include <string>
#include <vector>

#include "diagnostics/source_range.h"

namespace fmpc::lsp {

enum class PositionEncoding { Utf16, Utf8 };

struct Position {
  int line = 0;
  int character = 0;
};

class TextPositions {
 public:
  TextPositions(const std::string& text, PositionEncoding encoding);

  // The LSP position of byte `column` (1-based) of `line` (1-based); clamped to the text.
  Position at(int line, int column) const;
  // The LSP position of a byte offset.
  Position at_offset(std::size_t offset) const;
  // The byte offset of an LSP position; a character past its line's end is the line's end.
  std::size_t offset(const Position& position) const;
  // LSP's start and end of a SourceRange (an invalid range: the start of the text).
  std::pair<Position, Position> range(const SourceRange& range) const;
  Position end() const { return at_offset(text_.size()); }

 private:
  std::size_t line_start(int line) const;  // 0-based line; the text's size past the last
  std::size_t line_end(int line) const;    // before its \r\n or \n

  const std::string& text_;
  PositionEncoding encoding_;
  std::vector<std::size_t> line_starts_;
};

}  // namespace fmpc::lsp
