#pragma once
// Plain enumerations shared by the IR, the interpreter, the CUDA kernels and generated code. The numeric values
// are part of the compiled-artefact format (.fzt, generated headers): append, never renumber.

namespace fmpc {

// Membership function families. Parameters are always stored in MATLAB's order (the "[...]" column).
enum class MfKind : int {
  Triangle = 0,           // trimf   [a b c]            feet a, c; peak b
  Trapezoid = 1,          // trapmf  [a b c d]          feet a, d; shoulders b, c
  Gaussian = 2,           // gaussmf [sigma c]
  Gaussian2 = 3,          // gauss2mf [sigma1 c1 sigma2 c2]
  GeneralizedBell = 4,    // gbellmf [a b c]            1 / (1 + |(x-c)/a|^(2b))
  Sigmoid = 5,            // sigmf   [a c]              1 / (1 + exp(-a (x-c)))
  DifferenceSigmoid = 6,  // dsigmf  [a1 c1 a2 c2]      sig1 - sig2
  ProductSigmoid = 7,     // psigmf  [a1 c1 a2 c2]      sig1 * sig2
  ZShape = 8,             // zmf     [a b]
  SShape = 9,             // smf     [a b]
  PiShape = 10,           // pimf    [a b c d]          smf(a,b) * zmf(c,d)
  LinearS = 11,           // linsmf  [a b]              0 below a, 1 above b, linear between
  LinearZ = 12,           // linzmf  [a b]              1 below a, 0 above b, linear between
  Constant = 13,          // Sugeno output: [c]
  Linear = 14,            // Sugeno output: [p1 ... pn c]  z = sum p_i x_i + c
};

inline constexpr int kMaxMfParams = 4;  // every type-1 input MF fits; Linear outputs keep their own vector

enum class TNorm : int { Minimum = 0, Product = 1, EinsteinProduct = 2 };
enum class SNorm : int { Maximum = 0, ProbabilisticSum = 1, Sum = 2, EinsteinSum = 3 };

// Hedges are powers of the membership grade (Zadeh 1972): the exponent is the hedge's meaning.
enum class Hedge : int { None = 0, Somewhat = 1, Very = 2, Extremely = 3, VeryVery = 4 };

}  // namespace fmpc
