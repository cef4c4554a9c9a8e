#pragma once
// Every input file is read through here. Hostile paths are refused before a byte is read or allocated: a
// directory, a device (/dev/zero), a FIFO or a socket is not a regular file (opened with O_NONBLOCK so that a FIFO
// with no writer cannot block the open, then fstat), and a file larger than the reader's limit is refused with the
// limit named (st_size is checked before allocating, and the read stops one byte past the limit in case the file
// grows while it is read). The limits are documented in docs/limits.md.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace fmpc::sim {

inline constexpr std::size_t kMiB = std::size_t{1} << 20;
inline constexpr std::size_t kMaxRuleFileBytes = 8 * kMiB;      // fmpc language and MATLAB .fis
inline constexpr std::size_t kMaxSceneFileBytes = 1 * kMiB;     // scene YAML
inline constexpr std::size_t kMaxMeshFileBytes = 256 * kMiB;    // Gmsh, OBJ, legacy VTK
inline constexpr std::size_t kMaxCsvFileBytes = 64 * kMiB;      // fmpc eval --csv
inline constexpr std::size_t kMaxTableFileBytes = 1024 * kMiB;  // .fzt lookup tables

// The whole file at `path` ("-": standard input, read up to the same limit). `what` names the file's role in the
// error ("rule file", "mesh file"). Returns nullopt with `error` set to one sentence naming the path, the reason
// and what to do.
std::optional<std::string> read_input_file(const std::string& path, std::size_t limit, const std::string& what,
                                           std::string& error);

// An input that may be one of several kinds, told apart by their first bytes, each with its own limit (`fmpc eval`
// and the Python module take a .fzt table or a rule file): the first bytes are read, the kind chosen, and the size
// checked against that kind's limit before anything more is read (eval once read a 1 GiB rule file whole under the
// table's limit before the rule file's 8 MiB applied).
struct InputKind {
  std::string what;       // "lookup table", "rule file"
  std::size_t limit = 0;  // bytes
  std::string signature;  // the first bytes of a file of this kind; empty: any file
};
struct KindOfInput {
  std::size_t kind = 0;  // index into the kinds given: the first whose signature the file starts with
  std::string contents;
};
// The file at `path` ("-": standard input) as the first of `kinds` that it starts with; nullopt with `error` set as
// above (the messages name that kind), or when no kind matches.
std::optional<KindOfInput> read_input_file(const std::string& path, const std::vector<InputKind>& kinds,
                                           std::string& error);

// "8 MiB", "512 MiB", "1 GiB", "1,000 bytes": how the limits are spelled in messages.
std::string byte_size_text(std::size_t bytes);

}  // namespace fmpc::sim
