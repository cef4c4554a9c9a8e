#pragma once
// Implicit Euler's linear system on the CPU (Baraff & Witkin 1998, Eq. 16; kernels/implicit_math.h):
//   (M + h D + h^2 K) dv = h (f0 - h K v0)
// in a block-sparse pattern fixed when the simulation is created: one 3 x 3 block per pair of vertices that share a
// spring or (with element terms) an element, or (an element kind with a nodal pass) lie in one node's patch, two
// elements apart, both triangles stored, each row's blocks in column order. Internal to runtime/integrate
// (cpu_engine.cpp's implicit step, implicit_solver.h).
//
// Every step is assembled in parallel with the same bits for any thread count: each row's vertex term and springs
// by a gather over the row (one worker writes the row, in CSR order), then the element terms by colours (sets of
// runs of consecutive elements that share no vertex), each colour's runs side by side and the colours in order, so
// that every block's sum is taken in one order. The law's tangent comes from ElementTangents (model_tangent.h), the springs'
// blocks from implicit_spring_blocks: nothing here knows a law. A nodal pass's volumetric tangent
// (nodal_pressure_tangent.h, sum_n D_n g_n g_n^T) is added last, row by row: row i sums over the nodes n of its patch,
// in column order. Held axes are identity rows and columns with a zero right-hand side.
//
// Vectors are interleaved (x y z per vertex, 3 n values). Loops run over fixed chunks of kSystemChunkVertices
// vertices, and dot products are summed per chunk and then over the chunks in order: the thread count decides who
// computes a chunk, never the order of a sum. 64 vertices a chunk: the 20^3 box's 9,261 vertices are 145 chunks, which
// 16 threads share 9 or 10 apiece (91% of a perfect split); 256 gave 37, 2 or 3 apiece (77%), in every CG pass.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "runtime/integrate/model_tangent.h"
#include "runtime/integrate/nodal_pressure_tangent.h"
#include "runtime/integrate/simulation.h"
#include "runtime/integrate/worker_pool.h"

namespace fmpc::sim {

inline constexpr std::size_t kSystemChunkVertices = 64;
// A pass over the chunks splits over the threads only from 2 x kSystemChunksPerThread chunks (512 vertices, as with
// 256-vertex chunks before): below that a run's synchronisation costs more than its share of the work saves (SOFA's
// liver, 181 vertices in 3 chunks, took twice the CPU time a step on 2 threads as on 1 when every chunk was a part).
inline constexpr std::size_t kSystemChunksPerThread = 4;

class ImplicitSystem {
 public:
  // `held`: held_axes(setup). Reads the setup for its life.
  ImplicitSystem(const SimulationSetup& setup, const std::vector<unsigned char>& held);
  ImplicitSystem(const ImplicitSystem&) = delete;
  ImplicitSystem& operator=(const ImplicitSystem&) = delete;

  std::size_t vertices() const { return n_; }
  std::size_t dofs() const { return 3 * n_; }
  std::size_t blocks() const { return column_.size(); }
  std::size_t chunks() const { return (n_ + kSystemChunkVertices - 1) / kSystemChunkVertices; }
  // Unknowns not held (the size that chooses the direct solver).
  std::size_t free_dofs() const { return free_dofs_; }
  bool dof_held(std::size_t dof) const { return ((held_[dof / 3] >> (dof % 3)) & 1u) != 0u; }

  // The system and its right-hand side at the state: positions `x` and velocities `v` (m, m/s), accelerations `a`
  // (m/s^2, the model's and the loads' a(x, v) with held axes 0), the springs' current stiffness (N/m, one per
  // spring) and the step h (s). rhs = h (m a - h K v), zero on held axes. `linearisations`: the elements' linearisations
  // at x where the force pass kept them (ElementLinearisations), else null.
  void assemble(const std::vector<double>& x, const std::vector<double>& v, const std::vector<double>& a,
                const std::vector<double>& spring_stiffness, double h, WorkerPool& pool, std::vector<double>& rhs,
                const ElementLinearisations* linearisations = nullptr);

  // y = A p over vertex chunks [begin, end) (what a worker of a chunked loop calls).
  void multiply_chunks(const double* p, double* y, std::size_t begin, std::size_t end) const;
  // y = A p, in parallel.
  void multiply(const double* p, double* y, WorkerPool& pool) const;

  // The assembled blocks: row i's are [row_offset(i), row_offset(i + 1)), block k's column column(k) and its values
  // value(k)[3 r + c]; the diagonal block of row i is diagonal_block(i).
  std::size_t row_offset(std::size_t i) const { return static_cast<std::size_t>(row_offset_[i]); }
  std::int32_t column(std::size_t k) const { return column_[k]; }
  const double* value(std::size_t k) const { return &values_[9 * k]; }
  double* mutable_value(std::size_t k) { return &values_[9 * k]; }
  std::size_t diagonal_block(std::size_t i) const { return static_cast<std::size_t>(diagonal_[i]); }
  // How many colours the element terms were split into (0 without element terms).
  std::size_t colours() const { return colour_offset_.empty() ? 0 : colour_offset_.size() - 1; }

 private:
  void assemble_rows(std::size_t begin, std::size_t end, const std::vector<double>& x, const std::vector<double>& v,
                     const std::vector<double>& a, const std::vector<double>& spring_stiffness, double h,
                     std::vector<double>& rhs);
  void assemble_element(std::size_t e, const std::vector<double>& x, const std::vector<double>& v, double h,
                        std::vector<double>& rhs, const ElementLinearisations* linearisations);
  void apply_holds(std::size_t begin, std::size_t end, std::vector<double>& rhs);
  // Rows [begin, end)'s nodal volumetric part at the nodal_ evaluation held: h^2 D_n g_n[i] g_n[c]^T into block
  // (i, c) and h^2 g_n[i] D_n (g_n . v) out of the right-hand side, for every node n of row i's patch.
  void assemble_nodal_rows(std::size_t begin, std::size_t end, double h, std::vector<double>& rhs);

  const SimulationSetup& setup_;
  std::vector<unsigned char> held_;
  std::size_t n_ = 0;
  std::size_t free_dofs_ = 0;
  std::vector<std::int32_t> row_offset_;  // n + 1
  std::vector<std::int32_t> column_;      // per block
  std::vector<std::int32_t> diagonal_;    // per row: its diagonal block
  std::vector<double> values_;            // 9 per block
  std::vector<std::int32_t> spring_block_;   // per CSR entry of the springs' adjacency: the block (row, neighbour)
  std::vector<std::int32_t> neighbour_;      // per CSR entry: the other end
  std::size_t element_count_ = 0;
  std::vector<std::int32_t> element_block_;  // N^2 per element: the block (node a's row, node b's column)
  std::vector<std::int32_t> colour_order_;   // the runs of elements, colour by colour, increasing within a colour
  std::vector<std::int32_t> colour_offset_;  // colours + 1
  std::vector<unsigned char> row_touches_held_;  // whether row i or a column of it is held
  ElementTangents tangents_;
  NodalPressureTangent nodal_;  // inactive without a nodal pass
  // Per entry k of row i's patch (node n = nodal_.patch_vertex(k)): the entry of i in n's patch.
  std::vector<std::int32_t> nodal_own_entry_;
  std::vector<double> nodal_rate_;  // per node: D_n (g_n . v), the right-hand side's factor
};

}  // namespace fmpc::sim
