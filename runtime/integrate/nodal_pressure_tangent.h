#pragma once
// The volumetric tangent of an element kind with a nodal pass (kernels/elements/linear_nodal_pressure.h). Its energy
// sum_n V0_n K_n theta_n^2 / 2 couples each node's patch (the vertices of the elements at node n), so it is no
// element's block: its Gauss-Newton part is
//   K_vol = sum_n D_n g_n g_n^T,   g_n = dV_n/dx = sum over n's elements e of (dV_e/dx) / 4,   D_n = K_n / V0_n,
// D_n summed over the run's terms (each term's K_n from its own lambda, the same theta_n). Like the volume term's
// tangent it leaves out p_n times V_n's second derivative (zero at rest), which keeps it symmetric and positive
// semi-definite. It couples vertices two elements apart: b and c wherever one node's patch holds both. The element
// kind's own blocks (ElementTangents) are its shear part's. The static solver's tangent (model_tangent.cpp) and
// implicit Euler's block system (implicit_system.cpp) both read this one evaluation.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "runtime/integrate/simulation.h"
#include "runtime/integrate/worker_pool.h"

namespace fmpc::sim {

class NodalPressureTangent {
 public:
  // The patches of the setup's element geometry; empty (active() false) for a kind without a nodal pass. Reads the
  // setup for its life.
  explicit NodalPressureTangent(const SimulationSetup& setup);
  NodalPressureTangent(const NodalPressureTangent&) = delete;
  NodalPressureTangent& operator=(const NodalPressureTangent&) = delete;

  bool active() const { return !patch_offset_.empty(); }
  // Node n's patch: entries [patch_begin(n), patch_end(n)), their vertices increasing (n's own among them).
  std::size_t patch_begin(std::size_t n) const { return static_cast<std::size_t>(patch_offset_[n]); }
  std::size_t patch_end(std::size_t n) const { return static_cast<std::size_t>(patch_offset_[n + 1]); }
  std::int32_t patch_vertex(std::size_t entry) const { return patch_vertex_[entry]; }
  // The entry of vertex v in node n's patch (v and n share an element), found by bisection.
  std::size_t patch_entry(std::size_t n, std::int32_t v) const;

  // D_n and g_n at positions x (3 per vertex, x y z), in parallel on `pool` (null: this thread) with the same bits
  // for any thread count: each element's volume gradient, then each node's sums over its corners in CSR order.
  void evaluate(const double* x, WorkerPool* pool);
  // After evaluate: D_n (Pa/m^3) and g_n's entry for patch entry k (3 values, m^2).
  double modulus(std::size_t n) const { return modulus_[n]; }
  const double* gradient(std::size_t entry) const { return &gradient_[3 * entry]; }

 private:
  const SimulationSetup& setup_;
  std::vector<std::int32_t> patch_offset_;  // vertices + 1; empty: no nodal pass
  std::vector<std::int32_t> patch_vertex_;
  // Per corner entry k of the corners' CSR (node n's corner of element e) and node b of e: b's entry in n's patch.
  std::vector<std::int32_t> corner_patch_entry_;
  std::vector<double> element_gradient_;  // 12 per element: dV_e/dx_b, [b][axis]
  std::vector<double> element_modulus_;   // per element: sum over the terms of lambda V0 / 4 (the nodal shares' z)
  std::vector<double> modulus_, gradient_;
};

}  // namespace fmpc::sim
