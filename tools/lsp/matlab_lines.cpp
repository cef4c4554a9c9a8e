#include "tools/lsp/matlab_lines.h"

#include <cctype>
#include <cstdlib>

namespace fmpc::lsp {

namespace {

bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool starts_name(char c) { return std::isalpha(static_cast<unsigned char>(c)) || c == '_'; }
bool continues_name(char c) { return starts_name(c) || is_digit(c); }

// The tokens of text[begin, end) and whether a comment ends the line.
std::vector<MatlabToken> tokenize_line(const std::string& text, std::size_t begin, std::size_t end, bool& comment) {
  std::vector<MatlabToken> tokens;
  comment = false;
  std::size_t i = begin;
  while (i < end) {
    const char c = text[i];
    if (c == ' ' || c == '\t' || c == '\f' || c == '\r') {
      ++i;
      continue;
    }
    if (c == '%' || c == '#') {
      comment = true;
      break;
    }
    MatlabToken token;
    token.begin = i;
    if (c == '\'') {
      token.kind = MatlabToken::Kind::String;
      ++i;
      while (i < end) {
        if (text[i] == '\'' && i + 1 < end && text[i + 1] == '\'') i += 2;
        else if (text[i] == '\'') {
          ++i;
          break;
        } else ++i;
      }
    } else if (is_digit(c) || (c == '.' && i + 1 < end && is_digit(text[i + 1]))) {
      token.kind = MatlabToken::Kind::Number;
      while (i < end && (is_digit(text[i]) || text[i] == '.')) ++i;
      if (i < end && (text[i] == 'e' || text[i] == 'E')) {
        std::size_t j = i + 1;
        if (j < end && (text[j] == '+' || text[j] == '-')) ++j;
        if (j < end && is_digit(text[j])) {
          i = j;
          while (i < end && is_digit(text[i])) ++i;
        }
      }
    } else if (starts_name(c)) {
      token.kind = MatlabToken::Kind::Name;
      while (i < end && continues_name(text[i])) ++i;
    } else {
      token.kind = MatlabToken::Kind::Symbol;
      ++i;
    }
    token.end = i;
    token.text = text.substr(token.begin, token.end - token.begin);
    tokens.push_back(std::move(token));
  }
  return tokens;
}

}  // namespace

std::string MatlabToken::unquoted() const {
  if (kind != Kind::String || text.empty()) return text;
  std::string inner = text.substr(1);
  if (inner.size() >= 1 && inner.back() == '\'' && text.size() >= 2) inner.pop_back();
  std::string result;
  for (std::size_t i = 0; i < inner.size(); ++i) {
    result += inner[i];
    if (inner[i] == '\'' && i + 1 < inner.size() && inner[i + 1] == '\'') ++i;
  }
  return result;
}

std::string MatlabLine::key() const {
  if (tokens.size() >= 2 && tokens[0].kind == MatlabToken::Kind::Name && tokens[1].text == "=") return tokens[0].text;
  return "";
}

std::vector<MatlabLine> read_matlab_lines(const std::string& text) {
  std::vector<MatlabLine> lines;
  MatlabLine::Section section = MatlabLine::Section::None;
  int number = 0, header = -1;
  std::size_t begin = 0;
  for (int line = 0; begin <= text.size(); ++line) {
    std::size_t next = text.find('\n', begin);
    const bool last = next == std::string::npos;
    if (last) next = text.size();
    MatlabLine item;
    item.line = line;
    item.begin = begin;
    item.end = next > begin && text[next - 1] == '\r' ? next - 1 : next;
    item.tokens = tokenize_line(text, item.begin, item.end, item.has_comment);
    // A header: "[System]", "[InputN]", "[OutputN]" or "[Rules]" alone on its line (grammar/MatlabFis.g4, SECTION).
    const std::vector<MatlabToken>& t = item.tokens;
    if (t.size() == 3 && t[0].text == "[" && t[2].text == "]" && t[1].kind == MatlabToken::Kind::Name) {
      const std::string& word = t[1].text;
      const auto numbered = [&](const std::string& prefix) {
        if (word.size() <= prefix.size() || word.compare(0, prefix.size(), prefix) != 0) return 0;
        for (std::size_t i = prefix.size(); i < word.size(); ++i)
          if (!is_digit(word[i])) return 0;
        return std::atoi(word.c_str() + prefix.size());
      };
      MatlabLine::Section found = MatlabLine::Section::None;
      int n = 0;
      if (word == "System") found = MatlabLine::Section::System;
      else if (word == "Rules") found = MatlabLine::Section::Rules;
      else if ((n = numbered("Input")) > 0) found = MatlabLine::Section::Input;
      else if ((n = numbered("Output")) > 0) found = MatlabLine::Section::Output;
      if (found != MatlabLine::Section::None) {
        section = found;
        number = n;
        header = line;
        item.is_header = true;
      }
    }
    item.section = section;
    item.section_number = number;
    item.header_line = header;
    lines.push_back(std::move(item));
    if (last) break;
    begin = next + 1;
  }
  return lines;
}

}  // namespace fmpc::lsp
