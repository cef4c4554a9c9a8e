#pragma once
// Source positions of the fmpc parser's tokens (fmpc_parser.cpp, fmpc_token_repair.cpp): ANTLR indexes code points,
// SourceRange columns count bytes; SourceMap maps one to the other.
#include <algorithm>
#include <string>
#include <vector>

#include "antlr4-runtime.h"
#include "diagnostics/source_range.h"

namespace fmpc::ast {

// ANTLR indexes code points; SourceRange columns count bytes. This maps one to the other.
class SourceMap {
 public:
  SourceMap(std::string path, const std::string& text) : path_(std::move(path)), size_(text.size()) {
    line_starts_.push_back(0);
    for (std::size_t i = 0; i < text.size(); ++i) {
      const auto byte = static_cast<unsigned char>(text[i]);
      if ((byte & 0xC0) != 0x80) code_point_offsets_.push_back(i);
      if (byte == '\n') line_starts_.push_back(i + 1);
    }
    code_point_offsets_.push_back(text.size());
    const std::size_t last = text.find_last_not_of(" \t\r\n\f");
    end_of_text_ = last == std::string::npos ? 0 : last + 1;
  }

  SourceRange bytes(std::size_t begin, std::size_t end) const {
    SourceRange range;
    range.file = path_;
    position(begin, range.line, range.column);
    position(end, range.end_line, range.end_column);
    return range;
  }

  SourceRange token(const antlr4::Token* token) const {
    if (token->getType() == antlr4::Token::EOF) return bytes(end_of_text_, end_of_text_);
    return bytes(byte_of(token->getStartIndex()), byte_of(token->getStopIndex() + 1));
  }

  SourceRange span(const antlr4::Token* first, const antlr4::Token* last) const {
    SourceRange range = token(first);
    const SourceRange end = token(last);
    range.end_line = end.end_line;
    range.end_column = end.end_column;
    return range;
  }

  SourceRange context(antlr4::ParserRuleContext* context) const {
    return span(context->getStart(), context->getStop());
  }

  const std::string& path() const { return path_; }

  // The byte offset of code point `code_point` (ANTLR's index); the text's size past its end.
  std::size_t byte_offset(std::size_t code_point) const { return byte_of(code_point); }

 private:
  std::size_t byte_of(std::size_t code_point) const {
    return code_point < code_point_offsets_.size() ? code_point_offsets_[code_point] : size_;
  }

  void position(std::size_t byte, int& line, int& column) const {
    const auto next = std::upper_bound(line_starts_.begin(), line_starts_.end(), byte);
    const auto index = static_cast<std::size_t>(next - line_starts_.begin()) - 1;
    line = static_cast<int>(index + 1);
    column = static_cast<int>(byte - line_starts_[index] + 1);
  }

  std::string path_;
  std::size_t size_;
  std::size_t end_of_text_ = 0;
  std::vector<std::size_t> code_point_offsets_;
  std::vector<std::size_t> line_starts_;
};

}  // namespace fmpc::ast
