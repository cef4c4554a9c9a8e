#pragma once
#include <cuda_runtime_api.h>

#include <string>

#include "diagnostics/diagnostic.h"

// Checks a CUDA call; on failure appends an error naming the call and CUDA's reason, and returns `failure` from
// the enclosing function. Never exits.
#define FMPC_CUDA_CHECK(call, diagnostics, failure)                                                   \
  do {                                                                                                \
    const cudaError_t fmpc_cuda_status = (call);                                                      \
    if (fmpc_cuda_status != cudaSuccess) {                                                            \
      (diagnostics)                                                                                   \
          .error(::fmpc::SourceRange{}, std::string("CUDA: ") + #call +                               \
                                            " failed: " + cudaGetErrorName(fmpc_cuda_status) + " (" + \
                                            cudaGetErrorString(fmpc_cuda_status) + ")");              \
      return failure;                                                                                 \
    }                                                                                                 \
  } while (false)
