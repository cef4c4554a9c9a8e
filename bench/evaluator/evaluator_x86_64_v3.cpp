// The same liver evaluator compiled for x86-64-v3 (AVX2, FMA) and FMPC_NO_TARGET_CLONES (CMakeLists.txt): its own
// header (namespace liver_evaluator_v3), so that no inline function is shared with the other builds.
// evaluator_bench.cpp calls it only where the CPU has AVX2 and FMA.
#include "evaluator_x86_64_v3.h"

#include "liver_evaluator_v3.h"

void liver_batch_x86_64_v3(const double* inputs, double* outputs, std::size_t n) {
  liver_evaluator_v3::evaluate_batch(inputs, outputs, n);
}
void liver_batch_x86_64_v3(const float* inputs, float* outputs, std::size_t n) {
  liver_evaluator_v3::evaluate_batch(inputs, outputs, n);
}
