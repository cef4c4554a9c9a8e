#pragma once
// The C++ / CUDA code emitter: turns a specialised FuzzySystem into one self-contained header holding a
// straight-line evaluator (templated on float / double), a batch function over arrays and, for the CUDA target, a
// __global__ kernel with a host launcher. docs/codegen.md describes the generated interface.
//
// What "self-contained" means: the header compiles alone with any C++17 compiler (or nvcc); it includes only the
// standard library (and <cuda_runtime.h> for the CUDA target). The membership math is a verbatim copy of
// kernels/fmpc_hd.h, kernels/fuzzy_kinds.h and kernels/fuzzy_math.h, embedded into fmpc at build time, so there
// is one definition of every formula; the copy lives in a namespace named after its content hash, so headers
// from different systems (or fmpc versions) can share a translation unit.
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

// The text of fmpc's membership math (kernels/fmpc_hd.h, fuzzy_kinds.h, fuzzy_math.h) as embedded at build time,
// with its namespace renamed to `math_namespace`; used by the emitters and by tests that compare the copy.
std::string embedded_fuzzy_math(const std::string& math_namespace);

// The same for any list of embedded kernel headers (paths as in embedded_kernel_source), in the order given.
std::string embedded_kernel_math(const std::vector<std::string>& paths, const std::string& math_namespace);

// Spellings shared with the interval type-2 emitter (emit_type2.h), so that both write the same text.
std::string emitted_constant(double value);                   // "T(0.25)"; NaN and +-inf spelled for device code
std::string emitted_string_literal(const std::string& text);  // a C++ string literal, escaped
std::string emitted_comment_text(const std::string& text);    // fits one `//` line (no newline, no final backslash)
std::string emitted_enumerator(TNorm norm);                   // "fmpc_math::TNorm::Minimum"
std::string emitted_enumerator(SNorm norm);                   // "fmpc_math::SNorm::Maximum"
// norm(a, b) on grades, which cannot be NaN in generated code (a NaN input returns first): min and max through the
// header's grade_min / grade_max, product and sum written out, the Einstein norms through fmpc_math.
std::string emitted_tnorm_call(TNorm norm, const std::string& a, const std::string& b);
std::string emitted_snorm_call(SNorm norm, const std::string& a, const std::string& b);
// A Sugeno rule's output value: c, or p1 x1 + ... + pn xn + c summed left to right (the interpreter's
// sugeno_rule_value), over the inputs x0 .. x(input_count - 1); NaN for a malformed consequent. Zero coefficients
// are kept: 0 * inf is NaN there too.
std::string emitted_sugeno_value(const MembershipFunction& mf, std::size_t input_count);

// A rule's consequent clause on one output, in rule order.
struct EmittedConsequent {
  std::size_t rule = 0;
  const Clause* clause = nullptr;
};
std::vector<EmittedConsequent> consequents_on_output(const FuzzySystem& system, std::size_t output);

// The `#line` directives around a rule's code: one to the rule's line in the rule file, and after the code one
// back to the header (where the options name a source and a header path). Each returns the directive, or "".
class LineDirectives {
 public:
  explicit LineDirectives(const EmitOptions& options) : options_(options) {}
  std::string to_rule(const SourceRange& range);
  // `lines_written`: the header lines before this directive (#line N names the line after the directive).
  std::string back_to_header(int lines_written);

 private:
  const EmitOptions& options_;
  bool pending_return_ = false;
};

}  // namespace fmpc
