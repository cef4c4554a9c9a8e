#pragma once
// C++ text shared by the code emitters (the type-1 and type-2 evaluators, the lane batch, the table arrays), so that
// they spell every constant, string, comment and fuzzy operation alike: the spellings, the consequents as generated
// code reads them, a writer that counts the header's lines, and the `#line` directives around each rule.
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "compiler/backend/cpp/emit_cpp.h"
#include "compiler/ir/fuzzy_system.h"
#include "diagnostics/source_range.h"

namespace fmpc {

// ---- spellings ----

std::string hex64(std::uint64_t value);                    // 16 lower-case hex digits, no prefix
std::string cpp_string_literal(const std::string& text);  // a C++ string literal, escaped
std::string cpp_comment_text(const std::string& text);    // fits one `//` line (no newline, no final backslash)
// A T-typed constant: "T(0.25)"; NaN and +-inf spelled for device code too.
std::string cpp_constant(double value);

// norm(a, b) on grades, which cannot be NaN in generated code (a NaN input returns first): min and max through the
// header's grade_min / grade_max, product and sum written out, the Einstein norms through fmpc_math.
std::string tnorm_call(TNorm norm, const std::string& a, const std::string& b);
std::string snorm_call(SNorm norm, const std::string& a, const std::string& b);
// The call of kernels/fuzzy_math.h's function for a type-1 input MF at `x` (NaN for an output-only family).
std::string membership_call(const MembershipFunction& mf, const std::string& x);
// A Sugeno rule's output value: c, or p1 x1 + ... + pn xn + c summed left to right (the interpreter's
// sugeno_rule_value), over the inputs x0 .. x(input_count - 1); NaN for a malformed consequent. Zero coefficients
// are kept: 0 * inf is NaN there too.
std::string sugeno_value(const MembershipFunction& mf, std::size_t input_count);
// The value output `o` takes when no rule fired, under the system's policy (NaN for `error`).
std::string no_fire_value(const FuzzySystem& system, std::size_t o);
// Tests over the system's inputs, each spelled as `inputs[i]` ("x0", "x[0][j]"): any of them NaN; any of them
// outside its declared range.
std::string any_nan_test(const std::vector<std::string>& inputs);
std::string out_of_range_test(const FuzzySystem& system, const std::vector<std::string>& inputs);
// "x0", "x1", ...: the locals an evaluate function reads its inputs into.
std::vector<std::string> input_locals(std::size_t count);

// ---- consequents ----

// A rule's consequent clause on one output, in rule order.
struct OutputConsequent {
  std::size_t rule = 0;
  const Clause* clause = nullptr;
};
std::vector<OutputConsequent> consequents_on_output(const FuzzySystem& system, std::size_t output);

// A type-1 consequent's grades at output `o`'s sample points `x`, hedged and negated as the interpreter does;
// computed in double at emit time, so that generated code holds constants instead of output membership functions.
std::vector<double> consequent_samples(const FuzzySystem& system, std::size_t o, const Clause& clause,
                                       const std::vector<double>& x);

// ---- writing ----

// Writes lines and counts them, so that `#line` directives can point back into the header itself.
class CodeWriter {
 public:
  explicit CodeWriter(int lines_before = 0) : lines_(lines_before) {}
  void line(const std::string& text = {});
  void block(const std::string& text);  // text ending in a newline
  // A table of constants, in double whatever T is (a float table could not hold grades below float's range as
  // constant expressions, which nvcc rejects); the code converts each element where it reads it. A matrix is
  // `name[rows][width]`, a vector (one row, `matrix` false) `name[width]`; elements past a row's end are 0.
  void double_table(const std::string& indent, const std::string& name, const std::vector<std::vector<double>>& rows,
                    std::size_t width, bool matrix);
  // An initialiser's numbers, "v," each, in lines of about 100 characters after `indent`.
  void number_rows(const std::string& indent, const std::vector<double>& values);
  int lines() const { return lines_; }
  const std::string& text() const { return text_; }

 private:
  std::string text_;
  int lines_ = 0;
};

// The `#line` directives around a rule's code: one to the rule's line in the rule file, and after the code one
// back to the header (where the options name a source and a header path).
class LineDirectives {
 public:
  explicit LineDirectives(const EmitOptions& options) : options_(options) {}
  void to_rule(const SourceRange& range, CodeWriter& out);
  void back_to_header(CodeWriter& out);

 private:
  const EmitOptions& options_;
  bool pending_return_ = false;
};

}  // namespace fmpc
