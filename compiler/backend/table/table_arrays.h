#pragma once
// A lookup table as C++/CUDA arrays in a header (`fmpc compile --target table -o NAME.h`), for code that links no
// loader: the breakpoints, counts and values as constant arrays, and `view()`, the kernels/table_math.h view to
// pass to fmpc::interpolate_table. The header includes "kernels/table_math.h" (fmpc's kernels/ directory must be
// on the include path; fmpc_add_ruleset() adds it). Under nvcc the arrays also exist as __device__ copies and
// view() returns those in device code, so one call works in host and device functions. Also interpolate_batch (n
// lookups on the host) and, under nvcc, interpolate_kernel and its launcher interpolate_batch_cuda.
#include <optional>
#include <string>

#include "compiler/backend/table/lookup_table.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

struct TableArraysOptions {
  std::string namespace_name = "fmpc_generated";  // may be nested ("scene::liver"); C++ identifiers
};

// The header's text, or nullopt with an error when options.namespace_name cannot name its namespace
// (compiler/backend/cpp/namespace_name.h). Values are written with format_number (shortest round-trip text), so the
// arrays hold exactly the table's values (as float with an f suffix for float32 tables); names and paths in its
// comments are kept to one line each (emitted_comment_text). Precondition: validate_table(table) holds.
std::optional<std::string> write_table_arrays(const LookupTable& table, const TableArraysOptions& options,
                                              DiagnosticList& diagnostics);

}  // namespace fmpc
