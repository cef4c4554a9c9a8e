#include "compiler/backend/cpp/namespace_name.h"

#include <algorithm>
#include <set>

namespace fmpc {

namespace {

// C++20's keywords and alternative tokens ([lex.key], [lex.digraph]).
const std::set<std::string>& keywords() {
  static const std::set<std::string> words = {
      "alignas", "alignof", "and", "and_eq", "asm", "auto", "bitand", "bitor", "bool", "break", "case", "catch", "char",
      "char8_t", "char16_t", "char32_t", "class", "compl", "concept", "const", "consteval", "constexpr", "constinit",
      "const_cast", "continue", "co_await", "co_return", "co_yield", "decltype", "default", "delete", "do", "double",
      "dynamic_cast", "else", "enum", "explicit", "export", "extern", "false", "float", "for", "friend", "goto", "if",
      "inline", "int", "long", "mutable", "namespace", "new", "noexcept", "not", "not_eq", "nullptr", "operator",
      "or", "or_eq", "private", "protected", "public", "register", "reinterpret_cast", "requires", "return",
      "short", "signed", "sizeof", "static", "static_assert", "static_cast", "struct", "switch", "template", "this",
      "thread_local", "throw", "true", "try", "typedef", "typeid", "typename", "union", "unsigned", "using",
      "virtual", "void", "volatile", "wchar_t", "while", "xor", "xor_eq"};
  return words;
}

// Macros in lower case that the standard headers of generated code define (<cassert>, <cerrno>, <cstddef>,
// <csetjmp>, <cstdarg>, <cmath>), and GCC's and Clang's target macros in GNU modes.
const std::set<std::string>& lower_case_macros() {
  static const std::set<std::string> words = {"assert", "errno",    "offsetof", "setjmp", "va_arg",
                                              "va_copy", "va_end", "va_start", "math_errhandling",
                                              "linux",  "unix",     "i386"};
  return words;
}

bool is_ascii_letter(char c) { return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z'); }
bool is_ascii_digit(char c) { return c >= '0' && c <= '9'; }

std::optional<std::string> identifier_problem(const std::string& part) {
  if (part.empty()) return std::string("an empty name (the path starts or ends with '::', or holds '::::')");
  if (!(is_ascii_letter(part[0]) || part[0] == '_') ||
      !std::all_of(part.begin(), part.end(), [](char c) { return is_ascii_letter(c) || is_ascii_digit(c) || c == '_'; }))
    return "'" + part + "' is not an identifier (ASCII letters, digits and '_', not starting with a digit)";
  if (keywords().count(part)) return "'" + part + "' is a C++ keyword";
  if (part[0] == '_' || part.find("__") != std::string::npos)
    return "'" + part + "' is reserved for the compiler and library (a leading '_' or a \"__\")";
  if (lower_case_macros().count(part)) return "'" + part + "' is a macro of the standard headers";
  if (std::none_of(part.begin(), part.end(), [](char c) { return c >= 'a' && c <= 'z'; }))
    return "'" + part + "' is spelled in capitals only, as macros are (NULL, EOF, INFINITY); use lower case";
  return std::nullopt;
}

}  // namespace

std::optional<std::string> namespace_name_problem(const std::string& name) {
  std::size_t start = 0;
  for (bool first = true;; first = false) {
    const std::size_t end = name.find("::", start);
    const std::string part = name.substr(start, end == std::string::npos ? std::string::npos : end - start);
    if (auto problem = identifier_problem(part)) return problem;
    if (first && part == "std") return std::string("'std' is the standard library's namespace");
    if (end == std::string::npos) return std::nullopt;
    start = end + 2;
  }
}

}  // namespace fmpc
