#pragma once
// The files of the folder the studio opened: which ones the page may list, read and save. Every path comes from the
// page and goes through resolve_inside (studio_security.h). A file's version is the hash of its bytes on disk: the
// page sends back the version it read, and a save is refused when the file has changed since.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace fmpc::studio {

// At most this many files are listed, at most this many folders deep (hidden ones and links leading out skipped).
inline constexpr std::size_t kMaxListedFiles = 500;
inline constexpr int kMaxListedDepth = 4;

// Rule files (.fis .fll .fcl), data (.csv) and scenes (.yaml .yml) under `root`, relative, sorted.
std::vector<std::string> list_files(const std::filesystem::path& root);

// 16 hex digits of the FNV-1a hash of `text`.
std::string text_version(const std::string& text);

struct FileText {
  std::string path;  // relative, as the page names it
  std::string text;
  std::string version;
};

// Reads a file of the folder (at most `limit` bytes, through runtime/io/input_file.h); nullopt with `error`.
std::optional<FileText> read_folder_file(const std::filesystem::path& root, const std::string& relative,
                                         std::size_t limit, std::string& error);

enum class SaveOutcome { Saved, Conflict, Refused };

struct SaveResult {
  SaveOutcome outcome = SaveOutcome::Refused;
  std::string message;  // why not (Conflict, Refused)
  FileText file;        // Saved: the canonical text written and its version
};

// Writes `text` in the canonical layout (format_fmpc: comments kept) over the file, atomically, when its bytes on
// disk still have `version`. Refused: a path outside the folder, a file that is not in the fmpc language, a text
// with syntax errors (nothing is written). Conflict: the file changed on disk since it was read.
SaveResult save_rule_file(const std::filesystem::path& root, const std::string& relative, const std::string& text,
                          const std::string& version);

}  // namespace fmpc::studio
