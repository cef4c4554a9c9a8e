#pragma once
// Two versions of a rule system side by side (`fmpc diff`, the studio's comparison panel): what differs in their
// definitions (settings, variables, terms, rules), and what differs in their outputs over a cohort of patients,
// with each patient's stage (the output term that describes the output best) in both.
#include <cstddef>
#include <string>
#include <vector>

#include "compiler/eval/agreement.h"
#include "compiler/eval/interpreter.h"
#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

enum class ChangeKind { Added, Removed, Changed };

// A variable or term is matched by name (terms within the variable of the same name and role), so a renamed one
// is reported as removed and added.
struct VariableChange {
  ChangeKind kind = ChangeKind::Changed;
  bool output = false;
  int in_a = -1;  // index into a's inputs or outputs; -1 when added
  int in_b = -1;  // index into b's; -1 when removed
  std::vector<std::string> what;  // Changed: "range [0, 75] -> [0, 80]", "unit kPa -> Pa"
};

struct TermChange {
  ChangeKind kind = ChangeKind::Changed;
  bool output = false;
  std::string variable;
  int variable_in_a = -1, variable_in_b = -1;
  int in_a = -1, in_b = -1;  // term indices; -1 when added or removed
  bool family_changed = false;      // Changed: another MF family (trimf -> gaussmf)
  bool parameters_changed = false;  // Changed: the same family, other parameters (MATLAB order)
  bool footprint_changed = false;   // Changed: the type-2 footprint
};

// Rules are matched by label where both versions label them, then by their conditions (the same clauses, by
// variable and term name, in any order, and the same connective), then left over as removed (from a) and added (to
// b). A matched pair is reported only when its conditions, conclusions, weight or connective differ.
struct RuleChange {
  ChangeKind kind = ChangeKind::Changed;
  int in_a = -1;
  int in_b = -1;
  bool conditions_changed = false;
  bool conclusions_changed = false;
  bool weight_changed = false;
};

struct SystemDifferences {
  std::vector<std::string> settings;  // in words: "the defuzzifier changes from centroid to bisector"
  std::vector<VariableChange> variables;
  std::vector<TermChange> terms;
  std::vector<RuleChange> rules;
  bool empty() const { return settings.empty() && variables.empty() && terms.empty() && rules.empty(); }
};

SystemDifferences system_differences(const FuzzySystem& a, const FuzzySystem& b);

// The term of `output` that describes `value` best, by index, or -1 where none does: for a Mamdani output the term
// with the highest grade at value (the upper grade of a type-2 term; the first of equal grades), -1 when every grade
// is 0; for a Sugeno output the `constant` term nearest to value (interval constants by their middle; the first of
// equal distances), -1 when it has none. -1 for NaN.
int dominant_term(const FuzzySystem& system, std::size_t output, double value);

// One output that both systems have (matched by name), over every point.
struct OutputComparisonOverPoints {
  std::string name;
  int in_a = -1, in_b = -1;
  std::vector<double> a, b;  // per point; NaN where the evaluation gave NaN
  std::vector<int> stage_a, stage_b;  // dominant_term in each system; -1 where none
  std::vector<bool> policy_a, policy_b;  // the no-fire policy gave the value
  // b - a per point (NaN where either is NaN) and, over the points where both are finite, measure_agreement(b, a):
  // mean |b - a|, the largest change and where, the mean change (bias) and its spread. `agreement.count` is 0 when
  // no point has two finite values (the other fields are then 0).
  std::vector<double> difference;
  Agreement agreement;
  // Points whose stage differs, by the stage's term name (so that terms reordered or renamed in one version compare
  // by what they are called); a point with a stage in only one system counts as changed.
  std::vector<std::size_t> stage_changes;
};

// The outputs both systems have, from their evaluations at the same points (`evaluations_a[k]` and
// `evaluations_b[k]` at the k-th point). Precondition: both lists have the same length, and came from these systems.
std::vector<OutputComparisonOverPoints> compare_evaluations(const FuzzySystem& a, const FuzzySystem& b,
                                                            const std::vector<Evaluation>& evaluations_a,
                                                            const std::vector<Evaluation>& evaluations_b);

// Evaluates both systems and compares them: `points_a[k]` and `points_b[k]` are the k-th point as each system's
// input vector (a CSV column per input name, laid out per system by the caller). Precondition: both systems passed
// sema; the point lists have equal length and each point fits its system.
std::vector<OutputComparisonOverPoints> compare_over_points(const FuzzySystem& a, const FuzzySystem& b,
                                                            const std::vector<std::vector<double>>& points_a,
                                                            const std::vector<std::vector<double>>& points_b,
                                                            const EvaluationOptions& options = {});

}  // namespace fmpc
