#include "runtime/io/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

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

// Reads `fd` to its end, or until more than `limit` bytes came; false with `reason` on a read error.
bool read_all(int fd, std::size_t limit, std::string& contents, bool& too_large, std::string& reason) {
  char buffer[1 << 16];
  too_large = false;
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
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
  const std::string limit_text = "the limit for a " + what + " is " + byte_size_text(limit);
  if (path.find('\0') != std::string::npos) {
    error = "cannot read the " + what + ": its path contains a NUL byte; check the path";
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
  std::string contents;
  if (!from_stdin) {  // standard input may be a pipe or a terminal: it is read up to the limit
    struct stat info {};
    if (::fstat(fd, &info) != 0) {
      error = "cannot read " + shown + ": " + std::strerror(errno);
      return std::nullopt;
    }
    if (!S_ISREG(info.st_mode)) {
      error = "cannot read " + shown + ": it is " + file_kind(info.st_mode) + ", not a " + what +
              "; give the path of a regular file";
      return std::nullopt;
    }
    if (static_cast<unsigned long long>(info.st_size) > limit) {
      error = shown + " is " + byte_size_text(static_cast<std::size_t>(info.st_size)) + "; " + limit_text +
              ": split or simplify the file";
      return std::nullopt;
    }
    // Regular files never block; clearing O_NONBLOCK keeps read(2) from reporting EAGAIN on unusual file systems.
    ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
    contents.reserve(static_cast<std::size_t>(info.st_size));
  }
  bool too_large = false;
  std::string reason;
  if (!read_all(fd, limit, contents, too_large, reason)) {
    error = "cannot read " + shown + ": " + reason;
    return std::nullopt;
  }
  if (too_large) {
    error = shown + " holds more than " + byte_size_text(limit) + "; " + limit_text;
    return std::nullopt;
  }
  return contents;
}

}  // namespace fmpc::sim
