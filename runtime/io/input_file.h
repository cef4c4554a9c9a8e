#pragma once
// Every input file is read through here. Hostile paths are refused before a byte is read or allocated: a
// directory, a device (/dev/zero), a FIFO or a socket is not a regular file (opened with O_NONBLOCK so that a FIFO
// with no writer cannot block the open, then fstat), and a file larger than the reader's limit is refused with the
// limit named (st_size is checked before allocating, and the read stops one byte past the limit in case the file
// grows while it is read). The limits are documented in docs/limits.md.
#include <cstddef>
#include <optional>
#include <string>

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

// "8 MiB", "512 MiB", "1 GiB", "1,000 bytes": how the limits are spelled in messages.
std::string byte_size_text(std::size_t bytes);

}  // namespace fmpc::sim
