#pragma once
// How the CUDA backend launches a batch's steps, chosen once when the simulation is created: a pure function of the
// batch's shape, the GpuOptions and what the device answers about its kernels (DeviceLaunchLimits), so that it is
// unit-tested on machines without a GPU (tests/unit/launch_plan_test.cpp) with the answers given. No CUDA headers.
#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "runtime/gpu/launch_shapes.h"
#include "runtime/integrate/simulation_options.h"

namespace fmpc::gpu {

// The device's answers, as functions (the CUDA backend asks the device; a query's device error is nullopt and stops
// the plan). persistent_blocks: how many blocks of kPersistentThreads threads with `shared_bytes` of dynamic shared
// memory each the cooperative persistent kernel of `kind` keeps resident at once on the whole device (0: none, or no
// cooperative launches). cluster_fits: whether clusters of `blocks` blocks of `rows` threads with `shared_bytes` each
// run with one cluster resident.
struct DeviceLaunchLimits {
  std::function<std::optional<int>(GatherKind kind, long long shared_bytes)> persistent_blocks;
  std::function<std::optional<bool>(int blocks, int rows, long long shared_bytes)> cluster_fits;
  // How many blocks of kCgThreads threads the cooperative conjugate gradient (launch_cg_persistent) keeps resident
  // at once (0: none, or no cooperative launches). Asked only for implicit Euler.
  std::function<std::optional<int>()> cg_persistent_blocks;
  // The most dynamic shared memory, in bytes, one block of kCgBlockThreads threads of the one-block conjugate
  // gradient (launch_cg_block) may have (0: it cannot run that many threads). Asked only for implicit Euler.
  std::function<std::optional<long long>()> cg_block_shared_limit;
};

// What the plan reads of the concatenated batch (runtime/gpu/batch_concatenation.h).
struct BatchShape {
  GatherKind kind = GatherKind::Springs;
  bool double_precision = false;
  bool fused_scheme = false;          // forward or semi-implicit Euler: one kernel per step
  bool implicit_scheme = false;       // implicit Euler: a conjugate gradient per step
  bool strain_table = false;          // a lookup between steps (no persistent launch)
  bool point_state = false;           // an element state update between steps (no persistent launch)
  bool nodal_pass = false;            // an element kind's nodal pass before each element pass (no persistent launch)
  bool element_kind_not_persistent = false;  // one kernels::element_kind_runs_persistent refuses (no persistent launch)
  bool probe_vertices_unique = true;  // every probe vertex listed once (else the per-step probe kernel)
  int vertex_count = 0;
  int element_count = 0;
  long long element_nodes = 0;  // nodes summed over the elements (implicit Euler: 3 products per node)
  std::size_t scene_count = 1;
  const int* offset = nullptr;     // the springs' CSR offsets, vertex_count + 1
  const int* neighbour = nullptr;  // each CSR entry's other vertex
  std::vector<int> vertex_begin;   // scene_count + 1
  std::vector<int> element_begin;  // scene_count + 1
};

// The layout for a batch of `vertex_count` vertices and `element_nodes` element nodes.
CgBlockLayout cg_block_layout(int vertex_count, long long element_nodes);

struct LaunchPlan {
  int gather_lanes = 1;  // threads per vertex of the per-step fused kernel
  // The cooperative persistent grid (0 blocks: none): blocks of `rows` vertices, the most CSR records of a block and
  // blocks it waits for, and (springs alone) each block's waited blocks as CSR (BlockNeighbours).
  int grid_blocks = 0;
  int grid_rows = 0;
  int grid_block_records = 0;
  int grid_most_waited = 0;
  std::vector<int> neighbour_offset, neighbour_block;
  // Thread-block clusters (no blocks: none).
  std::vector<ClusterBlock> cluster_blocks;
  int cluster_size = 0;  // blocks per cluster
  int cluster_rows = 0;
  int cluster_window_capacity = 0;
  int cluster_shared_bytes = 0;
  // A persistent launch's checks (checkpoint slots on the grid, one in clusters) and each check's result slots.
  std::size_t persistent_checks = 1;
  std::size_t check_slot_stride = 1;
  // Implicit Euler: the blocks of the cooperative conjugate gradient (one launch per step's solve), 0: the
  // per-iteration kernels, enqueued in chunks (cg_iterations_before_read).
  int cg_grid_blocks = 0;
  // Implicit Euler on a batch whose solve fits one block's shared memory (GpuOptions::cg_single_block): the step's
  // whole solve (start, iterations, v and x updated) in one launch of one block (launch_cg_block) with this layout;
  // cg_block_bytes 0: none (then cg_grid_blocks or the per-iteration kernels).
  CgBlockLayout cg_block;
  long long cg_block_bytes = 0;
  // Implicit Euler's start and per-iteration launches as fused stages (GpuOptions::cg_fused_stages; at most
  // kFusedStageDofs degrees of freedom): the rows of A p with p.Ap and alpha in one launch, the update with r.r, r.z
  // and the stopping test in another (cg_fused_stage_kernel) instead of five.
  bool cg_fused_stages = false;

  bool persistent() const { return grid_blocks > 0 || !cluster_blocks.empty(); }
};

// A persistent launch on the cooperative grid takes a check per checkpoint slot that fits this (the 20^3 box's float
// state, 217 KiB, fits many), up to kMostPersistentChecks (4,096 steps at the 64 between checks).
constexpr std::size_t kPersistentCheckpointBytes = std::size_t{64} << 20;
constexpr std::size_t kMostPersistentChecks = 64;

// Threads per block of the cooperative conjugate gradient (kEnergyThreads: its dot products are the fixed-shape
// sums' virtual blocks).
constexpr int kCgThreads = 256;
// Threads of the one-block conjugate gradient: the fastest of 256, 512 and 1,024 on SOFA's liver (docs/
// performance.md, eighteenth run). At 1,024 a thread has 64 registers and spills, and most warps wait at the
// barriers; at 256 each phase takes more rounds.
constexpr int kCgBlockThreads = 512;

// The fewest conjugate gradient iterations enqueued between two reads of its scalars by the host.
constexpr int kCgLeastIterationsPerRead = 4;

// The most cooperative solves whose scalars wait on the device to be read together (GpuEngine::implicit_solve):
// the host then waits once per this many implicit steps at most.
constexpr int kDeferredSolves = 64;

// How many iterations of the per-iteration conjugate gradient to enqueue before the host next reads whether it has
// stopped: the previous step's count first (a step's solve is usually like the last one's; at SOFA's cap of 25, one
// read per step), then as many as already run (doubling), at least kCgLeastIterationsPerRead, never beyond the cap.
// The kernels stop on the device, so the choice changes how many empty launches and reads a step costs, never its
// result. 0 when the cap is reached.
int cg_iterations_before_read(int previous_step_iterations, int iterations_so_far, int limit);

// The plan; nullopt when a device query failed (its caller has the error).
std::optional<LaunchPlan> plan_launches(const BatchShape& batch, const sim::GpuOptions& options,
                                        const DeviceLaunchLimits& device);

}  // namespace fmpc::gpu
