// The liver evaluator compiled with the build's flags and FMPC_NO_TARGET_CLONES (CMakeLists.txt): evaluate_batch for
// the baseline target only (x86-64: SSE2), what a compiler without target_clones gives. Its own header (namespace
// liver_evaluator_baseline), so that no inline function is shared with the other builds.
#include "evaluator_baseline.h"

#include "liver_evaluator_baseline.h"

void liver_batch_baseline(const double* inputs, double* outputs, std::size_t n) {
  liver_evaluator_baseline::evaluate_batch(inputs, outputs, n);
}
void liver_batch_baseline(const float* inputs, float* outputs, std::size_t n) {
  liver_evaluator_baseline::evaluate_batch(inputs, outputs, n);
}
