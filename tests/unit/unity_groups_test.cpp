// Unity groups (cmake/FmpcUnityGroups.cmake; compiler/, runtime/, tools/ and tests/ unity_groups.cmake): a group's
// files compile as one source, so their file-scope helpers (anonymous namespaces, statics) share one scope. Two files
// defining the same such name would clash or, where the parameters differ, overload silently and change which
// function a call reaches. No group may hold two files that define the same file-scope name.
#include <catch2/catch.hpp>
#include <cctype>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace {

bool begins_with(const std::string& text, const std::string& prefix) { return text.rfind(prefix, 0) == 0; }

std::string identifier_at_start(const std::string& text) {
  std::size_t end = 0;
  while (end < text.size() && (std::isalnum(static_cast<unsigned char>(text[end])) || text[end] == '_')) ++end;
  return text.substr(0, end);
}

// Where a raw string literal that `line` opens without closing it ends: its `)delimiter"`, or "" if none is open.
std::string open_raw_string_end(const std::string& line) {
  for (std::size_t at = line.find("R\""); at != std::string::npos; at = line.find("R\"", at + 1)) {
    const std::size_t open = line.find('(', at + 2);
    if (open == std::string::npos) break;
    const std::string closing = ")" + line.substr(at + 2, open - at - 2) + "\"";
    const std::size_t closed = line.find(closing, open + 1);
    if (closed == std::string::npos) return closing;
    at = closed;
  }
  return "";
}

// A line such as `TEST_CASE("...", "[tag]") {`: an all-capitals name called like a function.
bool macro_call(const std::string& line) {
  const std::string name = identifier_at_start(line);
  if (name.empty() || line.size() == name.size() || line[name.size()] != '(') return false;
  for (char c : name)
    if (std::islower(static_cast<unsigned char>(c))) return false;
  return true;
}

// The names a C++ source defines at file scope with internal linkage: the declarations that start a line inside
// `namespace {` ... `}  // namespace` (the project's formatting), and `static` declarations at the start of a line.
// A declaration's name is the one after struct / class / enum / union or `using`, or else the identifier before
// its first `(`, `=`, `[`, `{` or `;` outside angle brackets. Templates' own lines, operators, namespace aliases,
// using-directives and macro calls (TEST_CASE: Catch numbers its names by __COUNTER__) name nothing that could
// clash, and neither do the lines of a raw string literal (a rule file's text in a test).
std::set<std::string> file_scope_names(const std::string& text) {
  std::set<std::string> names;
  bool anonymous = false;
  std::string raw_string_end;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    if (!raw_string_end.empty()) {
      const std::size_t closed = line.find(raw_string_end);
      if (closed == std::string::npos) continue;
      raw_string_end = open_raw_string_end(line.substr(closed + raw_string_end.size()));
      continue;
    }
    raw_string_end = open_raw_string_end(line);
    if (line == "namespace {") {
      anonymous = true;
      continue;
    }
    if (anonymous && line == "}  // namespace") {
      anonymous = false;
      continue;
    }
    if (!anonymous && !begins_with(line, "static ")) continue;
    if (line.empty() || !(std::isalpha(static_cast<unsigned char>(line[0])) || line[0] == '_')) continue;
    if (begins_with(line, "template") || begins_with(line, "namespace ") || begins_with(line, "using namespace") ||
        line.find("operator") != std::string::npos || macro_call(line))
      continue;
    std::string rest = line;
    while (begins_with(rest, "static ") || begins_with(rest, "inline ") || begins_with(rest, "constexpr "))
      rest = rest.substr(rest.find(' ') + 1);
    bool named = false;
    for (const char* keyword : {"struct ", "class ", "enum class ", "enum ", "union ", "using "}) {
      if (!begins_with(rest, keyword)) continue;
      const std::string after = rest.substr(std::string(keyword).size());
      const std::string name = identifier_at_start(after);
      // `using NAME = ...` declares NAME; `using fmpc::Frame;` brings in a name declared elsewhere.
      const bool alias = after.find_first_not_of(' ', name.size()) != std::string::npos &&
                         after[after.find_first_not_of(' ', name.size())] == '=';
      if (!name.empty() && (std::string(keyword) != "using " || alias)) names.insert(name);
      named = true;
      break;
    }
    if (named) continue;
    int angle = 0;
    for (std::size_t i = 0; i < rest.size(); ++i) {
      const char c = rest[i];
      if (c == '<') ++angle;
      if (c == '>') --angle;
      if (angle != 0 || std::string("(=[{;").find(c) == std::string::npos) continue;
      std::size_t end = i;
      while (end > 0 && rest[end - 1] == ' ') --end;
      std::size_t begin = end;
      while (begin > 0 && (std::isalnum(static_cast<unsigned char>(rest[begin - 1])) || rest[begin - 1] == '_'))
        --begin;
      // `Parser::parse(` defines a member declared in its class, not a new name.
      const bool member = begin >= 2 && rest[begin - 1] == ':' && rest[begin - 2] == ':';
      if (begin < end && !member) names.insert(rest.substr(begin, end - begin));
      break;
    }
  }
  return names;
}

const std::set<std::string> kStandardFunctionsFoundByAdl = {
    "quoted", "size",    "ssize",    "empty",      "data", "begin", "end", "cbegin", "cend",      "rbegin",     "rend",
    "swap",   "getline", "to_chars", "from_chars", "stoi", "stod",  "get", "visit",  "make_pair", "make_tuple", "tie"};

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST_CASE("file-scope names: anonymous namespaces and statics, not members, templates' lines or using-declarations",
          "[build]") {
  // Written line by line, so that this file's own lines do not start with the sample's declarations.
  const std::string text =
      "#include <map>\n"
      "namespace fmpc {\n"
      "namespace fs = std::filesystem;\n"
      "int external(int x) { return x; }\n"
      "namespace {\n"
      "using namespace std;\n"
      "constexpr double kNaN = 0.0;\n"
      "const char* const kNames[] = {\"a\"};\n"
      "std::map<std::pair<int, int>, double> table_of(int n) {\n"
      "  int local(3);\n"
      "  return {};\n"
      "}\n"
      "template <typename T, int N = 3>\n"
      "T twice(T x) { return x + x; }\n"
      "using fmpc::Variable;\n"
      "struct Frame {\n"
      "  int member(int);\n"
      "};\n"
      "enum class Kind { A, B };\n"
      "using ClauseKey = std::tuple<int, int>;\n"
      "std::function<void(int)> callback = nullptr;\n"
      "bool operator<(const Frame&, const Frame&);\n"
      "const char* const kRules = R\"rules(input x in [0, 1] kPa\n"
      "output y in [0, 2] kPa\n"
      "if x is low then y is high)rules\";\n"
      "TEST_CASE(\"a test's own name\", \"[t]\") {\n"
      "  CHECK(true);\n"
      "}\n"
      "int Frame::member(int x) { return x; }\n"
      "}  // namespace\n"
      "static int counter;\n"
      "static_assert(true, \"not a name\");\n"
      "}  // namespace fmpc\n";
  CHECK(file_scope_names(text) == std::set<std::string>{"kNaN", "kNames", "table_of", "twice", "Frame", "Kind",
                                                        "ClauseKey", "callback", "kRules", "counter"});
}

TEST_CASE("no unity group holds two files that define the same file-scope name", "[build]") {
  std::map<std::string, std::vector<std::string>> groups;
  std::istringstream lines(read_file(FMPC_UNITY_GROUPS_FILE));
  for (std::string line; std::getline(lines, line);) {
    const std::size_t bar = line.find('|');
    if (bar != std::string::npos) groups[line.substr(0, bar)].push_back(line.substr(bar + 1));
  }
  // The compiler's, the runtime's, the tools' and the tests' groups.
  CHECK(groups.count("compiler_emitters") == 1);
  CHECK(groups.count("runtime_scene_file") == 1);
  CHECK(groups.count("tools_studio_server") == 1);
  CHECK(groups.count("tests_0") == 1);
  std::size_t files = 0;
  for (const auto& [group, paths] : groups) {
    std::map<std::string, std::string> defined_in;
    for (const std::string& path : paths) {
      const std::string text = read_file(path);
      if (text.empty()) continue;  // a listed file that no longer exists is not compiled
      ++files;
      for (const std::string& name : file_scope_names(text)) {
        // Argument-dependent lookup brings these in for std::string or container arguments wherever another file
        // of the group includes their header (std::quoted took lower_fmpc.cpp's quoted(name) that way).
        if (kStandardFunctionsFoundByAdl.count(name))
          FAIL_CHECK("unity group " << group << ": " << path << " defines '" << name << "' at file scope, as the "
                                    << "standard library does: calls with std arguments may reach std::" << name
                                    << " once another file of the group includes its header; rename it");
        const auto [first, added] = defined_in.emplace(name, path);
        if (!added)
          FAIL_CHECK("unity group " << group << ": '" << name << "' is defined at file scope in both " << first->second
                                    << " and " << path
                                    << "; rename one of them or move one file to another group (unity_groups.cmake)");
      }
    }
  }
  CHECK(files > 100);
}
