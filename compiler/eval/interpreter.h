#pragma once
// The reference interpreter: type-1 Mamdani and Sugeno in double, with MATLAB's semantics by default
// (docs/numerics.md). Every faster path in fmpc states its error against this one.
#include <memory>
#include <vector>

#include "compiler/ir/fuzzy_system.h"

namespace fmpc {

// What happened during one evaluation that a caller may want to report. Never printed here.
struct EvaluationFlags {
  std::vector<int> inputs_out_of_range;   // indices of inputs outside [min, max] (evaluated as given)
  std::vector<int> inputs_nan;            // indices of NaN inputs (their outputs are NaN)
  std::vector<int> outputs_no_rule_fired; // outputs for which the no-fire policy applied
  bool no_fire_error = false;             // policy `error` was hit: those outputs are NaN
};

// The type-reduced interval [yl, yr] of one output of an interval type-2 system and how it was found
// (kernels/type_reduction_math.h). The crisp output is (yl + yr) / 2. When the no-fire policy applied, both ends
// are its value (NaN for `error`) and the switch points are -1.
struct TypeReducedOutput {
  double lower = 0.0;  // yl
  double upper = 0.0;  // yr
  TypeReduction method = TypeReduction::KarnikMendel;
  int left_switch = -1;        // k for yl: the k smallest points take their upper weight
  int right_switch = -1;       // k for yr: the k smallest points take their lower weight
  double left_switch_x = 0.0;  // the k-th smallest point for yl (NaN when k == 0 or no reduction ran)
  double right_switch_x = 0.0;
  int left_iterations = 0;
  int right_iterations = 0;
};

struct Evaluation {
  std::vector<double> outputs;           // one per output variable
  std::vector<double> firing_strengths;  // one per rule: antecedent strength times weight (type-2: upper end)
  EvaluationFlags flags;
  // Interval type-2 systems only (empty for type-1): the lower end of each rule's firing interval, and per output
  // the type-reduced interval.
  std::vector<double> firing_lower;
  std::vector<TypeReducedOutput> intervals;
};

// Aggregated output fuzzy set of a Mamdani output, sampled where the defuzzifier sampled it (101 points by
// default; for `samples exact`, the points the quadrature used, sorted). Sugeno outputs give the (value, weight)
// pairs instead.
struct OutputExplanation {
  std::vector<double> x;
  std::vector<double> membership;  // Mamdani: aggregated grade at x; Sugeno: rule weight at rule output x
  // Interval type-2: `membership` is the upper end, this the lower end (Sugeno: x is each rule's lowest output).
  std::vector<double> membership_lower;
};

struct Explanation {
  Evaluation evaluation;
  std::vector<OutputExplanation> outputs;
};

// Where MATLAB and GNU Octave's fuzzy-logic-toolkit 0.4.6 compute different numbers from the same .fis file,
// which one to follow (docs/numerics.md lists every difference). Matlab is fmpc's semantics; Octave exists to
// reproduce Octave's numbers (the goldens in ../shared/data/matlab-fis/golden were computed by Octave).
enum class Reference { Matlab, Octave };

struct EvaluationOptions {
  Reference reference = Reference::Matlab;
};

// [lower, upper] grade of x in `term` (kernels/type2_math.h); a term without a footprint gives [mu, mu].
GradeInterval<double> term_membership(const Term& term, double x);

// Evaluates `system` at `inputs` (one value per input variable, in declaration order).
// Precondition: the system passed sema without errors and inputs.size() == system.inputs.size().
// Throws std::logic_error where Karnik-Mendel or EKM type reduction reaches its iteration cap, which their
// strictly improving steps rule out (kernels/type_reduction_math.h): a bug in fmpc, never a returned number.
Evaluation evaluate(const FuzzySystem& system, const std::vector<double>& inputs);
Explanation explain(const FuzzySystem& system, const std::vector<double>& inputs);
Evaluation evaluate(const FuzzySystem& system, const std::vector<double>& inputs, const EvaluationOptions& options);
Explanation explain(const FuzzySystem& system, const std::vector<double>& inputs, const EvaluationOptions& options);

// For many evaluations of one system (tables, sweeps, benchmarks): samples the output terms once and reuses its
// buffers, so an evaluation allocates only its result. Not thread-safe; use one per thread.
class Interpreter {
 public:
  explicit Interpreter(const FuzzySystem& system, EvaluationOptions options = {});
  ~Interpreter();
  Interpreter(Interpreter&&) noexcept;
  Interpreter& operator=(Interpreter&&) noexcept;
  Interpreter(const Interpreter&) = delete;
  Interpreter& operator=(const Interpreter&) = delete;

  Evaluation evaluate(const std::vector<double>& inputs);
  Explanation explain(const std::vector<double>& inputs);
  // The system without rule `rule` (its weight taken as 0: a rule that does not fire adds nothing to any aggregate
  // or denominator, so this is exactly the evaluation of the system with the rule erased), for leave-one-rule-out
  // contributions (rule_contributions.h) without copying the system per rule.
  Evaluation evaluate_without_rule(const std::vector<double>& inputs, std::size_t rule);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace fmpc
