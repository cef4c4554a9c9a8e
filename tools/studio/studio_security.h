#pragma once
// What keeps the studio's server to its one user and its one folder (DESIGN section 9): a session token drawn from
// the kernel's random source, compared in constant time; the Host header (a page on another site that resolves its
// own name to 127.0.0.1, DNS rebinding, sends its own name); and paths, which must stay inside the opened folder
// after every symbolic link is followed.
#include <filesystem>
#include <optional>
#include <string>

namespace fmpc::studio {

// 32 bytes from /dev/urandom as 64 lower-case hex digits; nullopt (with `error`) when it cannot be read.
std::optional<std::string> random_token(std::string& error);

// Equal strings, compared in time independent of where they differ.
bool token_matches(const std::string& given, const std::string& token);

// "127.0.0.1:PORT" or "localhost:PORT", exactly.
bool host_allowed(const std::string& host, int port);

// `relative` (a path inside `root`, as the page names files: "rulesets/mamdani.fis") resolved to an absolute path
// that exists and lies inside `root` (itself canonical) once every symbolic link is followed. Refused, with `error`
// saying why: an empty, absolute or NUL-holding path, a `..` component, a path that does not exist, or one that
// leads outside `root` through a link.
std::optional<std::filesystem::path> resolve_inside(const std::filesystem::path& root, const std::string& relative,
                                                    std::string& error);

// `path` (canonical, inside `root`) as the page names it: relative to root, with '/'.
std::string relative_name(const std::filesystem::path& root, const std::filesystem::path& path);

}  // namespace fmpc::studio
