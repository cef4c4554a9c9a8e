#pragma once
// Rule files of the material.bind tests (tests/unit/parameter_binding_test.cpp, tests/gpu/
// gpu_parameter_binding_test.cpp): Sugeno systems with one rule that always fires, so that each output is its linear
// model of the inputs.

namespace fmpc::test_rules {

// E = 2 F + 1 kPa and nu = 0.3 + 0.01 F: two outputs of one input.
inline constexpr const char* kTwoOutputRules = R"(system tissue
  type sugeno
input F in [0, 10]
  all is gauss(mean 5, sd 1000)
output stiffness in [0, 30] kPa
  model is linear(F 2, offset 1)
output nu in [0.3, 0.45] dimensionless
  model is linear(F 0.01, offset 0.3)
rule r1: if F is all then stiffness is model and nu is model
)";

// E = 10 (1 + 2 s) kPa over strain s in [-0.3, 0.3]: linear in s, so that a strain table interpolates it exactly (to
// rounding) between any breakpoints.
inline constexpr const char* kStrainStiffeningRules = R"(system stiffening
  type sugeno
input s in [-0.3, 0.3]
  all is gauss(mean 0, sd 1000)
output stiffness in [0, 30] kPa
  model is linear(s 20, offset 10)
rule r1: if s is all then stiffness is model
)";

// E = 2 F + 1 kPa and two Prony weights, fast = 0.2 + 0.02 F and slow = 0.1 + 0.02 F (declared ranges [0.2, 0.4] and
// [0.1, 0.3]: their sum stays below 1).
inline constexpr const char* kPronyWeightRules = R"(system tissue
  type sugeno
input F in [0, 10]
  all is gauss(mean 5, sd 1000)
output stiffness in [0, 30] kPa
  model is linear(F 2, offset 1)
output fast in [0.2, 0.4]
  model is linear(F 0.02, offset 0.2)
output slow in [0.1, 0.3]
  model is linear(F 0.02, offset 0.1)
rule r1: if F is all then stiffness is model and fast is model and slow is model
)";

}  // namespace fmpc::test_rules
