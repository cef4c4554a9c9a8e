// docs/cli.md against the command line itself: every command `fmpc --help` lists has a section, every option its
// `--help` lists is named in that section (or among the options every command takes), and every option the
// section names exists. Also the -W warning flags and the one exit-status rule, run through the real binary.
#include <catch2/catch.hpp>
#include <sys/wait.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "tests/support/fmpc_process.h"

#include "diagnostics/warning_codes.h"

namespace {

namespace fs = std::filesystem;

using fmpc::testing::read_file_text;
using Run = fmpc::testing::FmpcRun;
using fmpc::testing::run_fmpc;

// Options named in a help text's option lines ("  -o,--output TEXT ...").
std::set<std::string> help_options(const std::string& help) {
  std::set<std::string> options;
  std::istringstream lines(help);
  static const std::regex name(R"((?:^|[ ,])(--?[A-Za-z][-A-Za-z0-9]*))");
  for (std::string line; std::getline(lines, line);) {
    const std::size_t start = line.find_first_not_of(' ');
    if (start == std::string::npos || line[start] != '-' || start > 4) continue;
    // Only the names ("-o,--output"), not the type and default after them ("TEXT=-std=c++17 -O2").
    const std::size_t end = line.find(' ', start);
    const std::string names = line.substr(start, end == std::string::npos ? std::string::npos : end - start);
    for (auto it = std::sregex_iterator(names.begin(), names.end(), name); it != std::sregex_iterator(); ++it)
      options.insert((*it)[1].str());
  }
  return options;
}

// Options a markdown text names in code spans: `--fix NAME=VALUE`, `-o`, `-Wno-CODE` (as -W).
std::set<std::string> documented_options(const std::string& markdown) {
  std::set<std::string> options;
  static const std::regex span(R"(`(--?[A-Za-z][-A-Za-z0-9]*))");
  for (auto it = std::sregex_iterator(markdown.begin(), markdown.end(), span); it != std::sregex_iterator(); ++it) {
    std::string option = (*it)[1].str();
    if (option.rfind("-W", 0) == 0) option = "-W";
    options.insert(option);
  }
  return options;
}

// The text of docs/cli.md from "## `fmpc NAME" to the next "## ".
std::string section(const std::string& markdown, const std::string& heading) {
  const std::size_t start = markdown.find("\n## " + heading);
  if (start == std::string::npos) return {};
  const std::size_t end = markdown.find("\n## ", start + 1);
  return markdown.substr(start, end == std::string::npos ? std::string::npos : end - start);
}

std::set<std::string> subcommands() {
  const Run help = run_fmpc("--help");
  std::set<std::string> names;
  const std::size_t at = help.out.find("Subcommands:");
  REQUIRE(at != std::string::npos);
  std::istringstream lines(help.out.substr(at));
  std::string line;
  std::getline(lines, line);
  while (std::getline(lines, line)) {
    std::istringstream words(line);
    std::string word;
    if (line.empty() || line[0] != ' ') break;
    // "  name   description"; a description's continuation lines are indented further.
    if (line.size() > 2 && line[2] != ' ' && (words >> word)) names.insert(word);
  }
  return names;
}

}  // namespace

TEST_CASE("docs/cli.md names every command and option of the CLI, and nothing else", "[cli][docs]") {
  const std::string docs = read_file_text(fs::path(FMPC_SOURCE_DIR) / "docs" / "cli.md");
  REQUIRE_FALSE(docs.empty());
  const std::set<std::string> common = documented_options(section(docs, "Options every command takes"));
  REQUIRE(common.count("-W"));
  REQUIRE(common.count("--help"));
  const std::set<std::string> commands = subcommands();
  CHECK(commands.size() >= 8);
  for (const std::string& command : commands) {
    INFO("fmpc " << command);
    const std::string text = section(docs, "`fmpc " + command);
    REQUIRE_FALSE(text.empty());
    const Run help = run_fmpc(command + " --help");
    REQUIRE(help.status == 0);
    const std::set<std::string> listed = help_options(help.out);
    const std::set<std::string> documented = documented_options(text);
    for (const std::string& option : listed) {
      INFO("option " << option << " (in --help)");
      CHECK((documented.count(option) + common.count(option)) > 0);
    }
    for (const std::string& option : documented) {
      INFO("option " << option << " (in docs/cli.md)");
      CHECK(listed.count(option) > 0);
    }
  }
}

TEST_CASE("help output shows defaults and no build path", "[cli][docs]") {
  const Run help = run_fmpc("eval --help");
  CHECK(help.status == 0);
  CHECK(help.out.find("fmpc eval") != std::string::npos);
  CHECK(help.out.find(fs::path(FMPC_BINARY).parent_path().string()) == std::string::npos);
  CHECK(help.out.find("0.001") != std::string::npos);  // --explain-threshold's default
}

TEST_CASE("warning flags: -Wno-CODE silences, -Werror=CODE fails with status 1, an unknown code is refused", "[cli]") {
  const fs::path folder = fs::temp_directory_path() / "fmpc_cli_docs_test";
  fs::create_directories(folder);
  const fs::path file = folder / "no_unit.fmpc";
  std::ofstream(file) << "system s\n  type mamdani\n"
                         "input x in [0, 1]\n  low is triangle(start 0, peak 0, end 1)\n"
                         "  high is triangle(start 0, peak 1, end 1)\n"
                         "output z in [0, 1] kPa\n  small is triangle(start 0, peak 0, end 1)\n"
                         "  big is triangle(start 0, peak 1, end 1)\n"
                         "rule r1: if x is low then z is small\nrule r2: if x is high then z is big\n";
  const Run plain = run_fmpc("check " + file.string());
  CHECK(plain.status == 0);
  CHECK(plain.out.find("[-Wunit]") != std::string::npos);

  const Run silenced = run_fmpc("check -Wno-unit " + file.string());
  CHECK(silenced.status == 0);
  CHECK(silenced.out.find("-Wunit") == std::string::npos);

  const Run promoted = run_fmpc("check -Werror=unit " + file.string());
  CHECK(promoted.status == 1);
  CHECK(promoted.out.find("error: input 'x' has no unit") != std::string::npos);
  CHECK(promoted.out.find("[-Werror=unit]") != std::string::npos);

  CHECK(run_fmpc("check -Werror " + file.string()).status == 1);
  CHECK(run_fmpc("check --werror " + file.string()).status == 1);
  CHECK(run_fmpc("check -Werror -Wno-error=unit " + file.string()).status == 0);
  // The same rule in another command: eval reports the out-of-range input as a warning.
  CHECK(run_fmpc("eval " + file.string() + " x=2").status == 0);
  CHECK(run_fmpc("eval -Werror=input-out-of-range " + file.string() + " x=2").status == 1);

  const Run unknown = run_fmpc("check -Wno-unti " + file.string());
  CHECK(unknown.status == 2);
  CHECK(unknown.out.find("did you mean 'unit'?") != std::string::npos);
  std::error_code ignored;
  fs::remove_all(folder, ignored);
}

// The -W flags accept exactly the codes in diagnostics/warning_codes.cpp: every `warning(RANGE, "code", ...)` in the
// sources must be listed there, or `-Wno-code` would be refused for a warning fmpc prints.
TEST_CASE("every warning code in the sources is a known -W code", "[cli][docs]") {
  static const std::regex call(R"re(\.warning\(\s*[^;]*?,\s*"([a-z0-9-]+)")re");
  std::set<std::string> found;
  for (const char* tree : {"compiler", "runtime", "tools", "diagnostics"})
    for (const auto& entry : fs::recursive_directory_iterator(fs::path(FMPC_SOURCE_DIR) / tree)) {
      const std::string extension = entry.path().extension().string();
      if (extension != ".cpp" && extension != ".h" && extension != ".cu") continue;
      const std::string text = read_file_text(entry.path());
      for (auto it = std::sregex_iterator(text.begin(), text.end(), call); it != std::sregex_iterator(); ++it)
        found.insert((*it)[1].str());
    }
  CHECK(found.size() >= 30);
  for (const std::string& code : found) {
    INFO("warning code '" << code << "'");
    CHECK(fmpc::is_warning_code(code));
  }
}

TEST_CASE("every option that takes a value refuses an empty one, naming it", "[cli][heavy]") {
  // `-o ''` once sent simulate's outputs to the default folder and `--csv ''` made trade write nothing: an empty
  // value is a mistake (an unset shell variable), and every command says so, whatever the option.
  std::size_t checked = 0;
  for (const std::string& command : subcommands()) {
    const Run help = run_fmpc(command + " --help");
    REQUIRE(help.status == 0);
    std::istringstream lines(help.out.substr(help.out.find("Options:")));
    for (std::string line; std::getline(lines, line);) {
      // "  -o,--output TEXT=-  ...": names, then a type in capitals; flags have no type.
      std::istringstream words(line);
      std::string names, type;
      if (!(words >> names >> type) || names[0] != '-' || line.find_first_not_of(' ') > 4) continue;
      static const std::regex value_type(R"(^[A-Z]+([:=].*)?$)");  // TEXT, UINT=20, FLOAT:FLOAT in [0 - 1]
      if (!std::regex_match(type, value_type) || names == "-W" || names == "--cxx-flags") continue;
      const std::string option = names.substr(names.rfind(',') + 1);
      const Run run = run_fmpc(command + " " + option + " ''");
      INFO("fmpc " << command << " " << option << " '': " << run.out);
      CHECK(run.status == 2);
      // "--output: an empty value names nothing ..." (by any of its names: --png is --image); numbers and choices
      // refuse '' through their own check.
      bool named = false;
      for (std::size_t start = 0; start < names.size();) {
        const std::size_t comma = std::min(names.find(',', start), names.size());
        named = named || run.out.find(names.substr(start, comma - start) + ": ") != std::string::npos;
        start = comma + 1;
      }
      CHECK(named);
      ++checked;
    }
  }
  CHECK(checked > 40);
}
