#pragma once
// The vectorisable exp of generated evaluate_batch functions (docs/codegen.md, "Batch evaluation"): lane_exp and
// lane_gaussian, host code that GCC vectorises over the lanes of a block. Not FMPC_HD: only evaluate_batch calls it,
// and evaluate_batch runs on the host (the CUDA kernel evaluates point by point through fuzzy_math.h's fmpc_exp).
//
// Like the other *_math.h, generated code carries a verbatim copy (embedded at build time,
// cmake/FmpcEmbedText.cmake), so the text compiled into users' programs is this file's: the emitter copies what
// lies between the namespace's braces below into the generated header's own namespace, after kBatchLanes, and
// only into headers whose evaluate_batch runs lanes (compiler/backend/cpp/lane_batch_emitter.h). Test `[emit]`
// "lane_exp" holds that copy to the accuracy stated below.
#include <cstdint>
#include <cstring>

namespace fmpc {

// exp for the lanes of evaluate_batch:
// Cody-Waite reduction a = n ln2 + r, |r| <= ln2 / 2, a polynomial for exp(r) (double: Taylor to degree 13 by
// Estrin's scheme; float: Cephes expf), then 2^n from its bits. Within 2 ulp of the C library's exp (float: 1 ulp)
// for arguments from `lowest` (-708, float: -86) up; below it, where exp is below 3.3e-308 (float: 4.5e-38), the
// result is 0 (NaN included: NaN lanes are overwritten). So every result is 0 or a normal number: computing a
// subnormal, or a product that rounds to one, costs a microcode assist on x86, and evaluate_batch sends the points
// where such grades could matter to evaluate() (docs/codegen.md "Batch evaluation"). Plain arithmetic, selects and
// bit copies, no branches and no calls, so that compilers vectorise the loops that call it. Arguments must be at
// most 15 (float: 5), which Gaussian exponents (<= 0) are. `lowest` is read from a volatile once per call, not
// written as a constant: with a constant GCC folds the clamped case and turns the clamp into a branch, which stops
// it vectorising the loop.
inline double lane_exp(double argument, double lowest) {
  const double a = argument > lowest ? argument : lowest;
  const double shifted = a * 0x1.71547652b82fep0 + 0x1.8p52;  // 1.5 2^52: the low bits hold n = round(a / ln2)
  const double n = shifted - 0x1.8p52;
  const double r = (a - n * 0x1.62e42feep-1) - n * 0x1.a39ef35793c76p-33;
  // Estrin's scheme: a shorter chain of dependent operations than Horner's, which the lanes' loops wait on.
  const double r2 = r * r, r4 = r2 * r2, r8 = r4 * r4;
  const double low = (1.0 + r) + r2 * (0.5 + r * (1.0 / 6.0));
  const double middle = (1.0 / 24.0 + r * (1.0 / 120.0)) + r2 * (1.0 / 720.0 + r * (1.0 / 5040.0));
  const double high = (1.0 / 40320.0 + r * (1.0 / 362880.0)) + r2 * (1.0 / 3628800.0 + r * (1.0 / 39916800.0));
  const double top = 1.0 / 479001600.0 + r * (1.0 / 6227020800.0);
  const double p = (low + r4 * middle) + r8 * (high + r4 * top);
  // 2^n with n >= -1021 (a >= -708): a normal number, and so is p 2^n (p >= 0.7); 0 below `lowest`. (A select
  // on the bits: GCC turns a select on the result into a branch, which stops it vectorising the loop.)
  std::uint64_t bits;
  std::memcpy(&bits, &shifted, sizeof bits);
  bits = argument >= lowest ? (bits + 1023u) << 52 : 0u;
  double scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}
inline float lane_exp(float argument, float lowest) {
  const float a = argument > lowest ? argument : lowest;
  const float shifted = a * 0x1.715476p0f + 0x1.8p23f;
  const float n = shifted - 0x1.8p23f;
  const float r = (a - n * 0.693359375f) - n * -2.12194440e-4f;
  float p = 1.9875691500e-4f;
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  p = p * (r * r) + r + 1.0f;
  // 2^n with n >= -124 (a >= -86): normal, and so is p 2^n; 0 below `lowest`.
  std::uint32_t bits;
  std::memcpy(&bits, &shifted, sizeof bits);
  bits = argument >= lowest ? (bits + 127u) << 23 : 0u;
  float scale;
  std::memcpy(&scale, &bits, sizeof scale);
  return p * scale;
}
inline const volatile double kLaneExpLowestDouble = -708.0;
inline const volatile float kLaneExpLowestFloat = -86.0f;
inline double lane_exp_lowest(double) { return kLaneExpLowestDouble; }
inline float lane_exp_lowest(float) { return kLaneExpLowestFloat; }

// gaussmf as fmpc_math::mf::gaussian computes it, with lane_exp.
template <typename T>
inline T lane_gaussian(T x, T sigma, T c, T lowest) {
  const T t = (x - c) / sigma;
  return lane_exp(-t * t / T(2), lowest);
}

}  // namespace fmpc
