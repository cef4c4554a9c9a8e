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
  std::string shown;  // a NUL byte or a newline in the path must not reach the terminal as such
  for (const char c : path) shown += static_cast<unsigned char>(c) < 0x20 ? std::string("?") : std::string(1, c);
  SourceRange range;
  range.file = shown;
  diagnostics.error(range, "cannot write '" + shown + "': " + reason + "; check that its folder exists and is writable");
  return false;
}

// Writes `contents` to a new temporary file beside `path`; its name is returned in `temp`.
bool write_temporary(const std::string& path, const std::string& contents, std::string& temp,
                     DiagnosticList& diagnostics) {
  if (path.empty()) return fail(path, "the path is empty", diagnostics);
  if (path.find('\0') != std::string::npos) return fail(path, "the path contains a NUL byte", diagnostics);
  // mkstemp in the target's folder: rename(2) is atomic only within one file system.
  temp = path + ".tmp.XXXXXX";
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
  return true;
}

}  // namespace

bool write_file_atomically(const std::string& path, const std::string& contents, DiagnosticList& diagnostics) {
  return write_files_atomically({{path, contents}}, diagnostics);
}

bool write_files_atomically(const std::vector<std::pair<std::string, std::string>>& files,
                            DiagnosticList& diagnostics) {
  std::vector<std::string> temps;
  for (const auto& [path, contents] : files) {
    std::string temp;
    if (!write_temporary(path, contents, temp, diagnostics)) {
      for (const std::string& t : temps) ::unlink(t.c_str());
      return false;
    }
    temps.push_back(temp);
  }
  for (std::size_t i = 0; i < files.size(); ++i) {
    if (std::rename(temps[i].c_str(), files[i].first.c_str()) == 0) continue;
    const std::string reason = std::strerror(errno);
    for (std::size_t j = i; j < temps.size(); ++j) ::unlink(temps[j].c_str());
    std::string replaced;
    for (std::size_t j = 0; j < i; ++j) replaced += (j ? ", " : "") + files[j].first;
    return fail(files[i].first, reason + (i > 0 ? " (already replaced: " + replaced + ")" : std::string()),
                diagnostics);
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
