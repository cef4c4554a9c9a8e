#include "diagnostics/warning_codes.h"

#include <algorithm>

namespace fmpc {

const std::vector<WarningCode>& warning_codes() {
  static const std::vector<WarningCode> codes = {
      // compiler/sema/lint.cpp (docs/lint.md)
      {"unit", "lint"},
      {"term-out-of-range", "lint"},
      {"near-zero-width", "lint"},
      {"lower-exceeds-upper", "lint"},
      {"unused-term", "lint"},
      {"rule-never-fires", "lint"},
      {"duplicate-rule", "lint"},
      {"conflicting-rules", "lint"},
      {"coverage-hole", "lint"},
      {"terms-out-of-order", "lint"},
      // readers and semantic analysis
      {"dont-care-hedge", "matlab"},
      {"duplicate-term", "sema"},
      {"empty-consequent", "matlab"},
      {"extra-params", "matlab"},
      {"identity-hedge", "matlab"},
      {"iasc-as-eiasc", "matlab"},
      {"lower-mf-ignored", "matlab"},
      {"missing-lower-mf", "matlab"},
      {"mf-index", "matlab"},
      {"unknown-version", "matlab"},
      {"duplicate-key", "matlab"},
      {"unknown-key", "matlab"},
      {"missing-key", "matlab"},
      {"format-difference", "fuzzylite"},
      {"renamed-term", "convert"},
      {"matlab-export", "convert"},
      {"matlab-lossy", "convert"},
      {"lossy-conversion", "convert"},
      {"sugeno-approximation", "convert"},
      {"sugeno-constants", "convert"},
      {"type-reduction-ignored", "matlab"},
      {"no-fire-out-of-range", "sema"},
      // evaluation
      {"input-out-of-range", "eval"},
      {"no-rule-fired", "eval"},
      {"nan-output", "plot"},
      {"missing-measurement", "validate, tune"},
      {"precision-dependent", "simulate"},
      {"probe-load", "scene"},
      {"scene-scale", "scene"},
      {"element-locking", "scene"},
      // meshes, scenes and the simulator
      {"mesh-ignored-elements", "scene"},
      {"mesh-repaired", "scene"},
      {"surface-orientation", "mesh"},
      {"surface-smoothed", "mesh"},
      {"mesh-size-field", "scene"},
      {"assumed-unit", "scene"},
      {"unstable-time-step", "simulate"},
      {"undamped-modes", "simulate"},
      {"inverted-elements", "simulate"},
      {"cg-not-converged", "simulate"},
      {"contact-not-settled", "simulate"},
  };
  return codes;
}

bool is_warning_code(const std::string& name) {
  const auto& codes = warning_codes();
  return std::any_of(codes.begin(), codes.end(), [&](const WarningCode& code) { return name == code.name; });
}

}  // namespace fmpc
