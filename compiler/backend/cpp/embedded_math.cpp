#include "compiler/backend/cpp/embedded_math.h"

#include <sstream>
#include <string_view>

#include "compiler/backend/cpp/embedded_kernels.h"

namespace fmpc {

namespace {

constexpr const char* kNamespaceOpen = "namespace fmpc {";
constexpr const char* kNamespaceClose = "}  // namespace fmpc";

}  // namespace

const std::vector<std::string>& type1_embedded_math_files() {
  static const std::vector<std::string> files = {"kernels/fmpc_hd.h", "kernels/fuzzy_kinds.h",
                                                 "kernels/fuzzy_math.h"};
  return files;
}

const std::vector<std::string>& type2_embedded_math_files() {
  static const std::vector<std::string> files = [] {
    std::vector<std::string> list = type1_embedded_math_files();
    list.insert(list.end(), {"kernels/type2_math.h", "kernels/type_reduction_math.h"});
    return list;
  }();
  return files;
}

std::string embedded_kernel_math(const std::vector<std::string>& paths, const std::string& math_namespace) {
  std::string result;
  for (const std::string& path : paths) {
    const std::string_view text = embedded_kernel_source(path);
    if (text.empty()) return {};
    result += std::string("// ---- copied from ") + path + " ----\n";
    const bool macro_file = path == "kernels/fmpc_hd.h";
    if (macro_file) result += "#ifndef FMPC_HD\n";
    std::istringstream lines{std::string(text)};
    std::string line;
    while (std::getline(lines, line)) {
      if (line.rfind("#pragma once", 0) == 0 || line.rfind("#include \"kernels/", 0) == 0) continue;
      if (line == kNamespaceOpen) line = "namespace " + math_namespace + " {";
      else if (line == kNamespaceClose) line = "}  // namespace " + math_namespace;
      result += line;
      result += '\n';
    }
    if (macro_file) result += "#endif\n";
  }
  return result;
}

std::string embedded_fuzzy_math(const std::string& math_namespace) {
  return embedded_kernel_math(type1_embedded_math_files(), math_namespace);
}

std::string embedded_namespace_body(const std::string& path) {
  const std::string text(embedded_kernel_source(path));
  const std::string open = std::string(kNamespaceOpen) + "\n", close = std::string("\n") + kNamespaceClose + "\n";
  const std::size_t begin = text.find(open);
  const std::size_t end = begin == std::string::npos ? begin : text.find(close, begin);
  if (end == std::string::npos) return {};
  std::string body = text.substr(begin + open.size(), end + 1 - (begin + open.size()));
  const std::size_t first = body.find_first_not_of('\n');
  if (first == std::string::npos) return {};
  body.erase(0, first);
  while (body.size() > 1 && body[body.size() - 1] == '\n' && body[body.size() - 2] == '\n') body.pop_back();
  return body;
}

}  // namespace fmpc
