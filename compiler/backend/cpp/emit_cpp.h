#pragma once
// The C++ / CUDA code emitter: turns a specialised FuzzySystem into one self-contained header holding a
// straight-line evaluator (templated on float / double), a batch function over arrays and, for the CUDA target, a
// __global__ kernel with a host launcher. docs/codegen.md describes the generated interface.
//
// What "self-contained" means: the header compiles alone with any C++17 compiler (or nvcc); it includes only the
// standard library (and <cuda_runtime.h> for the CUDA target). The membership math is a verbatim copy of
// kernels/fmpc_hd.h, kernels/fuzzy_kinds.h and kernels/fuzzy_math.h (and kernels/lane_exp_math.h where
// evaluate_batch runs lanes), embedded into fmpc at build time, so there is one definition of every formula; the
// copy lives in a namespace named after its content hash, so headers from different systems (or fmpc versions) can
// share a translation unit.
//
// By job: emit_evaluator (emit_cpp.cpp) writes the header's frame (banner, includes, embedded math, interface
// constants, the choice of evaluate_batch, the CUDA kernel and launcher); evaluator_emitter.h the type-1 evaluate
// function, emit_type2.h the interval type-2 one, lane_batch_emitter.h the vectorised evaluate_batch,
// embedded_math.h the copies of kernels/*_math.h, cpp_text.h the C++ spellings they share.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/diagnostic.h"

namespace fmpc {

struct EmitOptions {
  enum class Target { Cpp, Cuda };
  Target target = Target::Cpp;
  std::string source_path;        // the rule file, for the banner and the #line directives
  std::uint64_t source_hash = 0;  // fnv1a64 of the rule file's bytes (compiler/ir/content_hash.h), for the banner
  std::string namespace_name = "fmpc_generated";  // may be nested ("scene::liver"); must be C++ identifiers
  // Lines the banner repeats verbatim after the source and hash, e.g. the bindings ("fixed HCV = 10 kPa") and
  // what the passes removed. Each becomes one "//" comment line.
  std::vector<std::string> banner_notes;
  // `#line N "source_path"` before each rule's code, so compiler messages and debuggers point at the rule file.
  bool line_directives = true;
  // The header's own path as the user will include it; when set, a `#line` after each rule's code points back
  // into the header. When empty, lines after a rule keep the rule file's numbering until the next directive.
  std::string header_path;
};

// The generated header's text, or nullopt with errors in `diagnostics` (`samples exact`, a namespace that is not
// a C++ identifier path). Interval type-2 systems get emit_type2.h's evaluate function in the same frame.
// Precondition: `system` passed sema (compiler/sema/check.h).
std::optional<std::string> emit_evaluator(const FuzzySystem& system, const EmitOptions& options,
                                          DiagnosticList& diagnostics);

}  // namespace fmpc
