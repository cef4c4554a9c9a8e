#include "tools/studio/studio_security.h"

#include <array>
#include <fstream>

namespace fmpc::studio {

namespace fs = std::filesystem;

std::optional<std::string> random_token(std::string& error) {
  std::ifstream source("/dev/urandom", std::ios::binary);
  std::array<unsigned char, 32> bytes{};
  if (!source.read(reinterpret_cast<char*>(bytes.data()), bytes.size())) {
    error = "cannot read /dev/urandom for the session token";
    return std::nullopt;
  }
  static const char* digits = "0123456789abcdef";
  std::string token;
  for (unsigned char byte : bytes) {
    token += digits[byte >> 4];
    token += digits[byte & 15];
  }
  return token;
}

bool token_matches(const std::string& given, const std::string& token) {
  unsigned difference = given.size() == token.size() ? 0U : 1U;
  for (std::size_t i = 0; i < token.size(); ++i)
    difference |= static_cast<unsigned>(static_cast<unsigned char>(i < given.size() ? given[i] : 0) ^
                                        static_cast<unsigned char>(token[i]));
  return difference == 0;
}

bool host_allowed(const std::string& host, int port) {
  const std::string suffix = ":" + std::to_string(port);
  return host == "127.0.0.1" + suffix || host == "localhost" + suffix;
}

std::optional<fs::path> resolve_inside(const fs::path& root, const std::string& relative, std::string& error) {
  if (relative.empty()) {
    error = "no path given";
    return std::nullopt;
  }
  if (relative.find('\0') != std::string::npos) {
    error = "the path holds a NUL byte";
    return std::nullopt;
  }
  const fs::path given(relative);
  if (given.is_absolute() || given.has_root_name() || given.has_root_directory()) {
    error = "'" + relative + "' is absolute; name files relative to the opened folder";
    return std::nullopt;
  }
  for (const fs::path& part : given)
    if (part == "..") {
      error = "'" + relative + "' leads out of the opened folder ('..')";
      return std::nullopt;
    }
  std::error_code code;
  const fs::path resolved = fs::canonical(root / given, code);
  if (code) {
    error = "'" + relative + "' does not exist in the opened folder";
    return std::nullopt;
  }
  // Component by component, so that /data/rules-old is not taken to lie inside /data/rules.
  auto r = root.begin();
  auto p = resolved.begin();
  for (; r != root.end(); ++r, ++p)
    if (p == resolved.end() || *p != *r) {
      error = "'" + relative + "' leads out of the opened folder (through a symbolic link)";
      return std::nullopt;
    }
  return resolved;
}

std::string relative_name(const fs::path& root, const fs::path& path) {
  return path.lexically_relative(root).generic_string();
}

}  // namespace fmpc::studio
