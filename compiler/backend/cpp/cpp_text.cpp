#include "compiler/backend/cpp/cpp_text.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>

#include "diagnostics/number_format.h"
#include "kernels/fuzzy_math.h"

namespace fmpc {

namespace {

const char* tnorm_enumerator(TNorm norm) {
  switch (norm) {
    case TNorm::Minimum: return "fmpc_math::TNorm::Minimum";
    case TNorm::Product: return "fmpc_math::TNorm::Product";
    case TNorm::EinsteinProduct: return "fmpc_math::TNorm::EinsteinProduct";
  }
  return "fmpc_math::TNorm::Minimum";
}

const char* snorm_enumerator(SNorm norm) {
  switch (norm) {
    case SNorm::Maximum: return "fmpc_math::SNorm::Maximum";
    case SNorm::ProbabilisticSum: return "fmpc_math::SNorm::ProbabilisticSum";
    case SNorm::Sum: return "fmpc_math::SNorm::Sum";
    case SNorm::EinsteinSum: return "fmpc_math::SNorm::EinsteinSum";
  }
  return "fmpc_math::SNorm::Maximum";
}

std::size_t newlines(const std::string& text) {
  return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n'));
}

}  // namespace

std::string hex64(std::uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

// Names and paths: printable ASCII or UTF-8, escaped where C++ needs it.
std::string cpp_string_literal(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (byte < 0x20 || byte == 0x7f) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\%03o", byte);
      out += escaped;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// A comment line cannot end in a backslash (it would continue onto the next line) nor hold a newline.
std::string cpp_comment_text(const std::string& text) {
  std::string out;
  for (const char c : text) out += (c == '\n' || c == '\r') ? ' ' : c;
  while (!out.empty() && (out.back() == '\\' || out.back() == ' ')) out.pop_back();
  return out;
}

// Parameters are finite after sema; the non-finite spellings keep the header compiling if a caller passes one
// anyway (HUGE_VAL is <math.h>'s double infinity, usable in device code).
std::string cpp_constant(double value) {
  if (std::isnan(value)) return "fmpc_math::fmpc_quiet_nan<T>()";
  if (std::isinf(value)) return value > 0 ? "T(HUGE_VAL)" : "T(-HUGE_VAL)";
  return "T(" + format_number(value) + ")";
}

// Minimum and maximum go through grade_min / grade_max (defined in the generated header): grades cannot be NaN
// there, because a NaN input returns before any grade is computed, and nan_min's NaN branches cost more than the
// operation. Product and sum are written out; the Einstein norms call fuzzy_math.h's tnorm / snorm.
std::string tnorm_call(TNorm norm, const std::string& a, const std::string& b) {
  switch (norm) {
    case TNorm::Minimum: return "grade_min(" + a + ", " + b + ")";
    case TNorm::Product: return "(" + a + " * " + b + ")";
    case TNorm::EinsteinProduct: break;
  }
  return std::string("fmpc_math::tnorm(") + tnorm_enumerator(norm) + ", " + a + ", " + b + ")";
}

std::string snorm_call(SNorm norm, const std::string& a, const std::string& b) {
  switch (norm) {
    case SNorm::Maximum: return "grade_max(" + a + ", " + b + ")";
    case SNorm::Sum: return "(" + a + " + " + b + ")";
    case SNorm::ProbabilisticSum:
    case SNorm::EinsteinSum: break;
  }
  return std::string("fmpc_math::snorm(") + snorm_enumerator(norm) + ", " + a + ", " + b + ")";
}

std::string membership_call(const MembershipFunction& mf, const std::string& x) {
  const char* function = nullptr;
  switch (mf.kind) {
    case MfKind::Triangle: function = "triangle"; break;
    case MfKind::Trapezoid: function = "trapezoid"; break;
    case MfKind::Gaussian: function = "gaussian"; break;
    case MfKind::Gaussian2: function = "gaussian2"; break;
    case MfKind::GeneralizedBell: function = "generalized_bell"; break;
    case MfKind::Sigmoid: function = "sigmoid"; break;
    case MfKind::DifferenceSigmoid: function = "difference_sigmoid"; break;
    case MfKind::ProductSigmoid: function = "product_sigmoid"; break;
    case MfKind::ZShape: function = "z_shape"; break;
    case MfKind::SShape: function = "s_shape"; break;
    case MfKind::PiShape: function = "pi_shape"; break;
    case MfKind::LinearS: function = "linear_s"; break;
    case MfKind::LinearZ: function = "linear_z"; break;
    case MfKind::Constant:
    case MfKind::Linear: return "fmpc_math::fmpc_quiet_nan<T>()";  // not a grade of x (sema keeps them out)
  }
  const int count = mf_param_count(mf.kind);
  if (count < 0 || mf.params.size() != static_cast<std::size_t>(count)) return "fmpc_math::fmpc_quiet_nan<T>()";
  std::string call = std::string("fmpc_math::mf::") + function + "(" + x;
  for (const double p : mf.params) call += ", " + cpp_constant(p);
  return call + ")";
}

std::string sugeno_value(const MembershipFunction& mf, std::size_t input_count) {
  if (mf.kind == MfKind::Constant)
    return mf.params.empty() ? "fmpc_math::fmpc_quiet_nan<T>()" : cpp_constant(mf.params[0]);
  if (mf.kind != MfKind::Linear || mf.params.size() != input_count + 1) return "fmpc_math::fmpc_quiet_nan<T>()";
  std::string value;
  for (std::size_t i = 0; i < input_count; ++i)
    value += (i ? " + " : "") + cpp_constant(mf.params[i]) + " * x" + std::to_string(i);
  return value.empty() ? cpp_constant(mf.params.back()) : value + " + " + cpp_constant(mf.params.back());
}

std::string no_fire_value(const FuzzySystem& system, std::size_t o) {
  switch (system.no_fire) {
    case NoFirePolicy::Midrange: return cpp_constant((system.outputs[o].min + system.outputs[o].max) / 2.0);
    case NoFirePolicy::Value: return cpp_constant(system.no_fire_value);
    case NoFirePolicy::Error: break;
  }
  return "fmpc_math::fmpc_quiet_nan<T>()";
}

std::string any_nan_test(const std::vector<std::string>& inputs) {
  std::string test;
  for (std::size_t i = 0; i < inputs.size(); ++i)
    test += (i ? " || " : "") + std::string("fmpc_math::fmpc_is_nan(") + inputs[i] + ")";
  return test;
}

std::string out_of_range_test(const FuzzySystem& system, const std::vector<std::string>& inputs) {
  std::string test;
  for (std::size_t i = 0; i < inputs.size(); ++i)
    test += (i ? " || " : "") + inputs[i] + " < " + cpp_constant(system.inputs[i].min) + " || " + inputs[i] + " > " +
            cpp_constant(system.inputs[i].max);
  return test;
}

std::vector<std::string> input_locals(std::size_t count) {
  std::vector<std::string> names;
  for (std::size_t i = 0; i < count; ++i) names.push_back("x" + std::to_string(i));
  return names;
}

std::vector<OutputConsequent> consequents_on_output(const FuzzySystem& system, std::size_t output) {
  std::vector<OutputConsequent> result;
  for (std::size_t r = 0; r < system.rules.size(); ++r)
    for (const Clause& clause : system.rules[r].consequent)
      if (clause.variable == static_cast<int>(output)) result.push_back({r, &clause});
  return result;
}

std::vector<double> consequent_samples(const FuzzySystem& system, std::size_t o, const Clause& clause,
                                       const std::vector<double>& x) {
  const MembershipFunction& mf = system.outputs[o].terms[static_cast<std::size_t>(clause.term)].mf;
  std::vector<double> grades(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    double mu = membership(mf.kind, mf.params.data(), x[k]);
    mu = apply_hedge(mu, hedge_exponent(clause.hedge));
    if (clause.negated) mu = fuzzy_not(mu);
    grades[k] = mu;
  }
  return grades;
}

void CodeWriter::line(const std::string& text) {
  text_ += text;
  text_ += '\n';
  lines_ += 1 + static_cast<int>(newlines(text));
}

void CodeWriter::block(const std::string& text) {
  text_ += text;
  lines_ += static_cast<int>(newlines(text));
}

void CodeWriter::double_table(const std::string& indent, const std::string& name,
                              const std::vector<std::vector<double>>& rows, std::size_t width, bool matrix) {
  line(indent + "FMPC_GENERATED_TABLE double " + name + (matrix ? "[" + std::to_string(rows.size()) + "]" : "") +
       "[" + std::to_string(width) + "] = {");
  for (const auto& row : rows) {
    if (matrix) line(indent + "    {");
    number_rows(indent + (matrix ? "        " : "    "), row);
    if (matrix) line(indent + "    },");
  }
  line(indent + "};");
}

void CodeWriter::number_rows(const std::string& indent, const std::vector<double>& values) {
  std::string text;
  for (std::size_t k = 0; k < values.size(); ++k) {
    text += format_number(values[k]) + ",";
    if (text.size() > 100 || k + 1 == values.size()) {
      line(indent + text);
      text.clear();
    }
  }
}

void LineDirectives::to_rule(const SourceRange& range, CodeWriter& out) {
  if (!options_.line_directives || !range.valid() || options_.source_path.empty()) return;
  pending_return_ = true;
  out.line("#line " + std::to_string(range.line) + " " + cpp_string_literal(options_.source_path));
}

void LineDirectives::back_to_header(CodeWriter& out) {
  if (!pending_return_ || options_.header_path.empty()) return;
  pending_return_ = false;
  // The directive itself is line lines() + 1; #line N names the line after it.
  out.line("#line " + std::to_string(out.lines() + 2) + " " + cpp_string_literal(options_.header_path));
}

}  // namespace fmpc
