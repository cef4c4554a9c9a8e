#pragma once
// FMPC_HD marks functions compiled for both the host and the device: the CPU loops, the CUDA kernels and the
// generated evaluators all include the same *_math.h headers so that the back ends cannot drift apart.
#if defined(__CUDACC__)
#define FMPC_HD __host__ __device__ __forceinline__
#else
#define FMPC_HD inline
#endif

// Unrolls the gathers' loops over a vertex's springs or element corners by 4, so that the loads of four entries are
// in flight together: the sums still add the entries one after another in CSR order, so the result is the same bits
// (the CPU, the GPU and every earlier run agree). nvcc (both passes) and clang spell it `unroll`, GCC `GCC unroll`.
#if defined(__CUDACC__) || defined(__clang__)
#define FMPC_UNROLL_GATHER _Pragma("unroll 4")
#else
#define FMPC_UNROLL_GATHER _Pragma("GCC unroll 4")
#endif

// Unrolls a loop with a constant trip count completely (its arrays then live in registers).
#if defined(__CUDACC__) || defined(__clang__)
#define FMPC_UNROLL_ALL _Pragma("unroll")
#else
#define FMPC_UNROLL_ALL _Pragma("GCC unroll 16")
#endif
