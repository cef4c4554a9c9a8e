#pragma once
// Output files are written to a temporary file beside the target and renamed over it, so a reader (ParaView, a
// plotting script) never sees a half-written file and a failed run leaves the previous file in place.
#include <string>

#include "diagnostics/diagnostic.h"

namespace fmpc::sim {

// Writes `contents` to `path` atomically (temporary file in the same folder + fsync + rename). Appends an error
// naming the file and the system's reason on failure.
bool write_file_atomically(const std::string& path, const std::string& contents, DiagnosticList& diagnostics);

// Creates `directory` and its parents when missing; an error names it otherwise.
bool ensure_directory(const std::string& directory, DiagnosticList& diagnostics);

}  // namespace fmpc::sim
