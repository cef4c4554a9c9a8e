#include "compiler/backend/cpp/emit_type2.h"

#include <algorithm>
#include <map>
#include <set>
#include <tuple>
#include <utility>

#include "compiler/eval/defuzzify.h"
#include "compiler/eval/interpreter.h"
#include "kernels/type2_math.h"

namespace fmpc {

namespace {

const char* mf_kind_enumerator(MfKind kind) {
  switch (kind) {
    case MfKind::Triangle: return "fmpc_math::MfKind::Triangle";
    case MfKind::Trapezoid: return "fmpc_math::MfKind::Trapezoid";
    case MfKind::Gaussian: return "fmpc_math::MfKind::Gaussian";
    case MfKind::Gaussian2: return "fmpc_math::MfKind::Gaussian2";
    case MfKind::GeneralizedBell: return "fmpc_math::MfKind::GeneralizedBell";
    case MfKind::Sigmoid: return "fmpc_math::MfKind::Sigmoid";
    case MfKind::DifferenceSigmoid: return "fmpc_math::MfKind::DifferenceSigmoid";
    case MfKind::ProductSigmoid: return "fmpc_math::MfKind::ProductSigmoid";
    case MfKind::ZShape: return "fmpc_math::MfKind::ZShape";
    case MfKind::SShape: return "fmpc_math::MfKind::SShape";
    case MfKind::PiShape: return "fmpc_math::MfKind::PiShape";
    case MfKind::LinearS: return "fmpc_math::MfKind::LinearS";
    case MfKind::LinearZ: return "fmpc_math::MfKind::LinearZ";
    case MfKind::Constant: return "fmpc_math::MfKind::Constant";
    case MfKind::Linear: return "fmpc_math::MfKind::Linear";
  }
  return "fmpc_math::MfKind::Triangle";
}

const char* footprint_enumerator(FootprintKind kind) {
  switch (kind) {
    case FootprintKind::None: return "fmpc_math::FootprintKind::None";
    case FootprintKind::UncertainMean: return "fmpc_math::FootprintKind::UncertainMean";
    case FootprintKind::UncertainSd: return "fmpc_math::FootprintKind::UncertainSd";
    case FootprintKind::ExplicitLower: return "fmpc_math::FootprintKind::ExplicitLower";
    case FootprintKind::ScaleLag: return "fmpc_math::FootprintKind::ScaleLag";
    case FootprintKind::IntervalValue: return "fmpc_math::FootprintKind::IntervalValue";
  }
  return "fmpc_math::FootprintKind::None";
}

const char* type_reduction_enumerator(TypeReduction method) {
  switch (method) {
    case TypeReduction::KarnikMendel: return "fmpc_math::TypeReduction::KarnikMendel";
    case TypeReduction::EnhancedKarnikMendel: return "fmpc_math::TypeReduction::EnhancedKarnikMendel";
    case TypeReduction::Eiasc: return "fmpc_math::TypeReduction::Eiasc";
    case TypeReduction::NieTan: return "fmpc_math::TypeReduction::NieTan";
  }
  return "fmpc_math::TypeReduction::KarnikMendel";
}

// "{T(a), T(b), ...}": a parameter array's initialiser (one element at least, so that the array is valid C++).
std::string constant_list(const std::vector<double>& values) {
  std::string list;
  for (const double v : values) list += (list.empty() ? "" : ", ") + cpp_constant(v);
  return "{" + (list.empty() ? std::string("T(0)") : list) + "}";
}

class Type2Emitter {
 public:
  Type2Emitter(const FuzzySystem& system, const EmitOptions& options, CodeWriter& out)
      : system_(system), options_(options), out_(out) {}

  void emit() {
    emit_sort_helper();
    emit_evaluate_interval();
    line("");
    line("// The crisp outputs alone: (yl + yr) / 2 per output, as `fmpc eval` prints them.");
    line("template <typename T>");
    line("FMPC_HD unsigned evaluate(const T* inputs, T* outputs) {");
    line("  return evaluate_interval(inputs, outputs, static_cast<T*>(nullptr), static_cast<T*>(nullptr));");
    line("}");
  }

 private:
  void line(const std::string& text) { out_.line(text); }

  // The Sugeno centre-of-sets reduction sorts the rules by their output value at run time (linear consequents
  // move with the inputs): the interpreter's std::stable_sort, as an insertion sort (stable: an element moves only
  // past strictly greater keys, so the order is the same).
  void emit_sort_helper() {
    const bool sugeno_reduction =
        system_.type == SystemType::Sugeno && system_.defuzzifier != Defuzzifier::WeightedSum;
    if (!sugeno_reduction) return;
    line("// points[0 .. n) = key[0 .. n) in ascending order, ties in index order (std::stable_sort's order), with");
    line("// the weights [lower, upper] moved alongside.");
    line("template <typename T>");
    line("FMPC_HD void sort_type2_points(const T* key, const T* lower, const T* upper, int n, T* points,");
    line("                               T* sorted_lower, T* sorted_upper) {");
    line("  for (int i = 0; i < n; ++i) {");
    line("    int j = i;");
    line("    for (; j > 0 && key[i] < points[j - 1]; --j) {");
    line("      points[j] = points[j - 1];");
    line("      sorted_lower[j] = sorted_lower[j - 1];");
    line("      sorted_upper[j] = sorted_upper[j - 1];");
    line("    }");
    line("    points[j] = key[i];");
    line("    sorted_lower[j] = lower[i];");
    line("    sorted_upper[j] = upper[i];");
    line("  }");
    line("}");
    line("");
  }

  void emit_evaluate_interval() {
    const std::size_t input_count = system_.inputs.size();
    const std::string kind = std::string("interval type-2 ") + to_string(system_.type);
    line("// Evaluates the " + kind + " system at inputs[0 .. kInputCount): outputs[o] = (yl + yr) / 2 and, where");
    line("// lower / upper are not null, lower[o] = yl, upper[o] = yr, the type-reduced interval (type reduction " +
         std::string(to_string(system_.type_reduction)) + ").");
    line("// Returns the kFlag* bits. T is float or double; every step is the interpreter's (fmpc eval).");
    line("template <typename T>");
    line("FMPC_HD unsigned evaluate_interval(const T* inputs, T* outputs, T* lower, T* upper) {");
    if (input_count == 0) line("  (void)inputs;");
    for (std::size_t i = 0; i < input_count; ++i)
      line("  const T x" + std::to_string(i) + " = inputs[" + std::to_string(i) + "];  // " +
           cpp_comment_text(system_.inputs[i].name));
    const std::vector<std::string> x = input_locals(input_count);
    if (input_count > 0) {
      line("  if (" + any_nan_test(x) + ") {");
      line("    for (std::size_t o = 0; o < kOutputCount; ++o) {");
      line("      outputs[o] = fmpc_math::fmpc_quiet_nan<T>();");
      line("      if (lower != nullptr) lower[o] = fmpc_math::fmpc_quiet_nan<T>();");
      line("      if (upper != nullptr) upper[o] = fmpc_math::fmpc_quiet_nan<T>();");
      line("    }");
      line("    return kFlagNanInput;");
      line("  }");
    }
    line("  unsigned flags = 0u;");
    if (input_count > 0) line("  if (" + out_of_range_test(system_, x) + ") flags |= kFlagInputOutOfRange;");
    if (system_.type == SystemType::Mamdani) plan_mamdani_columns();
    emit_firing_intervals();
    for (std::size_t o = 0; o < system_.outputs.size(); ++o) {
      if (system_.type == SystemType::Mamdani) emit_mamdani_output(o);
      else emit_sugeno_output(o);
    }
    line("  return flags;");
    line("}");
  }

  // The local holding input `i`'s [lower, upper] grade in term `t` (kernels/type2_math.h footprint_membership,
  // the interpreter's term_membership), emitted at first use.
  std::string term_grade(int i, int t) {
    const std::string suffix = std::to_string(i) + "_" + std::to_string(t);
    const std::string name = "mu" + suffix;
    if (!emitted_.insert(name).second) return name;
    const Variable& input = system_.inputs[static_cast<std::size_t>(i)];
    const Term& term = input.terms[static_cast<std::size_t>(t)];
    line("  const T p" + suffix + "[] = " + constant_list(term.mf.params) + ";");
    FootprintKind footprint = FootprintKind::None;
    double first = 0.0, second = 0.0;
    std::string lower_kind = mf_kind_enumerator(MfKind::Triangle);
    std::string lower_params = "static_cast<const T*>(nullptr)";
    if (term.footprint) {
      footprint = term.footprint->kind;
      first = term.footprint->first;
      second = term.footprint->second;
      if (footprint == FootprintKind::ExplicitLower) {
        line("  const T q" + suffix + "[] = " + constant_list(term.footprint->lower.params) + ";");
        lower_kind = mf_kind_enumerator(term.footprint->lower.kind);
        lower_params = "q" + suffix;
      }
    }
    line("  const fmpc_math::GradeInterval<T> " + name + " = fmpc_math::footprint_membership<T>(" +
         mf_kind_enumerator(term.mf.kind) + ", p" + suffix + ", " + footprint_enumerator(footprint) + ", " +
         cpp_constant(first) + ", " + cpp_constant(second) + ", " + lower_kind + ", " + lower_params +
         ", x" + std::to_string(i) + ");  // " + cpp_comment_text(input.name + " is " + term.name));
    return name;
  }

  // The clause's [lower, upper] ends: the hedge on each end, then `not` swapping them (interpreter's
  // clause_interval), emitted once however many rules name the clause.
  std::pair<std::string, std::string> clause_ends(const Clause& clause) {
    const std::string grade = term_grade(clause.variable, clause.term);
    if (clause.hedge == Hedge::None && !clause.negated) return {grade + ".lower", grade + ".upper"};
    const std::string name = grade + "_h" + std::to_string(static_cast<int>(clause.hedge)) +
                             (clause.negated ? "_not" : "");
    if (emitted_.insert(name).second) {
      std::string lower = grade + ".lower", upper = grade + ".upper";
      if (clause.hedge != Hedge::None) {
        const std::string exponent = cpp_constant(hedge_exponent(clause.hedge));
        lower = "fmpc_math::apply_hedge(" + lower + ", " + exponent + ")";
        upper = "fmpc_math::apply_hedge(" + upper + ", " + exponent + ")";
      }
      if (clause.negated) {
        std::swap(lower, upper);
        lower = "fmpc_math::fuzzy_not(" + lower + ")";
        upper = "fmpc_math::fuzzy_not(" + upper + ")";
      }
      line("  const T " + name + "_l = " + lower + ";");
      line("  const T " + name + "_u = " + upper + ";");
    }
    return {name + "_l", name + "_u"};
  }

  // Firing intervals [fl_r, fu_r]: the clauses folded in input order from the connective's identity, on each end
  // (interpreter's compute_firing_intervals; every norm is nondecreasing, so the ends map to the ends), then the
  // span of the two ends times the weight. Grades cannot be NaN here (a NaN input returns first), so min and max
  // skip nan_min's NaN branches, as in type-1 code. Folding the first clause into the identity is skipped where
  // that is exact: T(1, a) = a and S(0, a) = a for grades in [0, 1], but for the Einstein product, whose
  // 2 - (1 + a - a) may round.
  void emit_firing_intervals() {
    // Mamdani rules without a consequent leave their firing unused.
    std::vector<bool> used(system_.rules.size(), system_.type == SystemType::Sugeno);
    for (std::size_t r = 0; r < system_.rules.size(); ++r)
      for (const Clause& clause : system_.rules[r].consequent)
        if (clause.variable >= 0 && static_cast<std::size_t>(clause.variable) < system_.outputs.size())
          used[r] = true;
    for (std::size_t r = 0; r < system_.rules.size(); ++r) {
      const Rule& rule = system_.rules[r];
      line("  // " + cpp_comment_text(system_.rule_display_name(r)));
      directives_.to_rule(rule.range, out_);
      std::vector<Clause> antecedent = rule.antecedent;
      std::stable_sort(antecedent.begin(), antecedent.end(),
                       [](const Clause& a, const Clause& b) { return a.variable < b.variable; });
      const bool conjunction = rule.connective == Connective::And;
      const std::string identity = conjunction ? "T(1)" : "T(0)";
      // Grades folded in by the specialize pass (Rule::folded_grade, folded_grade_lower) start the fold.
      const bool folded = rule.folded_grade.has_value();
      std::string lower = identity, upper = identity;
      if (folded) {
        upper = cpp_constant(*rule.folded_grade);
        lower = cpp_constant(rule.folded_grade_lower.value_or(*rule.folded_grade));
      }
      for (std::size_t c = 0; c < antecedent.size(); ++c) {
        const auto [mu_lower, mu_upper] = clause_ends(antecedent[c]);
        if (c == 0 && !folded && !(conjunction && system_.and_method == TNorm::EinsteinProduct)) {
          lower = mu_lower;
          upper = mu_upper;
        } else if (conjunction) {
          lower = tnorm_call(system_.and_method, lower, mu_lower);
          upper = tnorm_call(system_.and_method, upper, mu_upper);
        } else {
          lower = snorm_call(system_.or_method, lower, mu_lower);
          upper = snorm_call(system_.or_method, upper, mu_upper);
        }
      }
      const std::string rs = std::to_string(r);
      line("  const T sl" + rs + " = " + lower + ";");
      line("  const T su" + rs + " = " + upper + ";");
      // 1 * s == s exactly.
      const std::string weight = rule.weight == 1.0 ? "" : cpp_constant(rule.weight) + " * ";
      line("  const T fl" + rs + " = " + weight + "grade_min(sl" + rs + ", su" + rs + ");");
      line("  const T fu" + rs + " = " + weight + "grade_max(sl" + rs + ", su" + rs + ");");
      if (!used[r]) line("  (void)fl" + rs + ";  (void)fu" + rs + ";");
      if (system_.type == SystemType::Mamdani) emit_column_updates(r);
      directives_.back_to_header(out_);
    }
  }

  // Columns of a Mamdani output's aggregate: (strength ends, the consequent's grades at the samples). A rule that
  // did not fire (upper end not above 0) is skipped by the interpreter; here its column gets strength 0, and
  // implication(0, g) == 0 is the identity of every aggregation, exactly. With max aggregation and min or prod
  // implication, rules with the same consequent share a column of strength max(w) on each end:
  // max(min(w1, g), min(w2, g)) = min(max(w1, w2), g), and the same for w g with g >= 0 (rounding is monotone), so
  // the merge is exact. The strengths are accumulated right after each rule, so that a rule's firing interval
  // dies there (on a GPU, 247 live firing intervals spill).
  void plan_mamdani_columns() {
    const bool merge = system_.aggregation == SNorm::Maximum &&
                       (system_.implication == TNorm::Minimum || system_.implication == TNorm::Product);
    columns_.assign(system_.outputs.size(), {});
    rule_columns_.assign(system_.rules.size(), {});
    for (std::size_t o = 0; o < system_.outputs.size(); ++o) {
      std::map<std::tuple<int, int, bool>, std::size_t> column_of_consequent;
      for (const OutputConsequent& consequent : consequents_on_output(system_, o)) {
        const Clause& clause = *consequent.clause;
        const auto key = std::make_tuple(clause.term, static_cast<int>(clause.hedge), clause.negated);
        const auto found = merge ? column_of_consequent.find(key) : column_of_consequent.end();
        std::size_t c = 0;
        if (found != column_of_consequent.end()) {
          c = found->second;
        } else {
          c = columns_[o].size();
          column_of_consequent.emplace(key, c);
          const std::string cs = std::to_string(o) + "_" + std::to_string(c);
          columns_[o].push_back({&clause, "cl" + cs, "cu" + cs, false});
        }
        rule_columns_[consequent.rule].emplace_back(o, c);
      }
    }
    for (const auto& columns : columns_)
      for (const Column& column : columns) line("  T " + column.lower + " = T(0), " + column.upper + " = T(0);");
  }

  void emit_column_updates(std::size_t r) {
    const std::string rs = std::to_string(r);
    const std::string gated_upper = "(fu" + rs + " > T(0) ? fu" + rs + " : T(0))";
    const std::string gated_lower = "(fu" + rs + " > T(0) ? fl" + rs + " : T(0))";
    for (const auto& [o, c] : rule_columns_[r]) {
      Column& column = columns_[o][c];
      if (column.assigned) {
        line("  " + column.lower + " = grade_max(" + column.lower + ", " + gated_lower + ");");
        line("  " + column.upper + " = grade_max(" + column.upper + ", " + gated_upper + ");");
      } else {
        line("  " + column.lower + " = " + gated_lower + ";");
        line("  " + column.upper + " = " + gated_upper + ";");
        column.assigned = true;
      }
    }
  }

  void emit_no_fire(std::size_t o, const std::string& indent) {
    line(indent + "flags |= kFlagNoRuleFired;");
    if (system_.no_fire == NoFirePolicy::Error) line(indent + "flags |= kFlagNoFireError;");
    line(indent + "y = yl = yr = " + no_fire_value(system_, o) + ";");
  }

  void emit_nan_output(const std::string& indent) { line(indent + "y = yl = yr = fmpc_math::fmpc_quiet_nan<T>();"); }

  // KM and EKM end within N + 1 steps (kernels/type_reduction_math.h): their cap is a bug, flagged, never a number.
  void emit_internal_error(const std::string& indent) {
    line(indent + "flags |= kFlagInternalError;");
    emit_nan_output(indent);
  }

  void emit_output_store(std::size_t o) {
    const std::string os = std::to_string(o);
    line("    outputs[" + os + "] = y;");
    line("    if (lower != nullptr) lower[" + os + "] = yl;");
    line("    if (upper != nullptr) upper[" + os + "] = yr;");
    line("  }");
  }

  // Mamdani (interpreter's mamdani_type2_output): implication and aggregation on each end of the sampled
  // consequents, the ends put in order where an unclipped `sum` made them cross, then type reduction over the
  // sample points. The consequents' [lower, upper] grades at the samples, hedged and negated, are computed here
  // in double with the interpreter's functions and become constant tables.
  void emit_mamdani_output(std::size_t o) {
    const Variable& output = system_.outputs[o];
    const std::string os = std::to_string(o);
    const std::vector<double> x = output_sample_points(output.min, output.max, system_.samples, Reference::Matlab);
    const std::string n = std::to_string(x.size());
    line("  // output " + cpp_comment_text(output.name) + ": " + n +
         " samples of the aggregated [lower, upper] sets, then type reduction (" +
         to_string(system_.type_reduction) + ")");
    line("  {");
    line("    T y = T(0), yl = T(0), yr = T(0);");

    std::vector<std::pair<std::string, std::string>> strengths;  // (lower, upper) locals
    std::vector<std::vector<double>> grades_lower, grades_upper;
    for (const Column& column : columns_[o]) {
      strengths.emplace_back(column.lower, column.upper);
      const Clause& clause = *column.clause;
      std::vector<double> lower(x.size()), upper(x.size());
      const Term& term = output.terms[static_cast<std::size_t>(clause.term)];
      for (std::size_t k = 0; k < x.size(); ++k) {
        GradeInterval<double> mu = term_membership(term, x[k]);
        mu = interval_hedge(mu, hedge_exponent(clause.hedge));
        if (clause.negated) mu = interval_not(mu);
        lower[k] = mu.lower;
        upper[k] = mu.upper;
      }
      grades_lower.push_back(std::move(lower));
      grades_upper.push_back(std::move(upper));
    }
    std::string fired;
    for (const auto& strength : strengths) fired += (fired.empty() ? "(" : " || (") + strength.second + " > T(0))";
    if (strengths.empty()) {  // no rule concludes on this output
      emit_no_fire(o, "    ");
      emit_output_store(o);
      return;
    }
    line("    const bool fired = " + fired + ";");
    line("    if (!fired) {");
    emit_no_fire(o, "      ");
    line("    } else {");
    // Matrices even with one column, which the loop below indexes as [c][k].
    out_.double_table("      ", "kLowerGrades", grades_lower, x.size(), true);
    out_.double_table("      ", "kUpperGrades", grades_upper, x.size(), true);
    out_.double_table("      ", "kSamplePoints", {x}, x.size(), true);
    line("      T aggregate_lower[" + n + "], aggregate_upper[" + n + "], points[" + n + "];");
    line("      bool nan = false;");
    line("      FMPC_GENERATED_UNROLL");
    line("      for (int k = 0; k < " + n + "; ++k) {");
    for (std::size_t c = 0; c < strengths.size(); ++c) {
      const std::string cs = std::to_string(c);
      const std::string implied_lower =
          tnorm_call(system_.implication, strengths[c].first, "T(kLowerGrades[" + cs + "][k])");
      const std::string implied_upper =
          tnorm_call(system_.implication, strengths[c].second, "T(kUpperGrades[" + cs + "][k])");
      // The first column is taken as is: aggregation(0, v) == v for every s-norm and v >= 0.
      if (c == 0) {
        line("        T l = " + implied_lower + ";");
        line("        T u = " + implied_upper + ";");
      } else {
        line("        l = " + snorm_call(system_.aggregation, "l", implied_lower) + ";");
        line("        u = " + snorm_call(system_.aggregation, "u", implied_upper) + ";");
      }
    }
    line("        if (fmpc_math::fmpc_is_nan(l) || fmpc_math::fmpc_is_nan(u)) {");
    line("          nan = true;");
    line("        } else if (l > u) {  // crossed past 1 after an unclipped sum: keep the span");
    line("          const T crossed = l;");
    line("          l = u;");
    line("          u = crossed;");
    line("        }");
    line("        aggregate_lower[k] = l;");
    line("        aggregate_upper[k] = u;");
    line("        points[k] = T(kSamplePoints[0][k]);");
    line("      }");
    line("      if (nan) {");
    emit_nan_output("        ");
    line("      } else {");
    line("        const fmpc_math::TypeReducedInterval<T> reduced = fmpc_math::reduce_type(" +
         std::string(type_reduction_enumerator(system_.type_reduction)) + ", points, aggregate_lower, " +
         "aggregate_upper, " + n + ");");
    line("        if (reduced.iteration_cap_hit) {");
    emit_internal_error("          ");
    line("        } else if (!reduced.fired) {");
    emit_no_fire(o, "          ");
    line("        } else {");
    line("          yl = reduced.left;");
    line("          yr = reduced.right;");
    line("          y = (yl + yr) / T(2);");
    line("        }");
    line("      }");
    line("    }");
    emit_output_store(o);
  }

  // Sugeno (interpreter's sugeno_type2_output): each rule that fired gives a point [z_low, z_high] with weights
  // [lower, upper]; rules without a consequent on this output count as z = 0 with their firing interval (fis.c).
  // wtsum, and wtaver where every weight and z is exact, sum directly; wtaver otherwise type-reduces the points
  // sorted by z_low (yl) and, where some z is an interval, by z_high (yr).
  void emit_sugeno_output(std::size_t o) {
    const Variable& output = system_.outputs[o];
    const std::vector<OutputConsequent> consequents = consequents_on_output(system_, o);
    const bool weighted_sum = system_.defuzzifier == Defuzzifier::WeightedSum;
    std::vector<bool> concludes(system_.rules.size(), false);
    bool interval_values = false;
    for (const OutputConsequent& consequent : consequents) {
      concludes[consequent.rule] = true;
      const Term& term = output.terms[static_cast<std::size_t>(consequent.clause->term)];
      interval_values = interval_values || (term.footprint && term.footprint->kind == FootprintKind::IntervalValue);
    }
    const std::size_t capacity = std::max<std::size_t>(1, consequents.size() +
                                                              static_cast<std::size_t>(std::count(
                                                                  concludes.begin(), concludes.end(), false)));
    const std::string p = std::to_string(capacity);
    line("  // output " + cpp_comment_text(output.name) + ": " + to_string(system_.defuzzifier) +
         (weighted_sum ? "" : std::string(", type reduction ") + to_string(system_.type_reduction)));
    line("  {");
    line("    T y = T(0), yl = T(0), yr = T(0);");
    // Zero-initialised: only n <= capacity elements are set, and compilers cannot see that n bounds every read.
    line("    T z_low[" + p + "] = {}, z_high[" + p + "] = {}, w_low[" + p + "] = {}, w_high[" + p + "] = {};");
    line("    int n = 0;");
    line("    bool fired = false;");
    for (const OutputConsequent& consequent : consequents) {
      const std::string rs = std::to_string(consequent.rule);
      const Clause& clause = *consequent.clause;
      const Term& term = output.terms[static_cast<std::size_t>(clause.term)];
      line("    if (fu" + rs + " != T(0)) {");
      line("      fmpc_math::GradeInterval<T> h{fl" + rs + ", fu" + rs + "};");
      // Octave's eval_rules_sugeno hedges the height as w^(1/hedge), then negates it (interpreter).
      if (clause.hedge != Hedge::None) {
        const std::string power = cpp_constant(1.0 / hedge_exponent(clause.hedge));
        line("      h.lower = fmpc_math::fmpc_pow(h.lower, " + power + ");");
        line("      h.upper = fmpc_math::fmpc_pow(h.upper, " + power + ");");
      }
      if (clause.negated) line("      h = fmpc_math::interval_not(h);");
      line("      fired = fired || h.upper != T(0);");
      if (term.footprint && term.footprint->kind == FootprintKind::IntervalValue) {
        line("      z_low[n] = " + cpp_constant(term.footprint->first) + ";");
        line("      z_high[n] = " + cpp_constant(term.footprint->second) + ";");
      } else {
        line("      z_low[n] = " + sugeno_value(term.mf, system_.inputs.size()) + ";");
        line("      z_high[n] = z_low[n];");
      }
      line("      w_low[n] = h.lower;");
      line("      w_high[n] = h.upper;");
      line("      ++n;");
      line("    }");
    }
    for (std::size_t r = 0; r < system_.rules.size(); ++r) {
      if (concludes[r]) continue;
      const std::string rs = std::to_string(r);
      line("    z_low[n] = z_high[n] = T(0);");
      line("    w_low[n] = fl" + rs + ";");
      line("    w_high[n] = fu" + rs + ";");
      line("    ++n;");
    }
    line(std::string("    bool nan = false") + (weighted_sum ? "" : ", exact = true") + ";");
    line("    for (int i = 0; i < n; ++i) {");
    line("      nan = nan || fmpc_math::fmpc_is_nan(z_low[i]) || fmpc_math::fmpc_is_nan(z_high[i]) ||");
    line("            fmpc_math::fmpc_is_nan(w_low[i]) || fmpc_math::fmpc_is_nan(w_high[i]);");
    if (!weighted_sum) line("      exact = exact && w_low[i] == w_high[i] && z_low[i] == z_high[i];");
    line("    }");
    line("    if (!fired) {");
    emit_no_fire(o, "      ");
    line("    } else if (nan) {");
    emit_nan_output("      ");
    line(weighted_sum ? "    } else {" : "    } else if (exact) {");
    // Each term takes the weight end that lowers (yl) or raises (yr) it; with exact weights and z this is the
    // type-1 weighted average, in rule order.
    line("      T sum_low = T(0), sum_high = T(0), total = T(0);");
    line("      for (int i = 0; i < n; ++i) {");
    line("        sum_low += z_low[i] * (z_low[i] >= T(0) ? w_low[i] : w_high[i]);");
    line("        sum_high += z_high[i] * (z_high[i] >= T(0) ? w_high[i] : w_low[i]);");
    line("        total += w_high[i];");
    line("      }");
    if (weighted_sum) {
      line("      (void)total;");
      line("      yl = sum_low;");
      line("      yr = sum_high;");
      line("      y = yl == yr ? yl : (yl + yr) / T(2);");
    } else {
      line("      (void)sum_high;");
      line("      if (total == T(0)) {");
      emit_no_fire(o, "        ");
      line("      } else {");
      line("        y = yl = yr = sum_low / total;");
      line("      }");
    }
    if (!weighted_sum) {
      line("    } else {");
      line("      T points[" + p + "] = {}, sorted_low[" + p + "] = {}, sorted_high[" + p + "] = {};");
      line("      sort_type2_points(z_low, w_low, w_high, n, points, sorted_low, sorted_high);");
      const std::string method = type_reduction_enumerator(system_.type_reduction);
      line("      const fmpc_math::TypeReducedInterval<T> left = fmpc_math::reduce_type(" + method +
           ", points, sorted_low, sorted_high, n);");
      line("      if (left.iteration_cap_hit) {");
      emit_internal_error("        ");
      line("      } else if (!left.fired) {");
      emit_no_fire(o, "        ");
      line("      } else {");
      line("        yl = left.left;");
      line("        yr = left.right;");
      if (interval_values) {
        line("        bool crisp_z = true;");
        line("        for (int i = 0; i < n; ++i) crisp_z = crisp_z && z_low[i] == z_high[i];");
        line("        if (!crisp_z) {");
        line("          sort_type2_points(z_high, w_low, w_high, n, points, sorted_low, sorted_high);");
        line("          const fmpc_math::TypeReducedInterval<T> right = fmpc_math::reduce_type(" + method +
             ", points, sorted_low, sorted_high, n);");
        line("          yr = right.right;");
        line("          if (right.iteration_cap_hit) {");
        emit_internal_error("            ");
        line("          }");
        line("        }");
      }
      line("        y = (yl + yr) / T(2);");
      line("      }");
    }
    line("    }");
    emit_output_store(o);
  }

  const FuzzySystem& system_;
  const EmitOptions& options_;
  CodeWriter& out_;
  std::set<std::string> emitted_;
  LineDirectives directives_{options_};
  struct Column {
    const Clause* clause;
    std::string lower, upper;  // the locals holding its strength ends
    bool assigned;             // a rule has set it (later ones take the max)
  };
  std::vector<std::vector<Column>> columns_;                              // per Mamdani output
  std::vector<std::vector<std::pair<std::size_t, std::size_t>>> rule_columns_;  // per rule: (output, column)
};

}  // namespace

void emit_type2_evaluate_function(const FuzzySystem& system, const EmitOptions& options, CodeWriter& out) {
  Type2Emitter(system, options, out).emit();
}

}  // namespace fmpc
