#pragma once
// How a Simulation runs (runtime/integrate/simulation.h): its backend and the CUDA backend's launch choices. Plain
// data, so that every build (with or without nvcc) can name them; a CUDA choice in a build without CUDA is an error
// when the simulation is created.
namespace fmpc::sim {

enum class Backend { Cpu, Cuda };

struct GpuOptions {
  // Capture the steps between two NaN/Inf checks into a CUDA graph once and replay it (saves the launch overhead
  // that dominates small meshes). The results are bitwise the same either way.
  bool use_graphs = true;
  // Forward and semi-implicit Euler on meshes small enough for a group of threads per vertex with every block
  // resident: each chunk of steps in one cooperative launch with a grid barrier between steps
  // (launch_persistent_euler) instead of a few kernels per step. The results are bitwise the same either way;
  // use_graphs then has no effect.
  bool persistent = true;
  // Implicit Euler on meshes whose solve fits one block's shared memory (SOFA's liver: 596 tetrahedra): each step's
  // whole conjugate gradient in one block (launch_cg_block) instead of the cooperative grid; with `persistent` only.
  // The results are bitwise the same either way.
  bool cg_single_block = true;
  // Implicit Euler's per-iteration launches on meshes of at most 32,768 degrees of freedom: a stage's entries, its
  // dot products and its scalars in one launch (two per iteration and the direction) instead of a launch for each
  // (five and the direction). The results are bitwise the same either way.
  bool cg_fused_stages = true;
  // Which persistent launch: the cooperative grid (launch_persistent_euler: every block resident at once, each
  // waiting between steps for the blocks its springs reach) or thread-block clusters (launch_cluster_euler: springs
  // alone, Hopper or newer, each scene within one cluster of at most 16 x 1,024 vertices whose state and records fit
  // its shared memory; clusters run independently, in waves where there are more than the GPU holds). Automatic
  // takes the grid where the batch fits it and clusters where it does not: on an H100 the 20^3 box ran 310,322-
  // 320,840 steps/s end to end on the grid (94,019 in one cluster, measured when the grid ran 124,409-131,427), while
  // 1,000 demo patients, too many for one grid, ran at 6.33e10 spring-steps/s in clusters against 4.23e10 with a
  // launch per step. Grid and Clusters take that one first.
  // Bitwise the same results in every case.
  enum class PersistentKind { Automatic, Grid, Clusters };
  PersistentKind persistent_kind = PersistentKind::Automatic;
  // Vertices per block of the cooperative persistent launch (1 to 256; 0: automatic, the fewest whose grid is
  // resident). A setting whose grid does not fit takes the nearest that does, more rows first. Bitwise the same
  // results for any value.
  int persistent_rows = 0;
  // Threads per vertex in the per-step fused kernel of forward and semi-implicit Euler (1, 2, 4, 8, 16 or 32;
  // 0: automatic, by the mesh's size and model): more loads of a vertex's entries in flight. Bitwise the same
  // results for any value.
  int gather_lanes = 0;
  // The float element pass's register bound, in blocks of 256 threads per multiprocessor: 3 (80 registers, 20 bytes
  // spilled on linear tetrahedra) or 2 (no spills); 0: the element kind's default (kFloatElementBlocks: 3 on linear
  // tetrahedra, 2 on quadratic ones). The same bits either way.
  int element_blocks_per_sm = 0;
  // The kernels with one thread per vertex read the springs' records in the sliced layout (kernels::
  // SlicedSpringsView) instead of in CSR order, their threads ordered by entry count within windows of
  // `slice_window` vertices (32 to 1024, a power of two; 0: sim::kDefaultSliceWindow). Bitwise the same results
  // either way; false and the window are for measuring.
  bool sliced_springs = true;
  int slice_window = 0;
  // The element pass reads compact views (docs/performance.md, "Bytes per element"): one value for a per-element
  // array whose entries all have the same bits, the corner slots as a byte per node, and Dm^-1 per shape where the
  // mesh has at most 256 (a regular grid). The same values either way, so the same bits; false is for measuring.
  bool compact_element_views = true;
  // The CUDA device the engine runs on: made current (cudaSetDevice, checked) in the thread that creates the
  // simulation, before anything is allocated; the simulation is then used from that thread (or from one that made
  // the device current). -1: the creating thread's current device, whatever it is (a program that chose it itself).
  // A cohort spread over GPUs (docs/cohorts.md, --devices) runs one batch per device, each in its own thread.
  int device = -1;
};

struct SimulationOptions {
  Backend backend = Backend::Cpu;
  GpuOptions gpu;  // Backend::Cuda only
  // Backend::Cpu: workers stepping a batch's scenes side by side (0: every hardware thread); each scene's own vertex
  // loops use its setup's threads. Results do not depend on either.
  unsigned batch_threads = 0;
};

}  // namespace fmpc::sim
