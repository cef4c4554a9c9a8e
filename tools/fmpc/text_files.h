#pragma once
// File access for the CLI. Inputs go through runtime/io/input_file.h (regular files only, each kind of input
// bounded: docs/limits.md). Outputs are written to a temporary file beside the target and renamed over it, so a
// reader never sees a half-written file and a failed run leaves the old one in place.
#include <cstddef>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "runtime/io/input_file.h"

namespace fmpc::cli {

// The whole file ("-": standard input), at most `limit` bytes; nullopt with `error` set ("cannot read 'x.fis':
// No such file or directory", "'big.fis' is 9 MiB; the limit for a rule file is 8 MiB: ..."). `what` names the
// kind of file in messages.
std::optional<std::string> read_text_file(const std::string& path, std::size_t limit, const std::string& what,
                                          std::string& error);

// Writes `contents` to `path` atomically ("-" writes to stdout). Returns false with `error` set.
bool write_text_file_atomically(const std::string& path, const std::string& contents, std::string& error);

// Several outputs of one command, all or nothing (runtime/io/atomic_file.h); "-" entries go to stdout, and only
// after every file was written. Returns false with `error` set (naming the output that failed).
bool write_text_files_atomically(const std::vector<std::pair<std::string, std::string>>& files, std::string& error);

}  // namespace fmpc::cli
