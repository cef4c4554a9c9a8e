#pragma once
// Output files are written to a temporary file beside the target and renamed over it, so a reader (ParaView, a
// plotting script) never sees a half-written file and a failed run leaves the previous file in place. A command
// with several outputs writes them all or none: every temporary file is written and synced first, and only then
// are they renamed, so a missing folder for the second output leaves the first untouched too.
#include <string>
#include <utility>
#include <vector>

#include "diagnostics/diagnostic.h"

namespace fmpc::sim {

// Writes `contents` to `path` atomically (temporary file in the same folder + fsync + rename). Appends an error
// naming the file and the system's reason on failure. A path with a NUL byte is refused (the system would cut it
// there and write to another file).
bool write_file_atomically(const std::string& path, const std::string& contents, DiagnosticList& diagnostics);

// Writes every (path, contents) pair, all or nothing: nothing is renamed into place until every temporary file
// has been written; on failure the temporary files are removed and the targets keep what they had. (Only a rename
// failing after others succeeded, which needs the file system to fail between two renames in one folder, can
// leave some targets replaced; the error then names the outputs that were and were not.)
bool write_files_atomically(const std::vector<std::pair<std::string, std::string>>& files,
                            DiagnosticList& diagnostics);

// Creates `directory` and its parents when missing; an error names it otherwise.
bool ensure_directory(const std::string& directory, DiagnosticList& diagnostics);

}  // namespace fmpc::sim
