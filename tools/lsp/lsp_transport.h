#pragma once
// The base protocol of the Language Server Protocol (LSP 3.17, "Base Protocol"): each message is a header part
// (`Content-Length: N`, optionally `Content-Type`, each line ended by \r\n, then an empty line) and a content part
// of exactly N bytes of UTF-8 JSON. Reading is bounded (docs/limits.md): a header part longer than
// kMaxLspHeaderBytes is malformed, and a Content-Length over kMaxLspMessageBytes is refused without allocating it;
// its content is read and dropped in small pieces, so the stream stays in step and the next message is read.
#include <cstddef>
#include <string>

namespace fmpc::lsp {

inline constexpr std::size_t kMaxLspHeaderBytes = 8 * 1024;
// A rule file is read up to 8 MiB (docs/limits.md); its JSON-escaped text in a didOpen can be a few times that.
inline constexpr std::size_t kMaxLspMessageBytes = 32 * 1024 * 1024;

struct Frame {
  enum class Status {
    Message,    // `content` holds the message
    Malformed,  // the header part was not LSP's; `error` says how (the next header part is read next)
    Oversized,  // Content-Length above the limit; the content was skipped; `error` names the limit
    End,        // the input ended (between messages, or inside one: `error` says so then)
  };
  Status status = Status::End;
  std::string content;
  std::string error;
};

// Reads frames from a file descriptor (the server's standard input).
class FrameReader {
 public:
  explicit FrameReader(int fd, std::size_t max_message_bytes = kMaxLspMessageBytes)
      : fd_(fd), max_message_bytes_(max_message_bytes) {}
  Frame next();

 private:
  // The next byte, or -1 at the end of the input.
  int get();
  bool fill();

  int fd_;
  std::size_t max_message_bytes_;
  char buffer_[65536];
  std::size_t position_ = 0;
  std::size_t size_ = 0;
};

// `content` with its header part.
std::string frame_message(const std::string& content);

}  // namespace fmpc::lsp
