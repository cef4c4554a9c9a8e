// libFuzzer target: IEC 61131-7 FCL (compiler/frontend/fcl.cpp and fuzzylite_vocabulary.cpp, sema, lint), through
// load_rule_file as every command reads it (byte order mark, format detection). Text that would not be read as
// FCL is prefixed with "FUNCTION_BLOCK fuzz" so that every input reaches the FCL reader.
#include <string>

#include "compiler/frontend/rule_file_loader.h"
#include "tests/fuzz/fuzz_rule_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  if (fmpc::detect_dialect(text) != fmpc::Dialect::Fcl) text.insert(0, "FUNCTION_BLOCK fuzz\n");
  fmpc::fuzz::load_lint_render("fuzz.fcl", reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  return 0;
}
