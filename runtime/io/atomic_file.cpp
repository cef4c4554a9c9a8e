#include "runtime/io/atomic_file.h"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <system_error>

namespace fmpc::sim {

namespace {

bool fail(const std::string& path, const std::string& reason, DiagnosticList& diagnostics) {
  SourceRange range;
  range.file = path;
  diagnostics.error(range, "cannot write '" + path + "': " + reason + "; check that its folder exists and is writable");
  return false;
}

}  // namespace

bool write_file_atomically(const std::string& path, const std::string& contents, DiagnosticList& diagnostics) {
  // mkstemp in the target's folder: rename(2) is atomic only within one file system.
  std::string temp = path + ".tmp.XXXXXX";
  const int fd = ::mkstemp(temp.data());
  if (fd < 0) return fail(path, std::strerror(errno), diagnostics);
  std::size_t written = 0;
  while (written < contents.size()) {
    const ssize_t n = ::write(fd, contents.data() + written, contents.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string reason = std::strerror(errno);
      ::close(fd);
      ::unlink(temp.c_str());
      return fail(path, reason, diagnostics);
    }
    written += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string reason = std::strerror(errno);
    ::unlink(temp.c_str());
    return fail(path, reason, diagnostics);
  }
  // mkstemp creates 0600; keep the mode of the file being replaced, or give a new one the usual 0644.
  struct stat existing {};
  ::chmod(temp.c_str(), ::stat(path.c_str(), &existing) == 0 ? (existing.st_mode & 07777) : 0644);
  if (std::rename(temp.c_str(), path.c_str()) != 0) {
    const std::string reason = std::strerror(errno);
    ::unlink(temp.c_str());
    return fail(path, reason, diagnostics);
  }
  return true;
}

bool ensure_directory(const std::string& directory, DiagnosticList& diagnostics) {
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error || !std::filesystem::is_directory(directory)) {
    SourceRange range;
    range.file = directory;
    diagnostics.error(range, "cannot create the output directory '" + directory + "': " +
                                 (error ? error.message() : std::string("a file of that name exists")));
    return false;
  }
  return true;
}

}  // namespace fmpc::sim
