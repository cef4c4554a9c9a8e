#include "compiler/backend/cpp/evaluator_emitter.h"

#include <algorithm>
#include <map>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "compiler/eval/defuzzify.h"
#include "kernels/fuzzy_math.h"

namespace fmpc {

namespace {

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
                cpp_comment_text(system_.inputs[i].name));
    // A NaN input makes every output NaN (docs/numerics.md): never a silent number.
    const std::vector<std::string> x = input_locals(input_count);
    if (input_count > 0) {
      out_.line("  if (" + any_nan_test(x) + ") {");
      for (std::size_t o = 0; o < output_count; ++o)
        out_.line("    outputs[" + std::to_string(o) + "] = fmpc_math::fmpc_quiet_nan<T>();");
      out_.line("    return kFlagNanInput;");
      out_.line("  }");
    }
    out_.line("  unsigned flags = 0u;");
    if (input_count > 0) out_.line("  if (" + out_of_range_test(system_, x) + ") flags |= kFlagInputOutOfRange;");
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
                cpp_comment_text(system_.inputs[static_cast<std::size_t>(i)].name + " is " + term.name));
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
        value = "fmpc_math::apply_hedge(" + value + ", " + cpp_constant(hedge_exponent(clause.hedge)) + ")";
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
    const std::string start = rule.folded_grade ? cpp_constant(*rule.folded_grade) : conjunction ? "T(1)" : "T(0)";
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
      out_.line("  // " + cpp_comment_text(system_.rule_display_name(r)));
      directives_.to_rule(rule.range, out_);
      const std::string strength = antecedent_strength(rule, plans_[r]);
      const std::string name = "w" + std::to_string(r);
      // firing = weight * strength (interpreter); 1 * s == s exactly.
      if (rule.weight == 1.0) out_.line("  const T " + name + " = " + strength + ";");
      else out_.line("  const T " + name + " = " + cpp_constant(rule.weight) + " * " + strength + ";");
      firing_[r] = name;
      directives_.back_to_header(out_);
    }
  }

  // The system's no-rule-fired policy for output `o`: its value and the kFlag* bits.
  void emit_no_fire(std::size_t o, const std::string& indent) {
    out_.line(indent + "flags |= kFlagNoRuleFired;");
    out_.line(indent + "outputs[" + std::to_string(o) + "] = " + no_fire_value(system_, o) + ";");
    if (system_.no_fire == NoFirePolicy::Error) out_.line(indent + "flags |= kFlagNoFireError;");
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
    const std::vector<OutputConsequent> consequents = consequents_on_output(system_, o);
    out_.line("  // output " + cpp_comment_text(output.name) + ": " + n + " samples of the aggregate, then " +
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
    for (const OutputConsequent& consequent : consequents) {
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
      out_.double_table("    ", "kGrades", grades, padded, grades.size() > 1);
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
      out_.double_table("    ", "kOffsets", {offsets}, padded, false);
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
      out_.line("      outputs[" + os + "] = " + cpp_constant(middle) + " + moment / total;");
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
    out_.double_table("    ", "kSamplePoints", {x}, x.size(), false);
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
    const std::vector<OutputConsequent> consequents = consequents_on_output(system_, o);
    out_.line("  // output " + cpp_comment_text(output.name) + ": " + to_string(system_.defuzzifier));
    out_.line("  {");
    out_.line("    T numerator = T(0), denominator = T(0);");
    out_.line("    bool fired = false;");
    std::vector<bool> concludes(system_.rules.size(), false);
    for (const OutputConsequent& consequent : consequents) {
      concludes[consequent.rule] = true;
      const std::string& w = firing_[consequent.rule];
      const Clause& clause = *consequent.clause;
      std::string height = w;
      // Octave's eval_rules_sugeno hedges the height as w^(1/hedge), then negates it (interpreter).
      if (clause.hedge != Hedge::None)
        height = "fmpc_math::fmpc_pow(" + height + ", " + cpp_constant(1.0 / hedge_exponent(clause.hedge)) + ")";
      if (clause.negated) height = "fmpc_math::fuzzy_not(" + height + ")";
      const MembershipFunction& mf = output.terms[static_cast<std::size_t>(clause.term)].mf;
      out_.line("    if (" + w + " != T(0)) {");
      out_.line("      const T h = " + height + ";");
      out_.line("      numerator += h * (" + sugeno_value(mf, system_.inputs.size()) + ");");
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

}  // namespace

void emit_type1_evaluate_function(const FuzzySystem& system, const EmitOptions& options, CodeWriter& out) {
  EvaluatorEmitter(system, options, out).emit_evaluate_function();
}

}  // namespace fmpc
