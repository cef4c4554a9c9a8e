// Text from the command line and the rule file that generated headers repeat (issue 30: `--namespace 'a{} int x;
// namespace b'` wrote a declaration into a table header): the namespace is checked as code by one function for
// every emitter, and paths and names in comments stay inside their comment. Both are checked by the compiler.
#include <catch2/catch.hpp>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "compiler/backend/cpp/emit_cpp.h"
#include "compiler/backend/cpp/namespace_name.h"
#include "compiler/backend/table/table_arrays.h"
#include "tests/support/generated_program.h"

using namespace fmpc;

namespace {

// Candidates: every keyword and alternative token, contextual words, the standard headers' macros, names in
// capitals, reserved spellings, injections, and seeded random strings over identifier characters, ':', blanks
// and the characters that end a declaration.
std::vector<std::string> namespace_candidates() {
  std::vector<std::string> names = {
      "int", "and", "or", "not", "xor", "bitand", "compl", "class", "namespace", "template", "typename", "co_await",
      "char8_t", "concept", "requires", "consteval", "constinit", "export", "import", "module", "final", "override",
      "NULL", "EOF", "INFINITY", "NAN", "HUGE_VAL", "M_PI", "assert", "errno", "offsetof", "linux", "unix", "std",
      "std::x", "x::std", "_x", "_X", "a__b", "__global__", "fmpc", "fmpc_math", "kernels", "a{} int x; namespace b",
      "a {", "a//", "a/*", "a\\", "a\nb", "a b", "", "::", "a::", "::a", "a:::b", "a::::b", "1a", "a-b", "\xc3\xa9t\xc3\xa9",
      "liver", "scene::liver_2", "Liver", "x9", "a_b_c"};
  std::mt19937 random(30);
  const std::string alphabet = "abcXYZ_09:: {};\n/\\\"";
  for (int n = 0; n < 300; ++n) {
    std::string name;
    const std::size_t length = 1 + random() % 10;
    for (std::size_t k = 0; k < length; ++k) name += alphabet[random() % alphabet.size()];
    names.push_back(name);
  }
  return names;
}

bool is_identifier_path(const std::string& name) {
  bool at_start = true;
  for (std::size_t i = 0; i < name.size(); ++i) {
    const char c = name[i];
    if (c == ':' && i + 1 < name.size() && name[i + 1] == ':' && !at_start) {
      ++i;
      at_start = true;
      continue;
    }
    const bool letter = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
    if (!(letter || (c >= '0' && c <= '9' && !at_start))) return false;
    at_start = false;
  }
  return !name.empty() && !at_start;
}

}  // namespace

TEST_CASE("a namespace is accepted only when the compiler takes it as one", "[emit][hostile]") {
  // Every accepted candidate is an identifier path, and all of them, each declared in a TU that includes what the
  // generated headers include, compile at once.
  std::string source = "#include <cassert>\n#include <cerrno>\n#include <cmath>\n#include <cstddef>\n#include <cstdio>\n"
                       "#include <cstdint>\n#include <limits>\n";
  std::size_t accepted = 0;
  for (const std::string& name : namespace_candidates()) {
    const auto problem = namespace_name_problem(name);
    INFO("'" << name << "': " << problem.value_or("accepted"));
    if (problem) continue;
    CHECK(is_identifier_path(name));
    source += "namespace " + name + " { inline int f" + std::to_string(accepted++) + "() { return 0; } }\n";
  }
  CHECK(accepted >= 5);
  for (const char* keyword : {"int", "and", "class", "char8_t", "co_await"}) CHECK(namespace_name_problem(keyword));
  testing::ScratchFolder folder("namespaces");
  testing::write_text_file(folder.path() / "names.cpp", source + "int main() { return 0; }\n");
  std::string log;
  INFO(log);
  CHECK(testing::compile_generated_program(folder.path() / "names.cpp", folder.path() / "names", log));
}

TEST_CASE("generated headers refuse a namespace that is not one, and keep names and paths in their comments",
          "[emit][hostile]") {
  // A table whose path, system, variables and units try to end their comment line and start code: `#error` on a
  // line of its own would stop the compile.
  const std::string escape = "x\n#error injected\n";
  LookupTable table;
  table.source_path = "rules/" + escape + "r.fis\\";
  table.system_name = "s" + escape;
  table.value_type = TableValueType::Float64;
  TableAxis axis;
  axis.input_name = "in" + escape;
  axis.input_unit = "kPa\\";
  axis.breakpoints = {0.0, 1.0};
  table.axes = {axis};
  table.output_names = {"out\\"};
  table.output_units = {"Pa" + escape};
  table.fixed_inputs = {TableFixedInput{"f" + escape, "mm\\", 1.0}};
  table.values = {1.0, 2.0};
  table.max_error_location = {0.5};
  for (const std::string& bad : {std::string("a{} int x; namespace b"), std::string("int"), std::string("NULL")}) {
    TableArraysOptions options;
    options.namespace_name = bad;
    DiagnosticList diagnostics;
    CHECK_FALSE(write_table_arrays(table, options, diagnostics));
    REQUIRE(diagnostics.error_count() == 1);
    CHECK(diagnostics.items()[0].message.find("cannot name the generated code's namespace") != std::string::npos);
  }
  TableArraysOptions options;
  options.namespace_name = "scene::liver";
  DiagnosticList diagnostics;
  const std::optional<std::string> header = write_table_arrays(table, options, diagnostics);
  REQUIRE(header);
  testing::ScratchFolder folder("injection");
  testing::write_text_file(folder.path() / "t.h", *header);
  testing::write_text_file(folder.path() / "main.cpp",
                           "#include \"t.h\"\nint main() { return scene::liver::kAxes == 1 ? 0 : 1; }\n");
  // The header includes "kernels/table_math.h": the source tree on the include path (as table_arrays_test does).
  REQUIRE(setenv("CPLUS_INCLUDE_PATH", FMPC_SOURCE_DIR, 1) == 0);
  std::string log;
  const bool compiled = testing::compile_generated_program(folder.path() / "main.cpp", folder.path() / "main", log);
  unsetenv("CPLUS_INCLUDE_PATH");
  INFO(log);
  CHECK(compiled);
}
