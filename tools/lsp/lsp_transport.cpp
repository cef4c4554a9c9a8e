#include "tools/lsp/lsp_transport.h"

#include <unistd.h>

#include <cerrno>
#include <cctype>
#include <cstring>

namespace fmpc::lsp {

namespace {

std::string lowercase(std::string text) {
  for (char& c : text) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

std::string trimmed(const std::string& text) {
  const std::size_t first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return "";
  return text.substr(first, text.find_last_not_of(" \t") - first + 1);
}

Frame failure(Frame::Status status, std::string error) {
  Frame frame;
  frame.status = status;
  frame.error = std::move(error);
  return frame;
}

}  // namespace

bool FrameReader::fill() {
  for (;;) {
    const ssize_t got = ::read(fd_, buffer_, sizeof buffer_);
    if (got > 0) {
      position_ = 0;
      size_ = static_cast<std::size_t>(got);
      return true;
    }
    if (got < 0 && errno == EINTR) continue;
    return false;
  }
}

int FrameReader::get() {
  if (position_ == size_ && !fill()) return -1;
  return static_cast<unsigned char>(buffer_[position_++]);
}

Frame FrameReader::next() {
  // The header part: lines up to an empty one. A lone \n is taken for \r\n (some clients and test scripts write it).
  // Past kMaxLspHeaderBytes nothing more is kept, but the part is read to its end so that the next one is found.
  std::size_t header_bytes = 0;
  std::size_t line_length = 0;  // bytes of the current line, \r included
  std::size_t lines = 0;
  bool line_is_cr = false;      // the current line so far is one \r
  bool too_long = false;
  bool has_length = false;
  std::string line;
  std::string length_text;
  for (;;) {
    const int c = get();
    if (c < 0) {
      if (header_bytes == 0) return failure(Frame::Status::End, "");
      return failure(Frame::Status::End, "the input ended inside a message's header");
    }
    ++header_bytes;
    if (c != '\n') {
      line_is_cr = line_length == 0 && c == '\r';
      ++line_length;
      if (header_bytes <= kMaxLspHeaderBytes) line += static_cast<char>(c);
      else too_long = true;
      continue;
    }
    const bool blank = line_length == 0 || (line_length == 1 && line_is_cr);
    if (blank) {
      if (lines == 0) {  // blank lines between messages
        header_bytes = 0;
        continue;
      }
      break;
    }
    ++lines;
    if (!too_long) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      const std::size_t colon = line.find(':');
      if (colon != std::string::npos && lowercase(trimmed(line.substr(0, colon))) == "content-length") {
        has_length = true;
        length_text = trimmed(line.substr(colon + 1));
      }
    }
    line.clear();
    line_length = 0;
  }
  if (too_long)
    return failure(Frame::Status::Malformed, "the header part is longer than " + std::to_string(kMaxLspHeaderBytes) +
                                                 " bytes (the limit)");
  if (!has_length)
    return failure(Frame::Status::Malformed, "the header part has no Content-Length");
  // A decimal number of bytes; checked digit by digit so that no text overflows into a wrong small number.
  if (length_text.empty() || length_text.size() > 19 ||
      length_text.find_first_not_of("0123456789") != std::string::npos)
    return failure(Frame::Status::Malformed, "Content-Length '" + length_text.substr(0, 40) +
                                                 "' is not a whole number of bytes");
  const unsigned long long length = std::stoull(length_text);
  if (length > max_message_bytes_) {
    // Dropped in pieces: the stream stays in step without holding the content.
    unsigned long long left = length;
    while (left > 0) {
      if (position_ == size_ && !fill())
        return failure(Frame::Status::End, "the input ended inside an oversized message");
      const std::size_t take = static_cast<std::size_t>(std::min<unsigned long long>(left, size_ - position_));
      position_ += take;
      left -= take;
    }
    return failure(Frame::Status::Oversized, "Content-Length " + length_text + " is over the limit of " +
                                                 std::to_string(max_message_bytes_) + " bytes a message");
  }
  Frame frame;
  frame.content.reserve(static_cast<std::size_t>(length));
  while (frame.content.size() < length) {
    if (position_ == size_ && !fill()) return failure(Frame::Status::End, "the input ended inside a message");
    const std::size_t take =
        static_cast<std::size_t>(std::min<unsigned long long>(length - frame.content.size(), size_ - position_));
    frame.content.append(buffer_ + position_, take);
    position_ += take;
  }
  frame.status = Frame::Status::Message;
  return frame;
}

std::string frame_message(const std::string& content) {
  return "Content-Length: " + std::to_string(content.size()) + "\r\n\r\n" + content;
}

}  // namespace fmpc::lsp
