// libFuzzer target: the fmpc rule language (grammar/Fmpc.g4, compiler/frontend/fmpc_parser.cpp, sema, lint).
// The text is prefixed so that detect_dialect always picks the fmpc reader; fuzz_matlab_fis covers the other.
#include <string>

#include "tests/fuzz/fuzz_rule_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text = "# fuzz\n";
  text.append(reinterpret_cast<const char*>(data), size);
  if (text.find("[System]") != std::string::npos) return 0;  // the MATLAB reader's input
  fmpc::fuzz::load_lint_render("fuzz.fis", reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  return 0;
}
