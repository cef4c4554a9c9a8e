#pragma once
// evaluate_batch of the liver evaluator built with -march=x86-64-v3 (evaluator_x86_64_v3.cpp).
#include <cstddef>

void liver_batch_x86_64_v3(const double* inputs, double* outputs, std::size_t n);
void liver_batch_x86_64_v3(const float* inputs, float* outputs, std::size_t n);
