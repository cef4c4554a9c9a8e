#pragma once
// Runs the fmpc binary under test as a user would, for the command-line tests.
#include <filesystem>
#include <string>

namespace fmpc::testing {

struct FmpcRun {
  int status = -1;  // exit status; -1 when fmpc did not exit normally
  std::string out;  // stdout and stderr together
};

// `fmpc ARGUMENTS` with standard input from `input` (a path), killed after 60 s (then status 124): a test that
// would otherwise hang fails instead.
FmpcRun run_fmpc(const std::string& arguments, const std::string& input = "/dev/null");

// The whole file as text ("" when it cannot be read).
std::string read_file_text(const std::filesystem::path& path);

}  // namespace fmpc::testing
