#pragma once
// Compiling and running generated code at test time (the emitter tests): a scratch folder that removes itself,
// and the system compiler invoked with the warnings fmpc's own code obeys, as errors.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"

namespace fmpc::testing {

std::string read_text_file(const std::filesystem::path& path);
void write_text_file(const std::filesystem::path& path, const std::string& text);

// A fresh folder under the system's temporary directory, removed when the object goes.
class ScratchFolder {
 public:
  explicit ScratchFolder(const std::string& tag);
  ~ScratchFolder();
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// Compiles `source` into the executable `program` with FMPC_CXX_COMPILER (the compiler that built fmpc):
// -std=c++17 -O1 and fmpc's warning flags with -Werror. Returns true on success; `log` gets the compiler's output.
bool compile_generated_program(const std::filesystem::path& source, const std::filesystem::path& program,
                               std::string& log);

// `count` uniform points (random_inputs) plus the edges every evaluator must handle: each range's ends, below and
// above the range, +-inf, and NaN on one input.
std::vector<std::vector<double>> evaluator_test_points(const FuzzySystem& system, std::uint64_t seed,
                                                       std::size_t count);

// Checks (Catch2 CHECKs) the `#line` directives of a generated header: one per rule, in rule order, naming the
// rule's line in `rule_file`, each followed later by one back to `header_name` that names its own next line.
void check_line_directives(const std::string& header, const std::string& header_name, const std::string& rule_file,
                           const FuzzySystem& system);

}  // namespace fmpc::testing
