#pragma once
// The reference for the generated CUDA evaluator's device test: the interpreter on the rule file the header was
// generated from. Compiled by the host compiler (the test's .cu file includes only this declaration), so nvcc never
// parses the compiler's headers.
#include <cstddef>
#include <string>
#include <vector>

namespace fmpc::gpu_test {

struct ReferenceEvaluation {
  std::vector<double> outputs;  // count x outputs, row-major
  std::vector<unsigned> flags;  // per point, in the generated evaluator's kFlag* bits
  std::string error;            // non-empty when the rule file could not be loaded
};

// Evaluates the first system of `rule_file` at `count` points (row-major, `inputs` values each).
ReferenceEvaluation interpret_rule_file(const std::string& rule_file, const double* points, std::size_t count,
                                        std::size_t inputs);

}  // namespace fmpc::gpu_test
