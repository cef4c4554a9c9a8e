#include "tests/gpu/evaluator/evaluator_reference.h"

#include <fstream>
#include <sstream>

#include "compiler/eval/interpreter.h"
#include "compiler/frontend/rule_file_loader.h"

namespace fmpc::gpu_test {

ReferenceEvaluation interpret_rule_file(const std::string& rule_file, const double* points, std::size_t count,
                                        std::size_t inputs) {
  ReferenceEvaluation result;
  std::ifstream in(rule_file, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  DiagnosticList diagnostics;
  const RuleFile file = load_rule_file(rule_file, text.str(), diagnostics);
  if (!in || diagnostics.has_errors() || file.systems.empty()) {
    result.error = "cannot load " + rule_file;
    return result;
  }
  Interpreter interpreter(file.systems.front());
  for (std::size_t p = 0; p < count; ++p) {
    const Evaluation evaluation =
        interpreter.evaluate(std::vector<double>(points + p * inputs, points + (p + 1) * inputs));
    // The generated evaluator's flags (emit_cpp.h): NaN input alone, else out of range | no rule fired | error.
    unsigned flags = 0;
    if (!evaluation.flags.inputs_nan.empty()) {
      flags = 1u;
    } else {
      if (!evaluation.flags.inputs_out_of_range.empty()) flags |= 2u;
      if (!evaluation.flags.outputs_no_rule_fired.empty()) flags |= 4u;
      if (evaluation.flags.no_fire_error) flags |= 8u;
    }
    result.flags.push_back(flags);
    result.outputs.insert(result.outputs.end(), evaluation.outputs.begin(), evaluation.outputs.end());
  }
  return result;
}

}  // namespace fmpc::gpu_test
