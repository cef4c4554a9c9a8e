#include "compiler/backend/cpp/lane_batch_emitter.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "compiler/eval/defuzzify.h"
#include "diagnostics/number_format.h"

namespace fmpc {

namespace {

// The consequents of output `o` that share a column of the aggregate: same term, hedge and negation.
using ColumnKey = std::tuple<int, int, bool>;
ColumnKey column_key(const Clause& clause) {
  return {clause.term, static_cast<int>(clause.hedge), clause.negated};
}

// Unrolled aggregation costs (columns x samples) statements; beyond this the header would be too long to compile
// quickly, and evaluate_batch keeps the loop over evaluate().
constexpr std::size_t kMaxUnrolledAggregation = 16384;

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
      out_.number_rows("    ", values);
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
    std::vector<std::string> lane_x;
    for (std::size_t i = 0; i < input_count; ++i) lane_x.push_back("x[" + std::to_string(i) + "][j]");
    std::string slow_test = any_nan_test(lane_x);
    const std::string range_test = out_of_range_test(system_, lane_x);
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
        value = "lane_gaussian(" + x + ", " + cpp_constant(mf.params[0]) + ", " + cpp_constant(mf.params[1]) + ", lowest)";
        uses_lane_exp_ = true;
      } else {
        value = membership_call(mf, x);
      }
      const Term& term = input.terms[static_cast<std::size_t>(clause.term)];
      grade_lines_.push_back("T " + base + "[kBatchLanes];  // " + cpp_comment_text(input.name + " is " + term.name));
      grade_lines_.push_back("for (std::size_t j = 0; j < kBatchLanes; ++j) " + base + "[j] = " + value + ";");
    }
    if (clause.hedge == Hedge::None && !clause.negated) return base + "[j]";
    // Hedge first, then negation (interpreter's clause_grade).
    const std::string name =
        base + "_h" + std::to_string(static_cast<int>(clause.hedge)) + (clause.negated ? "_not" : "");
    if (emitted_arrays_.insert(name).second) {
      std::string value = base + "[j]";
      if (clause.hedge != Hedge::None)
        value = "fmpc_math::apply_hedge(" + value + ", " + cpp_constant(hedge_exponent(clause.hedge)) + ")";
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
    std::string value = rule.folded_grade ? cpp_constant(*rule.folded_grade) : conjunction ? "T(1)" : "T(0)";
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
                          (rule.weight == 1.0 ? value : cpp_constant(rule.weight) + " * (" + value + ")") + ";");
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
      if (rule.folded_grade) literals.push_back(literal(cpp_constant(*rule.folded_grade)));
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
    body_lines_.push_back("{  // output " + cpp_comment_text(output.name) + ": " + std::to_string(x.size()) +
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
                            (offset == 0.0 ? std::string() : " moment_" + p + " += g * " + cpp_constant(offset) + ";") +
                            " }");
    }
    body_lines_.push_back("  const T total = (total_0 + total_1) + (total_2 + total_3);");
    body_lines_.push_back("  const T moment = (moment_0 + moment_1) + (moment_2 + moment_3);");
    body_lines_.push_back("  value" + os + "[j] = " + cpp_constant(middle) + " + moment / total;");
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

}  // namespace

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

void emit_lane_batch(const FuzzySystem& system, const std::string& lane_exp_text, CodeWriter& out) {
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
  out.block(lane_exp_text);
  out.line();
  LaneBatchEmitter(system, out).emit();
}

}  // namespace fmpc
