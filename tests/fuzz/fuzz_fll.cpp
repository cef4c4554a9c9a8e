// libFuzzer target: fuzzylite's FLL (compiler/frontend/fll.cpp and fuzzylite_vocabulary.cpp, sema, lint), through
// load_rule_file as every command reads it (byte order mark, format detection). Text that would not be read as
// FLL is prefixed with "Engine: fuzz" so that every input reaches the FLL reader.
#include <string>

#include "compiler/frontend/rule_file_loader.h"
#include "tests/fuzz/fuzz_rule_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  if (fmpc::detect_dialect(text) != fmpc::Dialect::Fll) text.insert(0, "Engine: fuzz\n");
  fmpc::fuzz::load_lint_render("fuzz.fll", reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  return 0;
}
