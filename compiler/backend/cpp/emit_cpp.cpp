#include "compiler/backend/cpp/emit_cpp.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "compiler/backend/cpp/embedded_kernels.h"
#include "compiler/backend/cpp/emit_type2.h"
#include "compiler/backend/cpp/namespace_name.h"
#include "compiler/eval/defuzzify.h"
#include "compiler/ir/content_hash.h"
#include "diagnostics/number_format.h"
#include "kernels/fuzzy_math.h"

namespace fmpc {

namespace {

// The kernel headers a generated header carries, in dependency order.
constexpr const char* kEmbeddedMathFiles[] = {"kernels/fmpc_hd.h", "kernels/fuzzy_kinds.h", "kernels/fuzzy_math.h"};

std::string hex64(std::uint64_t value) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
  return text;
}

// A C++ string literal holding `text` (names, paths: printable ASCII or UTF-8, escaped where C++ needs it).
std::string quoted(const std::string& text) {
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
std::string comment_safe(const std::string& text) {
  std::string out;
  for (const char c : text) out += (c == '\n' || c == '\r') ? ' ' : c;
  while (!out.empty() && (out.back() == '\\' || out.back() == ' ')) out.pop_back();
  return out;
}

// A T-typed constant. Parameters are finite after sema; the non-finite spellings keep the header compiling if a
// caller passes one anyway (HUGE_VAL is <math.h>'s double infinity, usable in device code).
std::string constant(double value) {
  if (std::isnan(value)) return "fmpc_math::fmpc_quiet_nan<T>()";
  if (std::isinf(value)) return value > 0 ? "T(HUGE_VAL)" : "T(-HUGE_VAL)";
  return "T(" + format_number(value) + ")";
}

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

// The call of the kernels/fuzzy_math.h function for a type-1 input MF at `x`.
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
  for (const double p : mf.params) call += ", " + constant(p);
  return call + ")";
}

// Writes lines and counts them, so that `#line` directives can point back into the header itself.
class CodeWriter {
 public:
  void line(const std::string& text = {}) {
    text_ += text;
    text_ += '\n';
    lines_ += 1 + static_cast<int>(std::count(text.begin(), text.end(), '\n'));
  }
  void block(const std::string& text) {
    text_ += text;
    lines_ += static_cast<int>(std::count(text.begin(), text.end(), '\n'));
  }
  int lines() const { return lines_; }
  const std::string& text() const { return text_; }

 private:
  std::string text_;
  int lines_ = 0;
};

// The lines that give output `o` its no-rule-fired value (the system's policy): `target` takes the value and
// `flags` the kFlag* bits.
std::vector<std::string> no_fire_lines(const FuzzySystem& system, std::size_t o, const std::string& target,
                                       const std::string& flags) {
  std::vector<std::string> lines{flags + " |= kFlagNoRuleFired;"};
  switch (system.no_fire) {
    case NoFirePolicy::Midrange:
      lines.push_back(target + " = " + constant((system.outputs[o].min + system.outputs[o].max) / 2.0) + ";");
      break;
    case NoFirePolicy::Value: lines.push_back(target + " = " + constant(system.no_fire_value) + ";"); break;
    case NoFirePolicy::Error:
      lines.push_back(target + " = fmpc_math::fmpc_quiet_nan<T>();");
      lines.push_back(flags + " |= kFlagNoFireError;");
      break;
  }
  return lines;
}

// A consequent's grades at output `o`'s sample points `x`, hedged and negated as the interpreter does; computed
// here in double, so the generated code holds constants instead of output membership functions.
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

// The per-rule and per-output state the emitter derives from the system once.
struct RulePlan {
  std::vector<Clause> antecedent;  // sorted by input, the interpreter's fold order
};

class EvaluatorEmitter {
 public:
  EvaluatorEmitter(const FuzzySystem& system, const EmitOptions& options, CodeWriter& out)
      : system_(system), options_(options), out_(out) {}

  void emit_evaluate_function() {
    const std::size_t input_count = system_.inputs.size();
    const std::size_t output_count = system_.outputs.size();
    out_.line("// Evaluates the system at inputs[0 .. kInputCount) into outputs[0 .. kOutputCount) and returns the");
    out_.line("// kFlag* bits of what happened. T is float or double; every formula is the interpreter's");
    out_.line("// (fmpc eval), so double agrees with it to rounding.");
    out_.line("template <typename T>");
    out_.line("FMPC_HD unsigned evaluate(const T* inputs, T* outputs) {");
    if (input_count == 0) out_.line("  (void)inputs;");
    for (std::size_t i = 0; i < input_count; ++i)
      out_.line("  const T x" + std::to_string(i) + " = inputs[" + std::to_string(i) + "];  // " +
                comment_safe(system_.inputs[i].name));
    // A NaN input makes every output NaN (docs/numerics.md): never a silent number.
    if (input_count > 0) {
      std::string test;
      for (std::size_t i = 0; i < input_count; ++i)
        test += (i ? " || " : "") + std::string("fmpc_math::fmpc_is_nan(x") + std::to_string(i) + ")";
      out_.line("  if (" + test + ") {");
      for (std::size_t o = 0; o < output_count; ++o)
        out_.line("    outputs[" + std::to_string(o) + "] = fmpc_math::fmpc_quiet_nan<T>();");
      out_.line("    return kFlagNanInput;");
      out_.line("  }");
    }
    out_.line("  unsigned flags = 0u;");
    if (input_count > 0) {
      std::string test;
      for (std::size_t i = 0; i < input_count; ++i) {
        const std::string x = "x" + std::to_string(i);
        test += (i ? " || " : "") + x + " < " + constant(system_.inputs[i].min) + " || " + x + " > " +
                constant(system_.inputs[i].max);
      }
      out_.line("  if (" + test + ") flags |= kFlagInputOutOfRange;");
    }
    plan_rules();
    emit_firing_strengths();
    for (std::size_t o = 0; o < output_count; ++o) {
      if (system_.type == SystemType::Mamdani) emit_mamdani_output(o);
      else emit_sugeno_output(o);
    }
    out_.line("  return flags;");
    out_.line("}");
  }

 private:
  void line_directive(const SourceRange& range) {
    const std::string directive = directives_.to_rule(range);
    if (!directive.empty()) out_.line(directive);
  }
  void return_to_header() {
    const std::string directive = directives_.back_to_header(out_.lines());
    if (!directive.empty()) out_.line(directive);
  }

  void plan_rules() {
    plans_.resize(system_.rules.size());
    for (std::size_t r = 0; r < system_.rules.size(); ++r) {
      plans_[r].antecedent = system_.rules[r].antecedent;
      std::stable_sort(plans_[r].antecedent.begin(), plans_[r].antecedent.end(),
                       [](const Clause& a, const Clause& b) { return a.variable < b.variable; });
    }
  }

  // The local holding the grade of input `i` in term `t`, emitted at first use (each term is evaluated once
  // however many rules name it).
  std::string term_grade(int i, int t) {
    const std::string name = "mu" + std::to_string(i) + "_" + std::to_string(t);
    if (emitted_.insert(name).second) {
      const Term& term = system_.inputs[static_cast<std::size_t>(i)].terms[static_cast<std::size_t>(t)];
      out_.line("  const T " + name + " = " + membership_call(term.mf, "x" + std::to_string(i)) + ";  // " +
                comment_safe(system_.inputs[static_cast<std::size_t>(i)].name + " is " + term.name));
    }
    return name;
  }

  // The clause grade: hedge first, then negation (interpreter's clause_grade).
  std::string clause_grade(const Clause& clause) {
    std::string grade = term_grade(clause.variable, clause.term);
    if (clause.hedge == Hedge::None && !clause.negated) return grade;
    const std::string name = grade + "_h" + std::to_string(static_cast<int>(clause.hedge)) +
                             (clause.negated ? "_not" : "");
    if (emitted_.insert(name).second) {
      std::string value = grade;
      if (clause.hedge != Hedge::None)
        value = "fmpc_math::apply_hedge(" + value + ", " + constant(hedge_exponent(clause.hedge)) + ")";
      if (clause.negated) value = "fmpc_math::fuzzy_not(" + value + ")";
      out_.line("  const T " + name + " = " + value + ";");
    }
    return name;
  }

  // Antecedents fold clause by clause in input order from the norm's identity. Rules that share a prefix of
  // clauses share its partial result (a trie over the sorted clauses): the fold order, and so every rounding, is
  // the interpreter's. Folding the first clause into the identity is skipped where it is exact for grades in
  // [0, 1]: min(1, g) = 1 g = max(0, g) = 0 + g - 0 g = g, and (0 + g) / (1 + 0 g) = g.
  // A grade folded in by the specialize pass (Rule::folded_grade) starts the fold instead of the identity.
  std::string antecedent_strength(const Rule& rule, const RulePlan& plan) {
    const bool conjunction = rule.connective == Connective::And;
    const std::string start = rule.folded_grade ? constant(*rule.folded_grade) : conjunction ? "T(1)" : "T(0)";
    if (plan.antecedent.empty()) return start;
    std::string value;
    for (std::size_t c = 0; c < plan.antecedent.size(); ++c) {
      const std::string grade = clause_grade(plan.antecedent[c]);
      if (c == 0 && !rule.folded_grade && !(conjunction && system_.and_method == TNorm::EinsteinProduct)) {
        value = grade;
        continue;
      }
      const std::string previous = c == 0 ? start : value;
      const std::string key = (conjunction ? "and|" : "or|") + previous + "|" + grade;
      auto found = trie_.find(key);
      if (found == trie_.end()) {
        const std::string name = "s" + std::to_string(trie_.size());
        out_.line("  const T " + name + " = " +
                  (conjunction ? tnorm_call(system_.and_method, previous, grade)
                               : snorm_call(system_.or_method, previous, grade)) +
                  ";");
        found = trie_.emplace(key, name).first;
      }
      value = found->second;
    }
    return value;
  }

  void emit_firing_strengths() {
    firing_.resize(system_.rules.size());
    for (std::size_t r = 0; r < system_.rules.size(); ++r) {
      const Rule& rule = system_.rules[r];
      out_.line("  // " + comment_safe(system_.rule_display_name(r)));
      line_directive(rule.range);
      const std::string strength = antecedent_strength(rule, plans_[r]);
      const std::string name = "w" + std::to_string(r);
      // firing = weight * strength (interpreter); 1 * s == s exactly.
      if (rule.weight == 1.0) out_.line("  const T " + name + " = " + strength + ";");
      else out_.line("  const T " + name + " = " + constant(rule.weight) + " * " + strength + ";");
      firing_[r] = name;
      return_to_header();
    }
  }

  void emit_no_fire(std::size_t o, const std::string& indent) {
    for (const std::string& text : no_fire_lines(system_, o, "outputs[" + std::to_string(o) + "]", "flags"))
      out_.line(indent + text);
  }

  // A table of constants, in double whatever T is (a float table could not hold grades below float's range as
  // constant expressions, which nvcc rejects); the code converts each element where it reads it. Static in host
  // code (one copy in read-only data); a plain local in device code, where unrolled loops fold it into immediates.
  void emit_table(const std::string& indent, const std::string& name, const std::vector<std::vector<double>>& rows,
                  std::size_t width) {
    const bool matrix = rows.size() > 1;
    out_.line(indent + "FMPC_GENERATED_TABLE double " + name +
              (matrix ? "[" + std::to_string(rows.size()) + "]" : "") + "[" + std::to_string(width) + "] = {");
    for (const auto& row : rows) {
      if (matrix) out_.line(indent + "    {");
      std::string text;
      for (std::size_t k = 0; k < row.size(); ++k) {
        text += format_number(row[k]) + ",";
        if (text.size() > 100 || k + 1 == row.size()) {
          out_.line(indent + (matrix ? "        " : "    ") + text);
          text.clear();
        }
      }
      if (matrix) out_.line(indent + "    },");
    }
    out_.line(indent + "};");
  }

  void emit_mamdani_output(std::size_t o) {
    const Variable& output = system_.outputs[o];
    const std::string os = std::to_string(o);
    const std::vector<double> x =
        output_sample_points(output.min, output.max, system_.samples, Reference::Matlab);
    const std::string n = std::to_string(x.size());
    // The sample loops run over a multiple of 8 so that compilers vectorise them without a remainder loop; the
    // padding grades are 0, which add exactly nothing.
    const std::size_t padded = (x.size() + 7) / 8 * 8;
    const std::string np = std::to_string(padded);
    const std::vector<EmittedConsequent> consequents = consequents_on_output(system_, o);
    out_.line("  // output " + comment_safe(output.name) + ": " + n + " samples of the aggregate, then " +
              to_string(system_.defuzzifier));
    out_.line("  {");

    // Weighted columns of the aggregate: (strength, grades at the samples). With max aggregation and min or prod
    // implication, rules with the same consequent merge exactly into one column of strength max(w):
    // max(min(w1, g), min(w2, g)) = min(max(w1, w2), g), and the same for w g with g >= 0 (rounding is monotone).
    std::vector<std::string> strengths;
    std::vector<std::vector<double>> grades;
    const bool merge = system_.aggregation == SNorm::Maximum &&
                       (system_.implication == TNorm::Minimum || system_.implication == TNorm::Product);
    std::map<std::pair<int, std::pair<int, bool>>, std::size_t> column_of_consequent;
    for (const EmittedConsequent& consequent : consequents) {
      const std::string& w = firing_[consequent.rule];
      const auto key = std::make_pair(consequent.clause->term,
                                      std::make_pair(static_cast<int>(consequent.clause->hedge),
                                                     consequent.clause->negated));
      if (merge) {
        const auto found = column_of_consequent.find(key);
        if (found != column_of_consequent.end()) {
          std::string& strength = strengths[found->second];
          const std::string merged = "m" + os + "_" + std::to_string(merged_count_++);
          out_.line("    const T " + merged + " = grade_max(" + strength + ", " + w + ");");
          strength = merged;
          continue;
        }
        column_of_consequent.emplace(key, strengths.size());
      }
      strengths.push_back(w);
      grades.push_back(consequent_samples(system_, o, *consequent.clause, x));
    }
    // A rule fired when its strength is above zero; merged strengths are maxima, so testing them is the same.
    std::string fired;
    for (const std::string& strength : strengths)
      fired += (fired.empty() ? "(" : " | (") + strength + " > T(0))";
    out_.line("    const bool fired = " + (fired.empty() ? std::string("false") : fired) + ";");

    // g_k = aggregation over the columns of implication(strength, grade_k), the first column taken as is
    // (aggregation(0, v) == v for v >= 0). Zero grades need no special case: implication(w, 0) == 0 for every
    // t-norm and aggregation(a, 0) == a for every s-norm, exactly.
    out_.line("    T g[" + np + "];");
    if (strengths.empty()) {
      out_.line("    for (int k = 0; k < " + np + "; ++k) g[k] = T(0);");
    } else {
      emit_table("    ", "kGrades", grades, padded);
      std::string list;
      for (const std::string& strength : strengths) list += (list.empty() ? "" : ", ") + strength;
      out_.line("    const T strength[" + std::to_string(strengths.size()) + "] = {" + list + "};");
      const bool single = strengths.size() == 1;
      out_.line("    FMPC_GENERATED_UNROLL");
      out_.line("    for (int k = 0; k < " + np + "; ++k) {");
      for (std::size_t c = 0; c < strengths.size(); ++c) {
        const std::string cs = std::to_string(c);
        const std::string term = tnorm_call(system_.implication, "strength[" + cs + "]",
                                            single ? "T(kGrades[k])" : "T(kGrades[" + cs + "][k])");
        if (c == 0) out_.line("      T value = " + term + ";");
        else out_.line("      value = " + snorm_call(system_.aggregation, "value", term) + ";");
      }
      out_.line("      g[k] = value;");
      out_.line("    }");
    }
    if (system_.defuzzifier == Defuzzifier::Centroid) {
      // sum(g x) / sum(g) (MATLAB fis.c defuzzCentroid), with x measured from the middle of the range: the same
      // value, but float keeps its precision when the range is narrow compared with its distance from 0. Four
      // partial sums break the chain of dependent additions (and differ from one sum by rounding only).
      const double middle = (output.min + output.max) / 2.0;
      std::vector<double> offsets(x.size());
      for (std::size_t k = 0; k < x.size(); ++k) offsets[k] = x[k] - middle;
      emit_table("    ", "kOffsets", {offsets}, padded);
      out_.line("    T total0 = T(0), total1 = T(0), total2 = T(0), total3 = T(0);");
      out_.line("    T moment0 = T(0), moment1 = T(0), moment2 = T(0), moment3 = T(0);");
      out_.line("    FMPC_GENERATED_UNROLL");
      out_.line("    for (int k = 0; k < " + np + "; k += 4) {");
      for (int j = 0; j < 4; ++j) {
        const std::string js = std::to_string(j);
        const std::string at = j == 0 ? std::string("k") : "k + " + js;
        out_.line("      total" + js + " += g[" + at + "];");
        out_.line("      moment" + js + " += g[" + at + "] * T(kOffsets[" + at + "]);");
      }
      out_.line("    }");
      out_.line("    const T total = (total0 + total1) + (total2 + total3);");
      out_.line("    const T moment = (moment0 + moment1) + (moment2 + moment3);");
      out_.line("    if (!fired || total == T(0)) {");
      emit_no_fire(o, "      ");
      out_.line("    } else {");
      out_.line("      outputs[" + os + "] = " + constant(middle) + " + moment / total;");
      out_.line("    }");
    } else {
      emit_sampled_defuzzifier(o, x);
    }
    out_.line("  }");
  }

  // Bisector, mom, som and lom over g[], as compiler/eval/defuzzify.cpp defuzzify_sampled does for MATLAB.
  void emit_sampled_defuzzifier(std::size_t o, const std::vector<double>& x) {
    const std::string n = std::to_string(x.size());
    const std::string target = "outputs[" + std::to_string(o) + "]";
    emit_table("    ", "kSamplePoints", {x}, x.size());
    out_.line("    T total = T(0), peak = g[0];");
    out_.line("    for (int k = 0; k < " + n + "; ++k) {");
    out_.line("      total += g[k];");
    out_.line("      peak = peak > g[k] ? peak : g[k];");
    out_.line("    }");
    out_.line("    if (!fired || total == T(0)) {");
    emit_no_fire(o, "      ");
    out_.line("    } else {");
    switch (system_.defuzzifier) {
      case Defuzzifier::Bisector:
        // The first sample where the running sum reaches half the total.
        out_.line("      T running = T(0), value = T(kSamplePoints[" + std::to_string(x.size() - 1) + "]);");
        out_.line("      for (int k = 0; k < " + n + "; ++k) {");
        out_.line("        running += g[k];");
        out_.line("        if (running >= total / T(2)) { value = T(kSamplePoints[k]); break; }");
        out_.line("      }");
        out_.line("      " + target + " = value;");
        break;
      case Defuzzifier::MeanOfMaximum:
        out_.line("      T sum = T(0);");
        out_.line("      int count = 0;");
        out_.line("      for (int k = 0; k < " + n + "; ++k)");
        out_.line("        if (g[k] == peak) { sum += T(kSamplePoints[k]); ++count; }");
        out_.line("      " + target + " = sum / T(count);");
        break;
      case Defuzzifier::SmallestOfMaximum:
      case Defuzzifier::LargestOfMaximum: {
        // MATLAB: the maximising x of smallest (largest) magnitude, the first one on ties.
        const char* better = system_.defuzzifier == Defuzzifier::SmallestOfMaximum ? "<" : ">";
        out_.line("      bool found = false;");
        out_.line("      T best = T(0);");
        out_.line("      for (int k = 0; k < " + n + "; ++k) {");
        out_.line("        if (g[k] != peak) continue;");
        out_.line("        const T candidate = T(kSamplePoints[k]);");
        out_.line(std::string("        if (!found || fmpc_math::fmpc_fabs(candidate) ") + better +
                  " fmpc_math::fmpc_fabs(best)) best = candidate;");
        out_.line("        found = true;");
        out_.line("      }");
        out_.line("      " + target + " = best;");
        break;
      }
      case Defuzzifier::Centroid:
      case Defuzzifier::WeightedAverage:
      case Defuzzifier::WeightedSum: out_.line("      " + target + " = fmpc_math::fmpc_quiet_nan<T>();"); break;
    }
    out_.line("    }");
  }

  // MATLAB fis.c fisEvaluate: sum(h z) / sum(h) over the rules that fired, where the denominator also counts the
  // firing strengths of the rules with no consequent on this output; wtsum is the numerator alone.
  void emit_sugeno_output(std::size_t o) {
    const Variable& output = system_.outputs[o];
    const std::vector<EmittedConsequent> consequents = consequents_on_output(system_, o);
    out_.line("  // output " + comment_safe(output.name) + ": " + to_string(system_.defuzzifier));
    out_.line("  {");
    out_.line("    T numerator = T(0), denominator = T(0);");
    out_.line("    bool fired = false;");
    std::vector<bool> concludes(system_.rules.size(), false);
    for (const EmittedConsequent& consequent : consequents) {
      concludes[consequent.rule] = true;
      const std::string& w = firing_[consequent.rule];
      const Clause& clause = *consequent.clause;
      std::string height = w;
      // Octave's eval_rules_sugeno hedges the height as w^(1/hedge), then negates it (interpreter).
      if (clause.hedge != Hedge::None)
        height = "fmpc_math::fmpc_pow(" + height + ", " + constant(1.0 / hedge_exponent(clause.hedge)) + ")";
      if (clause.negated) height = "fmpc_math::fuzzy_not(" + height + ")";
      const MembershipFunction& mf = output.terms[static_cast<std::size_t>(clause.term)].mf;
      out_.line("    if (" + w + " != T(0)) {");
      out_.line("      const T h = " + height + ";");
      out_.line("      numerator += h * (" + emitted_sugeno_value(mf, system_.inputs.size()) + ");");
      out_.line("      denominator += h;");
      out_.line("      fired = fired || h != T(0);");
      out_.line("    }");
    }
    if (system_.defuzzifier != Defuzzifier::WeightedSum)
      for (std::size_t r = 0; r < system_.rules.size(); ++r)
        if (!concludes[r]) out_.line("    denominator += " + firing_[r] + ";");
    out_.line("    if (!fired || denominator == T(0)) {");
    emit_no_fire(o, "      ");
    out_.line("    } else {");
    out_.line("      outputs[" + std::to_string(o) + "] = " +
              (system_.defuzzifier == Defuzzifier::WeightedSum ? "numerator" : "numerator / denominator") + ";");
    out_.line("    }");
    out_.line("  }");
  }

  const FuzzySystem& system_;
  const EmitOptions& options_;
  CodeWriter& out_;
  std::vector<RulePlan> plans_;
  std::vector<std::string> firing_;
  std::set<std::string> emitted_;
  std::map<std::string, std::string> trie_;
  std::size_t merged_count_ = 0;
  LineDirectives directives_{options_};
};

// ---- evaluate_batch over blocks of lanes ----
//
// For Mamdani systems that defuzzify by centroid with max aggregation and min or product implication (MATLAB's
// defaults, the liver's kind), evaluate_batch takes the points in blocks of kBatchLanes and runs every step as a
// loop over the block's lanes on structure-of-arrays locals, which compilers vectorise (GCC: -O2
// -ftree-vectorize or -O3; docs/codegen.md "Batch evaluation"). Other systems keep a loop over evaluate().

// The consequents of output `o` that share a column of the aggregate: same term, hedge and negation.
using ColumnKey = std::tuple<int, int, bool>;
ColumnKey column_key(const Clause& clause) {
  return {clause.term, static_cast<int>(clause.hedge), clause.negated};
}

// Unrolled aggregation costs (columns x samples) statements; beyond this the header would be too long to compile
// quickly, and evaluate_batch keeps the loop over evaluate().
constexpr std::size_t kMaxUnrolledAggregation = 16384;

bool lane_batch_applies(const FuzzySystem& system) {
  if (system.interval_type2 || system.type != SystemType::Mamdani || system.defuzzifier != Defuzzifier::Centroid ||
      system.samples <= 0 || system.aggregation != SNorm::Maximum ||
      (system.implication != TNorm::Minimum && system.implication != TNorm::Product) || system.inputs.empty() ||
      system.outputs.empty())
    return false;
  std::size_t statements = 0;
  for (std::size_t o = 0; o < system.outputs.size(); ++o) {
    std::set<ColumnKey> columns;
    for (const Rule& rule : system.rules)
      for (const Clause& clause : rule.consequent)
        if (clause.variable == static_cast<int>(o)) columns.insert(column_key(clause));
    statements += columns.size() * static_cast<std::size_t>(system.samples);
  }
  return statements <= kMaxUnrolledAggregation;
}

// evaluate_batch's two shortcuts, which evaluate() does not take. lane_exp returns 0 below its `lowest`, where
// exp is below these (exp(-708), float exp(-86)), so that no lane computes a subnormal (slow on x86); and the
// aggregation leaves out consequent grades of at most kDroppedGrade (the liver: 210 of 357 remain), which is also
// above float's smallest normal, so that the grades read in float are normal numbers too.
constexpr double kLaneExpFlushedDouble = 3.31e-308;
constexpr double kLaneExpFlushedFloat = 4.48e-38;
constexpr double kDroppedGrade = 1e-36;

// The smallest aggregate total (sum of g_k over the samples) for which the shortcuts move a centroid by at most
// `relative_error` of the output range; evaluate_batch sends points with a smaller total to evaluate().
// Bound: a flushed input grade (below `flushed`) moves a clause grade by at most flushed^p under a hedge of
// exponent p < 1 (x^p is not Lipschitz at 0), p flushed otherwise, and `not` by as much; a rule's strength moves
// by at most the sum over its clauses (min, max, product, probabilistic sum and the Einstein norms have partial
// derivatives of at most 1 on grades; the factor 2 is margin), times its weight; implication min or product and
// max aggregation move g_k by at most the largest strength change, and a left-out grade g by at most g. A change of
// at most d in every g_k moves sum(g (x - middle)) by n d R / 2 and sum(g) by n d, so the centroid by at most
// n d R / total_true, and total_true >= floor / 2 where the computed total is at least floor = 2 n d / relative.
double lane_total_floor(const FuzzySystem& system, double flushed, double relative_error, double smallest) {
  double strength_change = 0.0;
  for (const Rule& rule : system.rules) {
    double clause_change = 0.0;
    for (const Clause& clause : rule.antecedent) {
      const double p = hedge_exponent(clause.hedge);
      clause_change = std::max(clause_change, p < 1.0 ? std::pow(flushed, p) : p * flushed);
    }
    strength_change = std::max(strength_change, 2.0 * static_cast<double>(rule.antecedent.size()) * clause_change *
                                                    std::max(1.0, rule.weight));
  }
  const double n = static_cast<double>(std::max(system.samples, 1));
  const double floor = std::max(smallest, 2.0 * n * (strength_change + kDroppedGrade) / relative_error);
  // Rounded up to one significant digit, so that the header reads 3e-19 rather than 2.0199999999999997e-19.
  const double unit = std::pow(10.0, std::floor(std::log10(floor)));
  return std::ceil(floor / unit) * unit;
}

class LaneBatchEmitter {
 public:
  LaneBatchEmitter(const FuzzySystem& system, CodeWriter& out) : system_(system), out_(out) {}

  void emit() {
    std::vector<OutputPlan> plans;
    for (std::size_t o = 0; o < system_.outputs.size(); ++o) plans.push_back(plan_output(o));
    for (std::size_t o = 0; o < plans.size(); ++o) emit_aggregation(o, plans[o]);

    const std::size_t input_count = system_.inputs.size();
    // The consequent grades the aggregation reads, in its order. Read through a volatile, once per call, so that
    // compilers cannot see the values: with constants, GCC threads jumps through the chain of min(w, grade)
    // comparisons (w < 0.5 implies w < 0.9), and the branches it creates stop it vectorising the lane loop.
    for (std::size_t o = 0; o < plans.size(); ++o) {
      const std::vector<double>& values = aggregation_grades_[o];
      if (values.empty()) continue;
      out_.line("inline const volatile double kLaneGrades" + std::to_string(o) + "[" + std::to_string(values.size()) +
                "] = {");
      std::string text;
      for (std::size_t k = 0; k < values.size(); ++k) {
        text += format_number(values[k]) + ",";
        if (text.size() > 100 || k + 1 == values.size()) {
          out_.line("    " + text);
          text.clear();
        }
      }
      out_.line("};");
      out_.line();
    }
    out_.line("// Evaluates n points (inputs n x kInputCount, outputs n x kOutputCount, row-major) with evaluate()'s");
    out_.line("// results and flags (double within 1e-12 of the output range, float within 1e-5; lane_exp is not the");
    out_.line("// C library's exp). Blocks of kBatchLanes points; each loop over j runs one step for every lane.");
    out_.line("template <typename T>");
    out_.line("FMPC_GENERATED_BATCH_CLONES");
    out_.line("inline void evaluate_batch(const T* inputs, T* outputs, std::size_t n, unsigned* flags = nullptr) {");
    if (uses_lane_exp_) out_.line("  const T lowest = lane_exp_lowest(T(0));");
    // The smallest aggregate total for which the shortcuts (grades flushed to 0 by lane_exp, consequent grades
    // left out) move the centroid by less than 1e-15 of the output range (float: 1e-8); see lane_total_floor.
    out_.line("  const T total_floor = sizeof(T) < sizeof(double) ? T(" +
              format_number(lane_total_floor(system_, kLaneExpFlushedFloat, 1e-8, 1e-30)) + ") : T(" +
              format_number(lane_total_floor(system_, kLaneExpFlushedDouble, 1e-15, 1e-300)) + ");");
    for (std::size_t o = 0; o < plans.size(); ++o) {
      const std::size_t count = aggregation_grades_[o].size();
      if (count == 0) continue;
      const std::string os = std::to_string(o), cs = std::to_string(count);
      out_.line("  T grades" + os + "[" + cs + "];");
      out_.line("  for (std::size_t k = 0; k < " + cs + "; ++k) grades" + os + "[k] = T(kLaneGrades" + os + "[k]);");
    }
    out_.line("  for (std::size_t start = 0; start < n; start += kBatchLanes) {");
    out_.line("    const std::size_t count = n - start < kBatchLanes ? n - start : kBatchLanes;");
    out_.line("    // The block's inputs, one row per input; lanes past the last point repeat it.");
    out_.line("    T x[kInputCount][kBatchLanes];");
    out_.line("    for (std::size_t j = 0; j < kBatchLanes; ++j) {");
    out_.line("      const T* point = inputs + (start + (j < count ? j : count - 1)) * kInputCount;");
    out_.line("      for (std::size_t i = 0; i < kInputCount; ++i) x[i][j] = point[i];");
    out_.line("    }");
    for (const std::string& text : grade_lines_) out_.line("    " + text);
    std::string results;
    for (std::size_t o = 0; o < plans.size(); ++o) {
      const std::string os = std::to_string(o);
      results += (o ? ", " : "") + std::string("value") + os + "[kBatchLanes], total" + os + "[kBatchLanes]";
    }
    out_.line("    T " + results + ";");
    out_.line("    for (std::size_t j = 0; j < kBatchLanes; ++j) {");
    for (const std::string& text : body_lines_) out_.line("      " + text);
    out_.line("    }");
    // Point by point: NaN inputs, and aggregates too small for the shortcuts (which include every point where no
    // rule fired), go through evaluate(); the others take the lanes' values and the out-of-range flag.
    out_.line("    for (std::size_t j = 0; j < count; ++j) {");
    out_.line("      T* y = outputs + (start + j) * kOutputCount;");
    out_.line("      unsigned f = 0u;");
    std::string slow_test, range_test;
    for (std::size_t i = 0; i < input_count; ++i) {
      const std::string xi = "x[" + std::to_string(i) + "][j]";
      slow_test += (i ? " || " : "") + std::string("fmpc_math::fmpc_is_nan(") + xi + ")";
      range_test += (i ? " || " : "") + xi + " < " + constant(system_.inputs[i].min) + " || " + xi + " > " +
                    constant(system_.inputs[i].max);
    }
    for (std::size_t o = 0; o < plans.size(); ++o)
      slow_test += " || !(total" + std::to_string(o) + "[j] >= total_floor)";
    out_.line("      if (" + slow_test + ") {");
    out_.line("        f = evaluate(inputs + (start + j) * kInputCount, y);");
    out_.line("      } else {");
    out_.line("        if (" + range_test + ") f = kFlagInputOutOfRange;");
    for (std::size_t o = 0; o < plans.size(); ++o)
      out_.line("        y[" + std::to_string(o) + "] = value" + std::to_string(o) + "[j];");
    out_.line("      }");
    out_.line("      if (flags != nullptr) flags[start + j] = f;");
    out_.line("    }");
    out_.line("  }");
    out_.line("}");
  }

 private:
  struct OutputPlan {
    std::vector<std::string> strengths;           // one per column: max over its rules' firing strengths
    std::vector<std::vector<double>> grades;      // the column's consequent grades at the sample points
  };

  // The array holding the grade of clause `clause` for every lane of the block, computed once per block (named
  // in the lane loop as `name[j]`). Gaussians go through lane_gaussian; the other families call the embedded
  // math (a loop that compilers may leave scalar, which costs speed, not accuracy).
  std::string clause_grade(const Clause& clause) {
    const std::string base = "mu" + std::to_string(clause.variable) + "_" + std::to_string(clause.term);
    if (emitted_arrays_.insert(base).second) {
      const Variable& input = system_.inputs[static_cast<std::size_t>(clause.variable)];
      const MembershipFunction& mf = input.terms[static_cast<std::size_t>(clause.term)].mf;
      const std::string x = "x[" + std::to_string(clause.variable) + "][j]";
      std::string value;
      if (mf.kind == MfKind::Gaussian && mf.params.size() == 2) {
        value = "lane_gaussian(" + x + ", " + constant(mf.params[0]) + ", " + constant(mf.params[1]) + ", lowest)";
        uses_lane_exp_ = true;
      } else {
        value = membership_call(mf, x);
      }
      const Term& term = input.terms[static_cast<std::size_t>(clause.term)];
      grade_lines_.push_back("T " + base + "[kBatchLanes];  // " + comment_safe(input.name + " is " + term.name));
      grade_lines_.push_back("for (std::size_t j = 0; j < kBatchLanes; ++j) " + base + "[j] = " + value + ";");
    }
    if (clause.hedge == Hedge::None && !clause.negated) return base + "[j]";
    // Hedge first, then negation (interpreter's clause_grade).
    const std::string name =
        base + "_h" + std::to_string(static_cast<int>(clause.hedge)) + (clause.negated ? "_not" : "");
    if (emitted_arrays_.insert(name).second) {
      std::string value = base + "[j]";
      if (clause.hedge != Hedge::None)
        value = "fmpc_math::apply_hedge(" + value + ", " + constant(hedge_exponent(clause.hedge)) + ")";
      if (clause.negated) value = "fmpc_math::fuzzy_not(" + value + ")";
      grade_lines_.push_back("T " + name + "[kBatchLanes];");
      grade_lines_.push_back("for (std::size_t j = 0; j < kBatchLanes; ++j) " + name + "[j] = " + value + ";");
    }
    return name + "[j]";
  }

  int literal(const std::string& text) {
    const auto found = literal_ids_.find(text);
    if (found != literal_ids_.end()) return found->second;
    literal_texts_.push_back(text);
    return literal_ids_.emplace(text, static_cast<int>(literal_texts_.size()) - 1).first->second;
  }

  // A rule's firing strength folded as the interpreter does (clauses in input order from the norm's identity or
  // the folded grade, then the weight), for rules whose norms are not min / max or whose weight is not 1.
  std::string folded_strength(std::size_t r) {
    const Rule& rule = system_.rules[r];
    const bool conjunction = rule.connective == Connective::And;
    std::vector<Clause> clauses = rule.antecedent;
    std::stable_sort(clauses.begin(), clauses.end(),
                     [](const Clause& a, const Clause& b) { return a.variable < b.variable; });
    std::string value = rule.folded_grade ? constant(*rule.folded_grade) : conjunction ? "T(1)" : "T(0)";
    for (std::size_t c = 0; c < clauses.size(); ++c) {
      const std::string grade = clause_grade(clauses[c]);
      // Folding the first clause into the identity is exact for grades in [0, 1] (EvaluatorEmitter).
      if (c == 0 && !rule.folded_grade && !(conjunction && system_.and_method == TNorm::EinsteinProduct)) {
        value = grade;
        continue;
      }
      value = conjunction ? tnorm_call(system_.and_method, value, grade) : snorm_call(system_.or_method, value, grade);
    }
    const std::string name = "r" + std::to_string(r);
    body_lines_.push_back("const T " + name + " = " +
                          (rule.weight == 1.0 ? value : constant(rule.weight) + " * (" + value + ")") + ";");
    return name;
  }

  // The rule's firing strength as a maximum over products (minima) of literals: exact rewriting where the
  // antecedent is min or max of grades and the weight is 1; otherwise one product holding the folded strength.
  const std::vector<std::vector<int>>& rule_products(std::size_t r) {
    auto found = rule_products_.find(r);
    if (found != rule_products_.end()) return found->second;
    const Rule& rule = system_.rules[r];
    const bool conjunction = rule.connective == Connective::And;
    const bool lattice = rule.weight == 1.0 && (conjunction ? system_.and_method == TNorm::Minimum
                                                            : system_.or_method == SNorm::Maximum);
    std::vector<std::vector<int>> products;
    if (!lattice) {
      products.push_back({literal(folded_strength(r))});
    } else {
      std::vector<int> literals;
      if (rule.folded_grade) literals.push_back(literal(constant(*rule.folded_grade)));
      for (const Clause& clause : rule.antecedent) literals.push_back(literal(clause_grade(clause)));
      std::sort(literals.begin(), literals.end());
      literals.erase(std::unique(literals.begin(), literals.end()), literals.end());
      // An And rule is one product (with no clauses: the identity 1, the empty product); an Or rule is one
      // single-literal product per clause (with no clauses: 0, which adds nothing to a maximum of grades).
      if (conjunction) products.push_back(literals);
      else
        for (const int l : literals) products.push_back({l});
    }
    return rule_products_.emplace(r, std::move(products)).first->second;
  }

  // min / max of two expressions, emitted once per pair (both are exact and commutative, so sharing is exact).
  std::string lattice_op(bool minimum, std::string a, std::string b) {
    if (b < a) std::swap(a, b);
    const std::string key = (minimum ? "min|" : "max|") + a + "|" + b;
    const auto found = lattice_ops_.find(key);
    if (found != lattice_ops_.end()) return found->second;
    const std::string name = "f" + std::to_string(lattice_ops_.size());
    body_lines_.push_back("const T " + name + " = " + (minimum ? "grade_min(" : "grade_max(") + a + ", " + b + ");");
    lattice_ops_.emplace(key, name);
    return name;
  }

  // max over `products` of the min of each product's literals, factored: the literal shared by the most
  // products comes out, max(min(a, b), min(a, c)) = min(a, max(b, c)), recursively. min and max only select
  // their operands, so the factored form has the unfactored value exactly, in far fewer operations (the liver:
  // 195 instead of 514, with the sharing across columns). The empty product is 1, which absorbs the maximum
  // (grades are in [0, 1]).
  std::string max_of_mins(const std::vector<std::vector<int>>& products) {
    if (products.empty()) return "T(0)";
    for (const auto& product : products)
      if (product.empty()) return "T(1)";
    std::map<int, int> uses;
    for (const auto& product : products)
      for (const int l : product) ++uses[l];
    int shared = -1, most = 1;
    for (const auto& [l, count] : uses)
      if (count > most) shared = l, most = count;
    if (shared < 0) {
      std::string result;
      for (const auto& product : products) {
        std::string minimum = literal_texts_[static_cast<std::size_t>(product[0])];
        for (std::size_t k = 1; k < product.size(); ++k)
          minimum = lattice_op(true, minimum, literal_texts_[static_cast<std::size_t>(product[k])]);
        result = result.empty() ? minimum : lattice_op(false, result, minimum);
      }
      return result;
    }
    std::vector<std::vector<int>> with, without;
    for (const auto& product : products) {
      if (std::find(product.begin(), product.end(), shared) == product.end()) {
        without.push_back(product);
        continue;
      }
      std::vector<int> rest;
      for (const int l : product)
        if (l != shared) rest.push_back(l);
      with.push_back(std::move(rest));
    }
    const std::string& factor = literal_texts_[static_cast<std::size_t>(shared)];
    const std::string inner = max_of_mins(with);
    const std::string joined = inner == "T(1)" ? factor : lattice_op(true, factor, inner);
    return without.empty() ? joined : lattice_op(false, joined, max_of_mins(without));
  }

  OutputPlan plan_output(std::size_t o) {
    const Variable& output = system_.outputs[o];
    const std::vector<double> x = output_sample_points(output.min, output.max, system_.samples, Reference::Matlab);
    std::map<ColumnKey, std::size_t> column_of;
    std::vector<std::vector<std::vector<int>>> column_products;
    OutputPlan plan;
    for (std::size_t r = 0; r < system_.rules.size(); ++r)
      for (const Clause& clause : system_.rules[r].consequent) {
        if (clause.variable != static_cast<int>(o)) continue;
        const auto [where, added] = column_of.emplace(column_key(clause), column_products.size());
        if (added) {
          column_products.emplace_back();
          plan.grades.push_back(consequent_samples(system_, o, clause, x));
        }
        const auto& products = rule_products(r);
        auto& column = column_products[where->second];
        column.insert(column.end(), products.begin(), products.end());
      }
    for (const auto& products : column_products) plan.strengths.push_back(max_of_mins(products));
    return plan;
  }

  // g_k = max over columns of implication(strength, grade_k), unrolled over the samples with the grades as
  // constants; a grade of at most kDroppedGrade is left out (implication(w, g) <= g, so g_k moves by at most that
  // much; lane_total_floor accounts for it), and a sample where every grade is left out with it. Centroid:
  // sum(g x) / sum(g) as in evaluate(), x measured from the middle of the range, four partial sums of each.
  void emit_aggregation(std::size_t o, const OutputPlan& plan) {
    const Variable& output = system_.outputs[o];
    const std::string os = std::to_string(o);
    const std::vector<double> x = output_sample_points(output.min, output.max, system_.samples, Reference::Matlab);
    const double middle = (output.min + output.max) / 2.0;
    std::vector<double>& table = aggregation_grades_[o];
    body_lines_.push_back("{  // output " + comment_safe(output.name) + ": " + std::to_string(x.size()) +
                          " samples of the aggregate, then centroid");
    body_lines_.push_back("  T total_0 = T(0), total_1 = T(0), total_2 = T(0), total_3 = T(0);");
    body_lines_.push_back("  T moment_0 = T(0), moment_1 = T(0), moment_2 = T(0), moment_3 = T(0);");
    std::size_t emitted = 0;
    for (std::size_t k = 0; k < x.size(); ++k) {
      std::vector<std::string> terms;
      for (std::size_t c = 0; c < plan.strengths.size(); ++c) {
        const double grade = plan.grades[c][k];
        if (grade <= kDroppedGrade) continue;
        const std::string& w = plan.strengths[c];
        std::string term;
        if (system_.implication == TNorm::Product && grade == 1.0) {
          term = w;  // w 1 = w exactly
        } else {
          const std::string read = "grades" + os + "[" + std::to_string(table.size()) + "]";
          table.push_back(grade);
          term = system_.implication == TNorm::Minimum ? "grade_min(" + w + ", " + read + ")"
                                                        : "(" + w + " * " + read + ")";
        }
        terms.push_back(term);
      }
      if (terms.empty()) continue;
      // max is exact, so a balanced tree (a shorter chain than a left fold) has the same value.
      while (terms.size() > 1) {
        std::vector<std::string> pairs;
        for (std::size_t t = 0; t + 1 < terms.size(); t += 2)
          pairs.push_back("grade_max(" + terms[t] + ", " + terms[t + 1] + ")");
        if (terms.size() % 2 == 1) pairs.push_back(terms.back());
        terms = std::move(pairs);
      }
      const std::string& g = terms[0];
      const std::string p = std::to_string(emitted++ % 4);
      const double offset = x[k] - middle;
      body_lines_.push_back("  { const T g = " + g + "; total_" + p + " += g;" +
                            (offset == 0.0 ? std::string() : " moment_" + p + " += g * " + constant(offset) + ";") +
                            " }");
    }
    body_lines_.push_back("  const T total = (total_0 + total_1) + (total_2 + total_3);");
    body_lines_.push_back("  const T moment = (moment_0 + moment_1) + (moment_2 + moment_3);");
    body_lines_.push_back("  value" + os + "[j] = " + constant(middle) + " + moment / total;");
    body_lines_.push_back("  total" + os + "[j] = total;");
    body_lines_.push_back("}");
  }

  const FuzzySystem& system_;
  CodeWriter& out_;
  std::vector<std::string> grade_lines_, body_lines_;
  std::set<std::string> emitted_arrays_;
  std::map<std::string, int> literal_ids_;
  std::vector<std::string> literal_texts_;
  std::map<std::size_t, std::vector<std::vector<int>>> rule_products_;
  std::map<std::string, std::string> lattice_ops_;
  std::map<std::size_t, std::vector<double>> aggregation_grades_;  // per output, what kLaneGrades<o> holds
  bool uses_lane_exp_ = false;
};

// lane_exp and lane_gaussian, the vectorisable exp of evaluate_batch (written into headers that use them).
constexpr const char* kLaneExpText = R"(// exp for the lanes of evaluate_batch:
// Cody-Waite reduction a = n ln2 + r, |r| <= ln2 / 2, a polynomial for exp(r) (double: Taylor to degree 13 by
// Estrin's scheme; float: Cephes expf), then 2^n from its bits. Within 2 ulp of the C library's exp (float: 1 ulp)
// for arguments from `lowest` (-708, float: -86) up; below it, where exp is below 3.3e-308 (float: 4.5e-38), the
// result is 0 (NaN included: NaN lanes are overwritten). So every result is 0 or a normal number: computing a
// subnormal, or a product that rounds to one, costs a microcode assist on x86, and evaluate_batch sends the points
// where such grades could matter to evaluate() (docs/codegen.md "Batch evaluation"). Plain arithmetic, selects and
// bit copies, no branches and no calls, so that compilers vectorise the loops that call it. Arguments must be at
// most 15 (float: 5), which Gaussian exponents (<= 0) are. `lowest` is read from a volatile once per call, not
// written as a constant: with a constant GCC folds the clamped case and turns the clamp into a branch, which stops
// it vectorising the loop.
inline double lane_exp(double argument, double lowest) {
  const double a = argument > lowest ? argument : lowest;
  const double shifted = a * 0x1.71547652b82fep0 + 0x1.8p52;  // 1.5 2^52: the low bits hold n = round(a / ln2)
  const double n = shifted - 0x1.8p52;
  const double r = (a - n * 0x1.62e42feep-1) - n * 0x1.a39ef35793c76p-33;
  // Estrin's scheme: a shorter chain of dependent operations than Horner's, which the lanes' loops wait on.
  const double r2 = r * r, r4 = r2 * r2, r8 = r4 * r4;
  const double low = (1.0 + r) + r2 * (0.5 + r * (1.0 / 6.0));
  const double middle = (1.0 / 24.0 + r * (1.0 / 120.0)) + r2 * (1.0 / 720.0 + r * (1.0 / 5040.0));
  const double high = (1.0 / 40320.0 + r * (1.0 / 362880.0)) + r2 * (1.0 / 3628800.0 + r * (1.0 / 39916800.0));
  const double top = 1.0 / 479001600.0 + r * (1.0 / 6227020800.0);
  const double p = (low + r4 * middle) + r8 * (high + r4 * top);
  // 2^n with n >= -1021 (a >= -708): a normal number, and so is p 2^n (p >= 0.7); 0 below `lowest`. (A select
  // on the bits: GCC turns a select on the result into a branch, which stops it vectorising the loop.)
  std::uint64_t bits;
  std::memcpy(&bits, &shifted, sizeof bits);
  bits = argument >= lowest ? (bits + 1023u) << 52 : 0u;
  double scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}
inline float lane_exp(float argument, float lowest) {
  const float a = argument > lowest ? argument : lowest;
  const float shifted = a * 0x1.715476p0f + 0x1.8p23f;
  const float n = shifted - 0x1.8p23f;
  const float r = (a - n * 0.693359375f) - n * -2.12194440e-4f;
  float p = 1.9875691500e-4f;
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  p = p * (r * r) + r + 1.0f;
  // 2^n with n >= -124 (a >= -86): normal, and so is p 2^n; 0 below `lowest`.
  std::uint32_t bits;
  std::memcpy(&bits, &shifted, sizeof bits);
  bits = argument >= lowest ? (bits + 127u) << 23 : 0u;
  float scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}
inline const volatile double kLaneExpLowestDouble = -708.0;
inline const volatile float kLaneExpLowestFloat = -86.0f;
inline double lane_exp_lowest(double) { return kLaneExpLowestDouble; }
inline float lane_exp_lowest(float) { return kLaneExpLowestFloat; }

// gaussmf as fmpc_math::mf::gaussian computes it, with lane_exp.
template <typename T>
inline T lane_gaussian(T x, T sigma, T c, T lowest) {
  const T t = (x - c) / sigma;
  return lane_exp(-t * t / T(2), lowest);
}
)";

// Everything a type-1 emitter cannot (yet) turn into code, as located errors.
bool check_supported(const FuzzySystem& system, const EmitOptions& options, DiagnosticList& diagnostics) {
  bool supported = true;
  const SourceRange where = system.range.valid() ? system.range : SourceRange{options.source_path, 0, 0, 0, 0};
  if (system.type == SystemType::Mamdani && system.samples <= 0) {
    diagnostics.error(where,
                      "the C++/CUDA emitter does not support `samples exact` yet: write `samples 101` (MATLAB's "
                      "default) or another count in the defuzzify line",
                      {"`fmpc compile --target table` accepts `samples exact`"});
    supported = false;
  }
  if (const auto problem = namespace_name_problem(options.namespace_name)) {
    diagnostics.error(SourceRange{options.source_path, 0, 0, 0, 0},
                      "namespace '" + options.namespace_name + "' cannot name the generated code's namespace: " +
                          *problem + "; use identifiers joined by '::', e.g. scene::liver");
    supported = false;
  }
  return supported;
}

const char* target_name(EmitOptions::Target target) {
  return target == EmitOptions::Target::Cuda ? "cuda" : "cpp";
}

}  // namespace

std::string embedded_fuzzy_math(const std::string& math_namespace) {
  return embedded_kernel_math({std::begin(kEmbeddedMathFiles), std::end(kEmbeddedMathFiles)}, math_namespace);
}

std::string embedded_kernel_math(const std::vector<std::string>& paths, const std::string& math_namespace) {
  std::string result;
  for (const std::string& path : paths) {
    const std::string_view text = embedded_kernel_source(path);
    if (text.empty()) return {};
    result += std::string("// ---- copied from ") + path + " ----\n";
    const bool macro_file = path == "kernels/fmpc_hd.h";
    if (macro_file) result += "#ifndef FMPC_HD\n";
    std::istringstream lines{std::string(text)};
    std::string line;
    while (std::getline(lines, line)) {
      if (line.rfind("#pragma once", 0) == 0 || line.rfind("#include \"kernels/", 0) == 0) continue;
      if (line == "namespace fmpc {") line = "namespace " + math_namespace + " {";
      else if (line == "}  // namespace fmpc") line = "}  // namespace " + math_namespace;
      result += line;
      result += '\n';
    }
    if (macro_file) result += "#endif\n";
  }
  return result;
}

std::optional<std::string> emit_evaluator(const FuzzySystem& system, const EmitOptions& options,
                                          DiagnosticList& diagnostics) {
  if (!check_supported(system, options, diagnostics)) return std::nullopt;

  // The math copy is named after its own hash: identical copies from several headers collapse into one (the
  // include guard), different fmpc versions' copies live side by side.
  // Type-2 headers carry the type reduction too (a copy with another hash, so both kinds share a translation unit).
  const std::vector<std::string> math_files =
      system.interval_type2 ? type2_embedded_math_files()
                            : std::vector<std::string>(std::begin(kEmbeddedMathFiles), std::end(kEmbeddedMathFiles));
  std::string original;
  for (const std::string& path : math_files) original += std::string(embedded_kernel_source(path));
  const std::string math_hash = hex64(fnv1a64(original));
  const std::string math_namespace = "fmpc_math_" + math_hash;
  const std::string math_text = embedded_kernel_math(math_files, math_namespace);
  if (math_text.empty()) {
    diagnostics.error(SourceRange{options.source_path, 0, 0, 0, 0},
                      "this fmpc was built without the embedded kernel headers; rebuild fmpc");
    return std::nullopt;
  }

  const bool cuda = options.target == EmitOptions::Target::Cuda;
  CodeWriter out;
  out.line("// Generated by fmpc 0.1.0 (fmpc compile --target " + std::string(target_name(options.target)) +
           "). Do not edit: regenerate from the rule file.");
  out.line("// source: " + comment_safe(options.source_path.empty() ? "(unnamed)" : options.source_path));
  out.line("// source hash (FNV-1a 64): " + hex64(options.source_hash));
  out.line("// system: " + comment_safe(system.name) + " (" + to_string(system.type) + ", " +
           std::to_string(system.inputs.size()) + " inputs, " + std::to_string(system.outputs.size()) +
           " outputs, " + std::to_string(system.rules.size()) + " rules)");
  for (const std::string& note : options.banner_notes) out.line("// " + comment_safe(note));
  out.line("//");
  out.line("// Interface (namespace " + options.namespace_name + "): inputs and outputs in the order below.");
  for (std::size_t i = 0; i < system.inputs.size(); ++i) {
    const Variable& v = system.inputs[i];
    out.line("//   input  " + std::to_string(i) + ": " + comment_safe(v.name) + " in [" + format_number(v.min) +
             ", " + format_number(v.max) + "]" + (v.unit.empty() ? "" : " " + comment_safe(v.unit)));
  }
  for (std::size_t o = 0; o < system.outputs.size(); ++o) {
    const Variable& v = system.outputs[o];
    out.line("//   output " + std::to_string(o) + ": " + comment_safe(v.name) + " in [" + format_number(v.min) +
             ", " + format_number(v.max) + "]" + (v.unit.empty() ? "" : " " + comment_safe(v.unit)));
  }
  out.line("//   unsigned evaluate<T>(const T* inputs, T* outputs): one point, returns kFlag* bits");
  out.line("//   void evaluate_batch<T>(const T* inputs, T* outputs, std::size_t n, unsigned* flags = nullptr):");
  out.line("//     n points, inputs n x kInputCount and outputs n x kOutputCount, row-major");
  if (cuda) {
    out.line("//   __global__ evaluate_kernel<T>(inputs, outputs, n, flags) and");
    out.line("//   cudaError_t evaluate_batch_cuda<T>(device inputs, device outputs, n, device flags = nullptr,");
    out.line("//     stream = 0): launches the kernel and returns the launch status (nvcc only)");
  }
  out.line("#pragma once");
  const bool lane_batch = lane_batch_applies(system);
  out.line("#include <cstddef>");
  if (lane_batch) {
    out.line("#include <cstdint>");
    out.line("#include <cstring>");
  }
  out.line("#include <math.h>");
  if (cuda) {
    out.line("#if defined(__CUDACC__)");
    out.line("#include <cuda_runtime.h>");
    out.line("#endif");
  }
  out.line();
  // Constant tables: one static copy on the host; in device code plain locals, which the unrolled loops fold
  // into immediates (a static local would live in global memory).
  out.line("#ifndef FMPC_GENERATED_TABLE");
  out.line("#if defined(__CUDA_ARCH__)");
  out.line("#define FMPC_GENERATED_TABLE constexpr");
  out.line("#define FMPC_GENERATED_UNROLL _Pragma(\"unroll\")");
  out.line("#else");
  out.line("#define FMPC_GENERATED_TABLE static constexpr");
  out.line("#define FMPC_GENERATED_UNROLL");
  out.line("#endif");
  out.line("#endif");
  out.line();
  out.line("#ifndef FMPC_GENERATED_MATH_" + math_hash);
  out.line("#define FMPC_GENERATED_MATH_" + math_hash);
  out.block(math_text);
  out.line("#endif  // FMPC_GENERATED_MATH_" + math_hash);
  out.line();
  out.line("namespace " + options.namespace_name + " {");
  out.line();
  out.line("namespace fmpc_math = ::" + math_namespace + ";");
  out.line();
  out.line("inline constexpr std::size_t kInputCount = " + std::to_string(system.inputs.size()) + ";");
  out.line("inline constexpr std::size_t kOutputCount = " + std::to_string(system.outputs.size()) + ";");
  const auto names = [](const std::vector<Variable>& variables, bool units) {
    std::string list;
    for (const Variable& v : variables) list += (list.empty() ? "" : ", ") + quoted(units ? v.unit : v.name);
    return list.empty() ? std::string("\"\"") : list;
  };
  const auto limits = [](const std::vector<Variable>& variables, bool upper) {
    std::string list;
    for (const Variable& v : variables) list += (list.empty() ? "" : ", ") + format_number(upper ? v.max : v.min);
    return list.empty() ? std::string("0") : list;
  };
  // Arrays keep one element when there are no inputs, so that the declarations stay valid C++.
  out.line("inline constexpr const char* kInputNames[] = {" + names(system.inputs, false) + "};");
  out.line("inline constexpr const char* kOutputNames[] = {" + names(system.outputs, false) + "};");
  out.line("// The rule file's units (\"\" where it gives none, as in MATLAB files).");
  out.line("inline constexpr const char* kInputUnits[] = {" + names(system.inputs, true) + "};");
  out.line("inline constexpr const char* kOutputUnits[] = {" + names(system.outputs, true) + "};");
  out.line("inline constexpr double kInputMin[] = {" + limits(system.inputs, false) + "};");
  out.line("inline constexpr double kInputMax[] = {" + limits(system.inputs, true) + "};");
  out.line("inline constexpr double kOutputMin[] = {" + limits(system.outputs, false) + "};");
  out.line("inline constexpr double kOutputMax[] = {" + limits(system.outputs, true) + "};");
  out.line("inline constexpr unsigned long long kSourceHash = 0x" + hex64(options.source_hash) + "ull;");
  out.line();
  out.line("// evaluate()'s result bits. NaN inputs give NaN outputs; out-of-range inputs are evaluated as given.");
  out.line("inline constexpr unsigned kFlagNanInput = 1u;");
  out.line("inline constexpr unsigned kFlagInputOutOfRange = 2u;");
  out.line("inline constexpr unsigned kFlagNoRuleFired = 4u;   // an output took the no-rule-fired value");
  out.line("inline constexpr unsigned kFlagNoFireError = 8u;   // ... and the policy is `error`: it is NaN");
  if (system.interval_type2)
    out.line("inline constexpr unsigned kFlagInternalError = 16u;  // type reduction hit its cap (an fmpc bug): NaN");
  out.line();
  out.line("// min and max of grades, which cannot be NaN here (a NaN input returns first): fmpc_math::nan_min's and");
  out.line("// nan_max's values without their NaN branches.");
  out.line("template <typename T>");
  out.line("FMPC_HD T grade_min(T a, T b) { return a < b ? a : b; }");
  out.line("template <typename T>");
  out.line("FMPC_HD T grade_max(T a, T b) { return a > b ? a : b; }");
  out.line();
  if (system.interval_type2) out.block(emit_type2_evaluate_function(system, options, out.lines()));
  else EvaluatorEmitter(system, options, out).emit_evaluate_function();
  out.line();
  if (lane_batch) {
    out.line("// evaluate_batch is compiled for the baseline x86-64 and for x86-64-v3 (AVX2, FMA) and v4 (AVX-512) by");
    out.line("// GCC on glibc x86-64 (target_clones); the dynamic loader runs the clone the CPU supports. Define");
    out.line("// FMPC_NO_TARGET_CLONES to compile only the one the compiler's flags select.");
    out.line("#ifndef FMPC_GENERATED_BATCH_CLONES");
    out.line("#if !defined(FMPC_NO_TARGET_CLONES) && defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 11 && \\");
    out.line("    defined(__x86_64__) && defined(__ELF__) && defined(__GLIBC__) && !defined(__CUDACC__)");
    out.line("#define FMPC_GENERATED_BATCH_CLONES \\");
    out.line("  __attribute__((target_clones(\"default\", \"arch=x86-64-v3\", \"arch=x86-64-v4\")))");
    out.line("#else");
    out.line("#define FMPC_GENERATED_BATCH_CLONES");
    out.line("#endif");
    out.line("#endif");
    out.line();
    out.line("// Points per block of evaluate_batch: 16 floats or doubles fill whole vector registers of every width.");
    out.line("inline constexpr std::size_t kBatchLanes = 16;");
    out.line();
    out.block(kLaneExpText);
    out.line();
    LaneBatchEmitter(system, out).emit();
  } else {
    out.line("template <typename T>");
    out.line("inline void evaluate_batch(const T* inputs, T* outputs, std::size_t n, unsigned* flags = nullptr) {");
    out.line("  for (std::size_t i = 0; i < n; ++i) {");
    out.line("    const unsigned f = evaluate(inputs + i * kInputCount, outputs + i * kOutputCount);");
    out.line("    if (flags != nullptr) flags[i] = f;");
    out.line("  }");
    out.line("}");
  }
  if (cuda) {
    out.line();
    out.line("#if defined(__CUDACC__)");
    out.line("// One thread per point, grid-stride so that any n fits any grid.");
    out.line("template <typename T>");
    out.line("__global__ void evaluate_kernel(const T* __restrict__ inputs, T* __restrict__ outputs, std::size_t n,");
    out.line("                                unsigned* __restrict__ flags) {");
    out.line("  const std::size_t stride = static_cast<std::size_t>(gridDim.x) * blockDim.x;");
    out.line("  for (std::size_t i = static_cast<std::size_t>(blockIdx.x) * blockDim.x + threadIdx.x; i < n;");
    out.line("       i += stride) {");
    out.line("    const unsigned f = evaluate(inputs + i * kInputCount, outputs + i * kOutputCount);");
    out.line("    if (flags != nullptr) flags[i] = f;");
    out.line("  }");
    out.line("}");
    out.line();
    out.line("// Launches evaluate_kernel on `stream` over device arrays; returns the launch status (errors of the");
    out.line("// kernel itself surface at the next synchronising call, as with any CUDA launch).");
    out.line("template <typename T>");
    out.line("inline cudaError_t evaluate_batch_cuda(const T* device_inputs, T* device_outputs, std::size_t n,");
    out.line("                                       unsigned* device_flags = nullptr, cudaStream_t stream = 0) {");
    out.line("  if (n == 0) return cudaSuccess;");
    out.line("  if (device_outputs == nullptr || (kInputCount > 0 && device_inputs == nullptr)) return cudaErrorInvalidValue;");
    out.line("  constexpr unsigned kThreads = 256;");
    out.line("  const std::size_t wanted = (n + kThreads - 1) / kThreads;");
    out.line("  const unsigned blocks = wanted < 65535u * 32u ? static_cast<unsigned>(wanted) : 65535u * 32u;");
    out.line("  evaluate_kernel<T><<<blocks, kThreads, 0, stream>>>(device_inputs, device_outputs, n, device_flags);");
    out.line("  return cudaGetLastError();");
    out.line("}");
    out.line("#endif  // __CUDACC__");
  }
  out.line();
  out.line("}  // namespace " + options.namespace_name);
  return out.text();
}

std::string emitted_constant(double value) { return constant(value); }
std::string emitted_string_literal(const std::string& text) { return quoted(text); }
std::string emitted_comment_text(const std::string& text) { return comment_safe(text); }
std::string emitted_enumerator(TNorm norm) { return tnorm_enumerator(norm); }
std::string emitted_enumerator(SNorm norm) { return snorm_enumerator(norm); }
std::string emitted_tnorm_call(TNorm norm, const std::string& a, const std::string& b) {
  return tnorm_call(norm, a, b);
}
std::string emitted_snorm_call(SNorm norm, const std::string& a, const std::string& b) {
  return snorm_call(norm, a, b);
}

std::string emitted_sugeno_value(const MembershipFunction& mf, std::size_t input_count) {
  if (mf.kind == MfKind::Constant) return mf.params.empty() ? "fmpc_math::fmpc_quiet_nan<T>()" : constant(mf.params[0]);
  if (mf.kind != MfKind::Linear || mf.params.size() != input_count + 1) return "fmpc_math::fmpc_quiet_nan<T>()";
  std::string value;
  for (std::size_t i = 0; i < input_count; ++i)
    value += (i ? " + " : "") + constant(mf.params[i]) + " * x" + std::to_string(i);
  return value.empty() ? constant(mf.params.back()) : value + " + " + constant(mf.params.back());
}

std::vector<EmittedConsequent> consequents_on_output(const FuzzySystem& system, std::size_t output) {
  std::vector<EmittedConsequent> result;
  for (std::size_t r = 0; r < system.rules.size(); ++r)
    for (const Clause& clause : system.rules[r].consequent)
      if (clause.variable == static_cast<int>(output)) result.push_back({r, &clause});
  return result;
}

std::string LineDirectives::to_rule(const SourceRange& range) {
  if (!options_.line_directives || !range.valid() || options_.source_path.empty()) return "";
  pending_return_ = true;
  return "#line " + std::to_string(range.line) + " " + quoted(options_.source_path);
}

std::string LineDirectives::back_to_header(int lines_written) {
  if (!pending_return_ || options_.header_path.empty()) return "";
  pending_return_ = false;
  // The directive itself is line lines_written + 1; #line N names the line after it.
  return "#line " + std::to_string(lines_written + 2) + " " + quoted(options_.header_path);
}

}  // namespace fmpc
