#pragma once
// File access for the CLI. Outputs are written to a temporary file beside the target and renamed over it, so a
// reader never sees a half-written file and a failed run leaves the old one in place.
#include <optional>
#include <string>

namespace fmpc::cli {

// The whole file, or nullopt with `error` set ("cannot read 'x.fis': No such file or directory").
std::optional<std::string> read_text_file(const std::string& path, std::string& error);

// Writes `contents` to `path` atomically ("-" writes to stdout). Returns false with `error` set.
bool write_text_file_atomically(const std::string& path, const std::string& contents, std::string& error);

}  // namespace fmpc::cli
