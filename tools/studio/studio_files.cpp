#include "tools/studio/studio_files.h"

#include <algorithm>
#include <cstdio>

#include "compiler/frontend/fmpc_language.h"
#include "compiler/frontend/rule_file_loader.h"
#include "compiler/ir/content_hash.h"
#include "runtime/io/atomic_file.h"
#include "runtime/io/input_file.h"
#include "tools/studio/studio_security.h"

namespace fmpc::studio {

namespace fs = std::filesystem;

std::vector<std::string> list_files(const fs::path& root) {
  static const std::vector<std::string> extensions = {".fis", ".fll", ".fcl", ".csv", ".yaml", ".yml"};
  std::vector<std::string> files;
  std::error_code code;
  fs::recursive_directory_iterator it(root, fs::directory_options::skip_permission_denied, code), end;
  for (; !code && it != end && files.size() < kMaxListedFiles; it.increment(code)) {
    const fs::path& path = it->path();
    const std::string name = path.filename().string();
    if (it->is_directory(code)) {
      if (!name.empty() && name[0] == '.') it.disable_recursion_pending();
      if (it.depth() + 1 >= kMaxListedDepth) it.disable_recursion_pending();
      continue;
    }
    if (name.empty() || name[0] == '.') continue;
    if (std::find(extensions.begin(), extensions.end(), path.extension().string()) == extensions.end()) continue;
    std::string error;
    const std::string relative = relative_name(root, path);
    if (resolve_inside(root, relative, error) && it->is_regular_file(code)) files.push_back(relative);
  }
  std::sort(files.begin(), files.end());
  return files;
}

std::string text_version(const std::string& text) {
  char digits[17];
  std::snprintf(digits, sizeof digits, "%016llx", static_cast<unsigned long long>(fnv1a64(text)));
  return digits;
}

std::optional<FileText> read_folder_file(const fs::path& root, const std::string& relative, std::size_t limit,
                                         std::string& error) {
  const std::optional<fs::path> path = resolve_inside(root, relative, error);
  if (!path) return std::nullopt;
  const std::optional<std::string> text = sim::read_input_file(path->string(), limit, "file", error);
  if (!text) return std::nullopt;
  return FileText{relative_name(root, *path), *text, text_version(*text)};
}

SaveResult save_rule_file(const fs::path& root, const std::string& relative, const std::string& text,
                          const std::string& version) {
  SaveResult result;
  std::string error;
  const std::optional<FileText> disk = read_folder_file(root, relative, sim::kMaxRuleFileBytes, error);
  if (!disk) {
    result.message = error;
    return result;
  }
  if (detect_dialect(text) != Dialect::Fmpc) {
    result.message = std::string("this is a ") + dialect_name(detect_dialect(text)) +
                     " file; the studio saves fmpc files only (convert it: fmpc convert FILE --to fmpc)";
    return result;
  }
  if (text.size() > sim::kMaxRuleFileBytes) {
    result.message = "the text is larger than the limit for a rule file (" +
                     sim::byte_size_text(sim::kMaxRuleFileBytes) + ")";
    return result;
  }
  if (disk->version != version) {
    result.outcome = SaveOutcome::Conflict;
    result.message = "'" + disk->path + "' has changed on disk since it was opened; nothing was written. Reload it "
                     "(your edit is lost) or copy your edit elsewhere first";
    return result;
  }
  DiagnosticList diagnostics;
  const std::optional<std::string> formatted = format_fmpc(disk->path, text, diagnostics);
  if (!formatted) {
    result.message = "the text has syntax errors; nothing was written: fix them first";
    return result;
  }
  const fs::path target = root / disk->path;
  if (!sim::write_file_atomically(target.string(), *formatted, diagnostics)) {
    result.message = diagnostics.items().empty() ? "the file could not be written" : diagnostics.items().front().message;
    return result;
  }
  result.outcome = SaveOutcome::Saved;
  result.file = FileText{disk->path, *formatted, text_version(*formatted)};
  return result;
}

}  // namespace fmpc::studio
