#include "tools/fmpc/text_files.h"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>

#include "runtime/io/atomic_file.h"

namespace fmpc::cli {

std::optional<std::string> read_text_file(const std::string& path, std::string& error) {
  if (path == "-") {
    std::ostringstream buffer;
    buffer << std::cin.rdbuf();
    return buffer.str();
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    error = "cannot read '" + path + "': " + std::strerror(errno);
    return std::nullopt;
  }
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) {
    error = "cannot read '" + path + "': read error";
    return std::nullopt;
  }
  return buffer.str();
}

bool write_text_file_atomically(const std::string& path, const std::string& contents, std::string& error) {
  if (path == "-") {
    std::cout << contents << std::flush;
    return true;
  }
  DiagnosticList diagnostics;
  if (sim::write_file_atomically(path, contents, diagnostics)) return true;
  error = diagnostics.items().front().message;
  return false;
}

}  // namespace fmpc::cli
