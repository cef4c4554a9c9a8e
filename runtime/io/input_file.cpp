#include "runtime/io/input_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
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
  if (bytes >= kMiB * 1024 && bytes % (kMiB * 1024) == 0) return std::to_string(bytes / (kMiB * 1024)) + " GiB";
  if (bytes >= kMiB && bytes % kMiB == 0) return std::to_string(bytes / kMiB) + " MiB";
  if (bytes >= 1024 && bytes % 1024 == 0) return std::to_string(bytes / 1024) + " KiB";
  return std::to_string(bytes) + " bytes";
}

std::optional<std::string> read_input_file(const std::string& path, std::size_t limit, const std::string& what,
                                           std::string& error) {
  const std::string limit_text = "the limit for a " + what + " is " + byte_size_text(limit);
  if (path.find('\0') != std::string::npos) {
    error = "cannot read the " + what + ": its path contains a NUL byte; check the path";
    return std::nullopt;
  }
  std::string contents;
  bool too_large = false;
  std::string reason;
  if (path == "-") {
    if (!read_all(STDIN_FILENO, limit, contents, too_large, reason)) {
      error = "cannot read the " + what + " from standard input: " + reason;
      return std::nullopt;
    }
    if (too_large) {
      error = "the " + what + " on standard input is larger than " + byte_size_text(limit) + "; " + limit_text;
      return std::nullopt;
    }
    return contents;
  }
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) {
    error = "cannot read '" + path + "': " + std::strerror(errno);
    return std::nullopt;
  }
  struct stat info {};
  if (::fstat(fd, &info) != 0) {
    error = "cannot read '" + path + "': " + std::strerror(errno);
    ::close(fd);
    return std::nullopt;
  }
  if (!S_ISREG(info.st_mode)) {
    error = "cannot read '" + path + "': it is " + file_kind(info.st_mode) + ", not a " + what +
            "; give the path of a regular file";
    ::close(fd);
    return std::nullopt;
  }
  if (static_cast<unsigned long long>(info.st_size) > limit) {
    error = "'" + path + "' is " + byte_size_text(static_cast<std::size_t>(info.st_size)) + "; " + limit_text +
            ": split or simplify the file";
    ::close(fd);
    return std::nullopt;
  }
  // Regular files never block; clearing O_NONBLOCK keeps read(2) from reporting EAGAIN on unusual file systems.
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK);
  contents.reserve(static_cast<std::size_t>(info.st_size));
  const bool ok = read_all(fd, limit, contents, too_large, reason);
  ::close(fd);
  if (!ok) {
    error = "cannot read '" + path + "': " + reason;
    return std::nullopt;
  }
  if (too_large) {
    error = "'" + path + "' grew past " + byte_size_text(limit) + " while it was read; " + limit_text;
    return std::nullopt;
  }
  return contents;
}

}  // namespace fmpc::sim
