#pragma once
// FMPC_HD marks functions compiled for both the host and the device: the CPU loops, the CUDA kernels and the
// generated evaluators all include the same *_math.h headers so that the back ends cannot drift apart.
#if defined(__CUDACC__)
#define FMPC_HD __host__ __device__ __forceinline__
#else
#define FMPC_HD inline
#endif
