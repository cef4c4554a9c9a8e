#include "tools/fmpc/text_files.h"

#include <iostream>

#include "runtime/io/atomic_file.h"

namespace fmpc::cli {

std::optional<std::string> read_text_file(const std::string& path, std::size_t limit, const std::string& what,
                                          std::string& error) {
  return sim::read_input_file(path, limit, what, error);
}

bool write_text_file_atomically(const std::string& path, const std::string& contents, std::string& error) {
  return write_text_files_atomically({{path, contents}}, error);
}

bool write_text_files_atomically(const std::vector<std::pair<std::string, std::string>>& files, std::string& error) {
  std::vector<std::pair<std::string, std::string>> on_disk;
  for (const auto& file : files)
    if (file.first != "-") on_disk.push_back(file);
  DiagnosticList diagnostics;
  if (!sim::write_files_atomically(on_disk, diagnostics)) {
    error = diagnostics.items().front().message;
    return false;
  }
  for (const auto& [path, contents] : files)
    if (path == "-") std::cout << contents << std::flush;
  return true;
}

}  // namespace fmpc::cli
