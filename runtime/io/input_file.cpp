#include "runtime/io/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

namespace fmpc::sim {

namespace {

std::string file_kind(mode_t mode) {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISFIFO(mode)) return "a FIFO (named pipe)";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// Appends what `fd` holds to `contents`, to its end or until more than `limit` bytes are there in all (then
// `too_large`); with `stop_at_limit`, it stops once `limit` bytes are there instead, without reading further (the
// first bytes of a file, to tell its kind). False with `reason` on a read error.
bool read_all(int fd, std::size_t limit, std::string& contents, bool& too_large, std::string& reason,
              bool stop_at_limit) {
  char buffer[1 << 16];
  too_large = false;
  for (;;) {
    const std::size_t wanted = stop_at_limit ? std::min(sizeof buffer, limit - std::min(limit, contents.size()))
                                             : sizeof buffer;
    if (wanted == 0) return true;
    const ssize_t n = ::read(fd, buffer, wanted);
    if (n < 0) {
      if (errno == EINTR) continue;
      reason = std::strerror(errno);
      return false;
    }
    if (n == 0) return true;
    if (contents.size() + static_cast<std::size_t>(n) > limit) {
      too_large = true;
      return true;
    }
    contents.append(buffer, static_cast<std::size_t>(n));
  }
}

}  // namespace

std::string byte_size_text(std::size_t bytes) {
  const auto scaled = [&](std::size_t unit, const char* name) {
    if (bytes % unit == 0) return std::to_string(bytes / unit) + " " + name;
    char text[32];
    std::snprintf(text, sizeof text, "%.1f %s", static_cast<double>(bytes) / static_cast<double>(unit), name);
    return std::string(text);
  };
  if (bytes >= kMiB * 1024) return scaled(kMiB * 1024, "GiB");
  if (bytes >= kMiB) return scaled(kMiB, "MiB");
  if (bytes >= 1024) return scaled(1024, "KiB");
  return std::to_string(bytes) + " bytes";
}

std::optional<std::string> read_input_file(const std::string& path, std::size_t limit, const std::string& what,
                                           std::string& error) {
  std::optional<KindOfInput> input = read_input_file(path, {InputKind{what, limit, ""}}, error);
  if (!input) return std::nullopt;
  return std::move(input->contents);
}

std::optional<KindOfInput> read_input_file(const std::string& path, const std::vector<InputKind>& kinds,
                                           std::string& error) {
  // Until the kind is known, messages name the kinds in general ("lookup table or rule file").
  std::string any_kind;
  std::size_t signature_bytes = 0;
  for (const InputKind& kind : kinds) {
    any_kind += (any_kind.empty() ? "" : " or ") + kind.what;
    signature_bytes = std::max(signature_bytes, kind.signature.size());
  }
  if (path.find('\0') != std::string::npos) {
    error = "cannot read the " + any_kind + ": its path contains a NUL byte; check the path";
    return std::nullopt;
  }
  const bool from_stdin = path == "-";
  const std::string shown = from_stdin ? "standard input" : "'" + path + "'";
  const int fd = from_stdin ? STDIN_FILENO : ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    error = "cannot read " + shown + ": " + std::strerror(errno);
    return std::nullopt;
  }
  struct Closer {
    int fd;
    bool owned;
    ~Closer() {
      if (owned) ::close(fd);
    }
  } closer{fd, !from_stdin};
  std::optional<std::size_t> size;  // of a regular file; standard input may be a pipe or a terminal
  if (!from_stdin) {
    struct stat info {};
    if (::fstat(fd, &info) != 0) {
      error = "cannot read " + shown + ": " + std::strerror(errno);
      return std::nullopt;
    }
    if (!S_ISREG(info.st_mode)) {
      error = "cannot read " + shown + ": it is " + file_kind(info.st_mode) + ", not a " + any_kind +
              "; give the path of a regular file";
      return std::nullopt;
    }
    size = static_cast<std::size_t>(info.st_size);
    // Regular files never block; clearing O_NONBLOCK keeps read(2) from reporting EAGAIN on unusual file systems.
    ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  }
  KindOfInput input;
  bool too_large = false;
  std::string reason;
  // The first bytes, as many as the longest signature (a short file is its whole self), then the kind.
  if (!read_all(fd, signature_bytes, input.contents, too_large, reason, /*stop_at_limit=*/true)) {
    error = "cannot read " + shown + ": " + reason;
    return std::nullopt;
  }
  input.kind = kinds.size();
  for (std::size_t k = 0; k < kinds.size() && input.kind == kinds.size(); ++k)
    if (input.contents.compare(0, kinds[k].signature.size(), kinds[k].signature) == 0) input.kind = k;
  if (input.kind == kinds.size()) {
    error = "cannot read " + shown + ": it is not a " + any_kind;
    return std::nullopt;
  }
  const InputKind& kind = kinds[input.kind];
  const std::string limit_text = "the limit for a " + kind.what + " is " + byte_size_text(kind.limit);
  if (size && *size > kind.limit) {
    error = shown + " is " + byte_size_text(*size) + "; " + limit_text + ": split or simplify the file";
    return std::nullopt;
  }
  if (size) input.contents.reserve(*size);
  if (!read_all(fd, kind.limit, input.contents, too_large, reason, /*stop_at_limit=*/false)) {
    error = "cannot read " + shown + ": " + reason;
    return std::nullopt;
  }
  if (too_large) {
    error = shown + " holds more than " + byte_size_text(kind.limit) + "; " + limit_text;
    return std::nullopt;
  }
  return input;
}

}  // namespace fmpc::sim
