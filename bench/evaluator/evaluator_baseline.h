#pragma once
// evaluate_batch of the liver evaluator built for the baseline target alone (evaluator_baseline.cpp).
#include <cstddef>

void liver_batch_baseline(const double* inputs, double* outputs, std::size_t n);
void liver_batch_baseline(const float* inputs, float* outputs, std::size_t n);
