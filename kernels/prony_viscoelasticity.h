#pragma once
// Per-point state of an element term, and its first user: finite-strain viscoelasticity by a Prony series on any law.
//
// State (PointStateView): a term may keep `width` values per material point (an element kind has kPoints points per
// element: the linear tetrahedron one), value k of point p at values[k * points + p] (structure of arrays: a warp's
// points read consecutive addresses). The state changes only after an accepted step (point_state_update, run by the
// CPU loop and the CUDA kernel alike), never during one, so that every force evaluation of a step (Runge-Kutta's
// stages, Verlet's kick, implicit Euler's residual) sees the state of the step's start; the engines save and restore
// it with their checkpoint, so the supervisor's replay to an exact step reproduces it bit for bit.
//
// Viscoelasticity: Simo's (1987, "On a fully three-dimensional finite-strain viscoelastic damage model", CMAME 60)
// convolution and his recursive update of the internal variables, with the reduced relaxation function in Abaqus's
// convention G(t) = g_inf + sum_i g_i exp(-t / tau_i), g_inf = 1 - sum_i g_i: the law gives the INSTANTANEOUS
// response (its E is the modulus at t = 0+, so the law's stable step and stiffness bound hold unchanged) and the
// long-term one is g_inf times it. The convolution acts on the whole second Piola-Kirchhoff stress S0 = F^-1 P0 of the
// law (quasi-linear viscoelasticity at finite strain, as Puso & Weiss 1998, J Biomech Eng 120, and FEBio's
// viscoelastic material do), not on its isochoric part alone as Holzapfel (2000, "Nonlinear Solid Mechanics", 6.10)
// does: a law here gives P(F), not a volumetric-isochoric split, and liver's measured relaxation (Kerdok et al. 2006)
// is of the whole stress. S(t) = g_inf S0(t) + sum_i h_i(t), h_i(t) = int g_i exp(-(t - s) / tau_i) dS0/ds ds, and
// with S0 linear over a step (Simo 1987, eq. 3.13; Taylor, Pister & Goudreau 1970):
//   h_i(n+1) = a_i h_i(n) + c_i (S0(n+1) - S0(n)),  a_i = exp(-dt / tau_i),  c_i = g_i (1 - a_i) / (dt / tau_i),
// exact for a step strain held (relaxation: h_i = g_i S0 a_i^n). During a step the state is held and the stress at F
// is that recursion's stress as a function of F with stress constants (b_i, d_i, gamma):
//   S(F) = gamma S0(F) + H,  H = sum_i (b_i h_i(n) - d_i S0(n)),  so P = F S = gamma P0(F) + F H
// (no inverse of F in the force). The explicit integrators evaluate forces at the step's start, time t_n: b_i = 1,
// d_i = g_i, gamma = 1 make S(F_n) the convolution's stress at t_n exactly (g_inf S0 + sum h_i). Implicit Euler solves
// for the step's end, t_(n+1): b_i = a_i, d_i = c_i, gamma = g_inf + sum_i c_i make S(F_(n+1)) the stress the update
// will record there (Simo's algorithm, backward in time). All are per-scene constants computed once on the host in
// double (PronyConstants); exp is never evaluated in code both backends run.
// Per-element weights (material.bind of a Prony weight to a rule output that varies over the elements): every
// constant above is linear in its g_i (c_i = g_i k_i with k_i = (1 - a_i) / (dt / tau_i), d_i = g_i or c_i, and
// gamma = 1 - sum_i g_i (1 - k_i) under implicit Euler), so the host computes such a term's constants per unit weight
// and each element scales them by its own g_i (prony_weighted: two products and a sum per term, the same operations on
// both backends; no exp).
// The update needs S0 = F^-1 P0 = cof(F)^T P0 / det F: a collapsed point (det F = 0) makes the state, then the
// forces, non-finite, which the run supervisor reports as a non-finite step. The law's stiffness damping (F_rate)
// is scaled by gamma with its elastic stress (1 but under implicit Euler). State per point: S0 at the last accepted step (9 values), then h_i (9
// each).
#include "kernels/fmpc_hd.h"
#include "kernels/tetrahedron_math.h"

namespace fmpc::kernels {

// The most Prony terms a viscoelastic term has (sim::validate_setup and the scene parser refuse more).
constexpr int kMostPronyTerms = 4;

// A term's per-point state (null values: none).
template <typename Real>
struct PointStateView {
  Real* values;
  int width;   // values per point
  int points;  // points of the term (elements x the kind's kPoints)
};

// The Prony series' per-scene constants at the run's time step (count 0: the term is elastic).
template <typename Real>
struct PronyConstants {
  int count;
  // The stress during a step: gamma, b_i, d_i (explicit integrators: 1, 1, g_i; implicit Euler: g_inf + sum c_i,
  // a_i, c_i).
  Real stress_scale;
  Real stress_decay[kMostPronyTerms];
  Real stress_gain[kMostPronyTerms];
  // The update after a step: a_i = exp(-dt / tau_i), c_i = g_i (1 - a_i) / (dt / tau_i).
  Real decay[kMostPronyTerms];
  Real gain[kMostPronyTerms];
  // A term whose weight is per element has its constants above per unit weight (g_i = 1) and no part in
  // stress_scale; its weight g_i adds g_i stress_scale_per_weight[i] there (implicit Euler: k_i - 1; else 0).
  Real stress_scale_per_weight[kMostPronyTerms];
};

// The constants of an element whose terms' weights `weight[i]` (null: the term's weight is the scene's, already in c)
// are per element: c with each such term's constants scaled by the element's weight g = weight[i][e].
template <typename Real>
FMPC_HD PronyConstants<Real> prony_weighted(PronyConstants<Real> c, const Real* const weight[kMostPronyTerms], int e) {
  for (int i = 0; i < c.count; ++i) {
    if (weight[i] == nullptr) continue;
    const Real g = weight[i][e];
    c.stress_gain[i] = g * c.stress_gain[i];
    c.gain[i] = g * c.gain[i];
    c.stress_scale = c.stress_scale + g * c.stress_scale_per_weight[i];
  }
  return c;
}

// Values per point for `count` Prony terms: S0, then h_i.
FMPC_HD constexpr int prony_state_width(int count) { return 9 * (count + 1); }

// The constants and the state's view by value: a reference into a kernel's parameter would copy the whole
// ElementTermView to local memory in every thread (main's cd5b8a5 measured that on the element pass).

// The held history's stress H = sum_i (b_i h_i - d_i S0) at point p.
template <typename Real>
FMPC_HD void prony_history_stress(const PronyConstants<Real> c, const PointStateView<Real> state, int p, Real* H) {
  const Real* values = state.values;
  const long long points = state.points;
  for (int k = 0; k < 9; ++k) H[k] = Real(0);
  for (int i = 0; i < c.count; ++i) {
    for (int k = 0; k < 9; ++k) {
      const Real history = values[(9 * (i + 1) + k) * points + p];
      const Real previous = values[k * points + p];
      H[k] = H[k] + (c.stress_decay[i] * history - c.stress_gain[i] * previous);
    }
  }
}

// P of the viscoelastic point: gamma P0 + F H, with P0 the law's stress at F (in P on entry).
template <typename Real>
FMPC_HD void prony_first_piola(const PronyConstants<Real> c, const PointStateView<Real> state, int p, const Real* F,
                               Real* P) {
  Real H[9], FH[9];
  prony_history_stress(c, state, p, H);
  multiply3(F, H, FH);
  for (int k = 0; k < 9; ++k) P[k] = c.stress_scale * P[k] + FH[k];
}

// The update after an accepted step at point p: S0' = F^-1 P0 (P0 the law's elastic stress at the step's end F),
// h_i = a_i h_i + c_i (S0' - S0), S0 = S0'.
template <typename Real>
FMPC_HD void prony_update(const PronyConstants<Real> c, const PointStateView<Real> state, int p, const Real* F,
                          const Real* P0) {
  Real C[9], S[9];
  cofactor3(F, C);
  const Real det = determinant3(F);
  // F^-1 = cof(F)^T / det F: S_jk = sum_m C_mj P0_mk / det.
  for (int j = 0; j < 3; ++j)
    for (int k = 0; k < 3; ++k)
      S[3 * j + k] = (C[j] * P0[k] + C[3 + j] * P0[3 + k] + C[6 + j] * P0[6 + k]) / det;
  Real* values = state.values;
  const long long points = state.points;
  for (int k = 0; k < 9; ++k) {
    const Real previous = values[k * points + p];
    const Real change = S[k] - previous;
    for (int i = 0; i < c.count; ++i) {
      Real& history = values[(9 * (i + 1) + k) * points + p];
      history = c.decay[i] * history + c.gain[i] * change;
    }
    values[k * points + p] = S[k];
  }
}

}  // namespace fmpc::kernels
