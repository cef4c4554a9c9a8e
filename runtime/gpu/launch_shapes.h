#pragma once
// The shapes the CUDA backend's launches take, as plain data without CUDA headers: what the launch plan (runtime/gpu/
// launch_plan.h, a pure function unit-tested on machines without a GPU) computes and the launchers (runtime/gpu/
// gpu_launch.h) and kernels read.
#include "kernels/fmpc_hd.h"
#include "kernels/spring_math.h"

namespace fmpc::gpu {

// Which internal-force struct of kernels/internal_force_math.h the per-vertex kernels are instantiated with: the
// launchers dispatch on it once per launch (static dispatch inside the kernels).
enum class GatherKind : int { Springs = 0, Elements = 1, SpringsAndElements = 2 };

// Energies of one scene (and implicit Euler's dot products), summed in double by a fixed-shape tree (kEnergyBlocks
// partial sums of kEnergyThreads threads each, then one block): the same bits on every run, whatever the scheduling.
constexpr int kEnergyBlocks = 128;
constexpr int kEnergyThreads = 256;
// Degrees of freedom up to which implicit Euler's conjugate gradient may run a stage's entries, dot products and
// scalars in one launch (LaunchPlan::cg_fused_stages): one stride of the dot products' virtual blocks, a thread each.
constexpr int kFusedStageDofs = kEnergyBlocks * kEnergyThreads;

// Where the one-block conjugate gradient (launch_cg_block) keeps its vectors in shared memory: offsets in doubles of
// x, r, z, p, ap, the Jacobi preconditioner (3 per vertex each), the diagonal (1 per vertex), the element products (3
// per element node), the dot products' terms (two arrays of the degrees of freedom rounded up to kEnergyThreads)
// and the partial sums (alpha's kEnergyBlocks, then the residual's pair); `doubles` in all.
struct CgBlockLayout {
  int x = 0, r = 0, z = 0, p = 0, ap = 0, inverse_jacobi = 0, diagonal = 0, product = 0, terms = 0, alpha_partial = 0,
      residual_partial = 0;
  long long doubles = 0;
};

// Threads per vertex the lane kernels take: a power of two up to a warp, so a vertex's lanes are one aligned part of
// a warp (their shuffles' width).
constexpr bool valid_lanes(int lanes) { return lanes > 0 && lanes <= 32 && (lanes & (lanes - 1)) == 0; }

// Probes on a batch's vertices, applied around every step exactly as the CPU backend does (kernels/
// integrator_math.h): before a step at t = (step_base + offset) h, displacement probes set their vertices' positions
// and ramp velocity and force probes their share of the force; after it (t + h) displacement probes set the
// positions again with zero velocity. step_base (device memory) is written before every chunk, so a captured graph
// replays with the right times (a persistent launch has it by value instead); offset is the step's index within the
// chunk. Every scene of a batch may have its own probe (ProbeScene): each probe vertex is written by one thread from
// its own scene's values, so a scene's probe is bitwise the one it has when run alone.
struct ProbeScene {
  double target_x, target_y, target_z;
  double ramp_time;
  int cycles;  // ProbeLoad::cycles
  double h;
  int count;  // the scene's probe vertices (a force probe shares its target equally among them)
  bool force_mode;
  bool has_base_force;  // force probes: whether base_force_* hold the vertices' own external force
};
// ProbeArguments' entry i as the probe kernels read it (kernels/probe_schedule.cuh, probe_entry), with the chunk's
// first step; the persistent kernel keeps its probe vertices' entries in shared memory for a launch.
struct ProbeEntry {
  ProbeScene scene;
  double start_x, start_y, start_z;
  double base_force_x, base_force_y, base_force_z;  // force probes with a base force; else 0
  unsigned long long step_base;
  int vertex;
};

// Block b's count is steps_done[kBlockStepsStride b], one per 128-byte line: some forty blocks poll each count every
// step, and counts sharing a line made every poll and publication of a line's blocks queue at one L2 slice.
constexpr int kBlockStepsStride = 32;

constexpr int kPersistentThreads = 256;  // per block
// Dynamic shared memory of a persistent block of `rows` vertices with `records` CSR records that waits for
// `neighbour_blocks` blocks: the records, their terms (three Reals), the vertices' probe entries and state (six
// Reals), each record's vertex and the waited blocks' indices.
template <typename Real>
FMPC_HD constexpr long long persistent_euler_shared_bytes(long long rows, long long records,
                                                          long long neighbour_blocks) {
  return records * static_cast<long long>(sizeof(kernels::SpringIncidence<Real>) + 3 * sizeof(Real) + sizeof(int)) +
         rows * static_cast<long long>(sizeof(ProbeEntry) + 6 * sizeof(Real)) +
         neighbour_blocks * static_cast<long long>(sizeof(int));
}

// Springs alone in thread-block clusters (launch_cluster_euler, gpu_launch.h): the most rows a block and blocks a
// cluster take, and a block's vertices.
constexpr int kClusterRows = 1024;  // rows per block at most (one thread each)
constexpr int kClusterBlocks = 16;  // blocks per cluster at most (Hopper's non-portable cluster size)
struct ClusterBlock {
  int first_vertex, end_vertex;    // its vertices (at most the launch's rows)
  int window_first, window_count;  // the vertices its gathers read (its own where the cluster is one block)
  int element_first, element_end;  // the elements whose inversion it checks at the end of a chunk
};

// Shared memory of the state in a block of `rows` rows with windows of `capacity`: two published copies of six
// arrays of `rows`, six arrays of `capacity` (a multiple of 4, so the records after them stay 16-byte aligned).
template <typename Real>
FMPC_HD constexpr long long cluster_euler_state_bytes(int rows, int capacity) {
  return (12LL * rows + 6LL * capacity) * static_cast<long long>(sizeof(Real));
}
template <typename Real>
FMPC_HD constexpr long long cluster_euler_shared_bytes(int rows, int capacity, long long records) {
  return cluster_euler_state_bytes<Real>(rows, capacity) +
         records * static_cast<long long>(sizeof(kernels::SpringIncidence<Real>));
}

}  // namespace fmpc::gpu
