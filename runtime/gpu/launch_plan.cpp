#include "runtime/gpu/launch_plan.h"

#include <algorithm>
#include <utility>

namespace fmpc::gpu {

namespace {

// The per-step fused kernel's lanes (GpuOptions::gather_lanes; automatic from what an H100 measured, docs/
// performance.md, sixth run): springs on a 20^3 box (9,261 vertices) step in 7.4 us with 8 lanes, 9.5 with 4 and 17.0
// with 1, while the 240^3 box (14M vertices) ran at 166 steps/s with 4 lanes and 207 with 1. Lanes pay while a thread
// per vertex cannot fill the GPU (about 2^18 resident threads), so the automatic choice is the most of 8, 4, 2, 1 that
// keeps vertices x lanes within 2^18. Elements alone gather contiguous corner forces, which lanes read coalesced: 4
// lanes (the 120^3 FEM box: 812 steps/s against 769 with 1).
int gather_lanes(const BatchShape& batch, const sim::GpuOptions& options) {
  const long long n = batch.vertex_count;
  int lanes = 8;
  if (valid_lanes(options.gather_lanes)) {
    lanes = options.gather_lanes;
  } else if (batch.kind == GatherKind::Elements) {
    lanes = 4;
  } else {
    while (lanes > 1 && n * lanes > (1LL << 18)) lanes /= 2;
  }
  while (lanes > 1 && n * lanes > (1LL << 30)) lanes /= 2;
  return lanes;
}

// Whether the persistent chunks run as one cooperative grid (launch_persistent_euler): blocks of `rows` vertices
// (GpuOptions::persistent_rows; automatically the fewest that keep every block resident, the 20^3 box on an H100: 36
// rows, 258 blocks), each with its records, terms, state and waited blocks in its shared memory. A setting that does
// not fit takes the nearest that does, more rows first. Leaves grid_blocks 0 where no grid fits.
template <typename Real>
bool plan_grid(const BatchShape& batch, const sim::GpuOptions& options, const DeviceLaunchLimits& device,
               LaunchPlan& plan) {
  const bool springs = batch.kind != GatherKind::Elements;
  const long long n = batch.vertex_count;
  // With the least shared memory: registers and threads bound it.
  const std::optional<int> resident =
      device.persistent_blocks(batch.kind, persistent_euler_shared_bytes<Real>(1, 0, 0));
  if (!resident) return false;
  if (*resident <= 0) return true;
  const auto blocks_of = [&](int rows) { return (n + rows - 1) / rows; };
  const auto fewest_rows =
      static_cast<int>(std::min<long long>((n + *resident - 1) / *resident, kPersistentThreads + 1));
  const int wanted = std::max(fewest_rows, options.persistent_rows > 0 ? options.persistent_rows : fewest_rows);
  std::vector<int> candidates;
  for (int rows = wanted; rows <= kPersistentThreads; ++rows) candidates.push_back(rows);
  for (int rows = std::min(wanted, kPersistentThreads + 1) - 1; rows >= fewest_rows; --rows) candidates.push_back(rows);
  std::vector<int> offset, waited, owners;
  for (const int rows : candidates) {
    const long long blocks = blocks_of(rows);
    const auto entry_range = [&](long long b) {
      return std::pair<int, int>{batch.offset[static_cast<std::size_t>(b * rows)],
                                 batch.offset[static_cast<std::size_t>(std::min<long long>(n, (b + 1) * rows))]};
    };
    int records = 0;
    for (long long b = 0; springs && b < blocks; ++b) {
      const auto [begin, end] = entry_range(b);
      records = std::max(records, end - begin);
    }
    std::optional<int> limit =
        device.persistent_blocks(batch.kind, persistent_euler_shared_bytes<Real>(rows, records, 0));
    if (!limit) return false;
    if (blocks > *limit) continue;
    // Springs alone: the other blocks owning a neighbour of each block's vertices.
    int most_waited = 0;
    offset.assign(1, 0);
    waited.clear();
    for (long long b = 0; batch.kind == GatherKind::Springs && b < blocks; ++b) {
      const auto [begin, end] = entry_range(b);
      owners.clear();
      for (int e = begin; e < end; ++e) {
        const int owner = batch.neighbour[static_cast<std::size_t>(e)] / rows;
        if (owner != b) owners.push_back(owner);
      }
      std::sort(owners.begin(), owners.end());
      owners.erase(std::unique(owners.begin(), owners.end()), owners.end());
      waited.insert(waited.end(), owners.begin(), owners.end());
      offset.push_back(static_cast<int>(waited.size()));
      most_waited = std::max(most_waited, static_cast<int>(owners.size()));
    }
    limit = device.persistent_blocks(batch.kind, persistent_euler_shared_bytes<Real>(rows, records, most_waited));
    if (!limit) return false;
    if (blocks > *limit) continue;
    if (batch.kind == GatherKind::Springs) {
      plan.neighbour_offset = offset;
      plan.neighbour_block = waited;
    }
    plan.grid_blocks = static_cast<int>(blocks);
    plan.grid_rows = rows;
    plan.grid_block_records = records;
    plan.grid_most_waited = most_waited;
    return true;
  }
  return true;
}

// Whether the persistent chunks run in thread-block clusters (launch_cluster_euler; GpuOptions::persistent_kind):
// springs alone, every scene within one cluster of at most kClusterBlocks blocks of kClusterRows rows. A scene alone
// takes the fewest blocks, up to kClusterBlocks, that give each at most kClusterRows rows and, where the mesh allows,
// at least 256 (the 20^3 box: 16 blocks of 608); a batch takes the fewest blocks per cluster its largest scene needs,
// consecutive scenes packed into each cluster (1,000 demo patients: one block of 416 rows each). A block's published
// state, window and records must fit its shared memory, with one cluster resident. Leaves cluster_blocks empty where
// no cluster shape fits.
template <typename Real>
bool plan_clusters(const BatchShape& batch, const DeviceLaunchLimits& device, LaunchPlan& plan) {
  if (batch.kind != GatherKind::Springs || batch.offset[batch.vertex_count] == 0) return true;
  const std::size_t scenes = batch.vertex_begin.size() - 1;
  const std::vector<int>& vertex_begin = batch.vertex_begin;
  int largest = 0;
  for (std::size_t s = 0; s < scenes; ++s) largest = std::max(largest, vertex_begin[s + 1] - vertex_begin[s]);
  if (largest > kClusterBlocks * kClusterRows) return true;
  const int fewest = std::max(1, (largest + kClusterRows - 1) / kClusterRows);
  // A scene alone spreads over several multiprocessors; a batch's parallelism is its many clusters.
  const int first_try = scenes == 1 ? std::max(fewest, std::min(kClusterBlocks, (largest + 255) / 256)) : fewest;
  for (int per_cluster = first_try; per_cluster <= kClusterBlocks; ++per_cluster) {
    const int rows = ((largest + per_cluster - 1) / per_cluster + 31) / 32 * 32;
    if (rows > kClusterRows) continue;
    // Consecutive scenes packed into clusters of per_cluster x rows vertices.
    std::vector<ClusterBlock> blocks;
    int capacity = 0;
    long long records = 0;
    for (std::size_t s = 0; s < scenes;) {
      std::size_t end_scene = s + 1;
      while (end_scene < scenes && vertex_begin[end_scene + 1] - vertex_begin[s] <= per_cluster * rows) ++end_scene;
      const int first = vertex_begin[s], end = vertex_begin[end_scene];
      const int element_first = batch.element_begin[s], elements = batch.element_begin[end_scene] - element_first;
      for (int b = 0; b < per_cluster; ++b) {
        ClusterBlock block{};
        block.first_vertex = std::min(first + b * rows, end);
        block.end_vertex = std::min(block.first_vertex + rows, end);
        block.element_first = element_first + static_cast<int>(static_cast<long long>(elements) * b / per_cluster);
        block.element_end = element_first + static_cast<int>(static_cast<long long>(elements) * (b + 1) / per_cluster);
        // The window: from the least to the greatest of its vertices and their neighbours.
        int least = block.first_vertex, greatest = block.end_vertex - 1;
        const int entry_first = batch.offset[static_cast<std::size_t>(block.first_vertex)];
        const int entry_end = batch.offset[static_cast<std::size_t>(block.end_vertex)];
        for (int e = entry_first; e < entry_end; ++e) {
          least = std::min(least, batch.neighbour[static_cast<std::size_t>(e)]);
          greatest = std::max(greatest, batch.neighbour[static_cast<std::size_t>(e)]);
        }
        block.window_first = block.first_vertex < block.end_vertex ? least : block.first_vertex;
        block.window_count = block.first_vertex < block.end_vertex ? greatest - least + 1 : 0;
        if (per_cluster > 1) capacity = std::max(capacity, block.window_count);
        records = std::max<long long>(records, entry_end - entry_first);
        blocks.push_back(block);
      }
      s = end_scene;
    }
    capacity = (capacity + 3) / 4 * 4;
    const long long bytes = cluster_euler_shared_bytes<Real>(rows, capacity, records);
    const std::optional<bool> fits = device.cluster_fits(per_cluster, rows, bytes);
    if (!fits) return false;
    if (!*fits) continue;
    plan.cluster_blocks = std::move(blocks);
    plan.cluster_size = per_cluster;
    plan.cluster_rows = rows;
    plan.cluster_window_capacity = capacity;
    plan.cluster_shared_bytes = static_cast<int>(bytes);
    return true;
  }
  return true;
}

// Implicit Euler's conjugate gradient as one cooperative launch per solve (GpuOptions::persistent) where every
// degree of freedom and every element has a thread of its own in a grid that is all resident: the small meshes whose
// iterations are bound by launch latency (SOFA's liver: 596 tetrahedra, 3 blocks). Larger meshes keep a launch per
// kernel, whose grids fill the GPU.
bool plan_cg_grid(const BatchShape& batch, const DeviceLaunchLimits& device, LaunchPlan& plan) {
  const std::optional<int> resident = device.cg_persistent_blocks();
  if (!resident) return false;
  const long long entries = std::max<long long>(3LL * batch.vertex_count, batch.element_count);
  const long long wanted = (entries + kCgThreads - 1) / kCgThreads;
  if (wanted >= 1 && wanted <= *resident) plan.cg_grid_blocks = static_cast<int>(wanted);
  return true;
}

// Implicit Euler's whole solve in one block (launch_cg_block) where its vectors and element products fit the block's
// shared memory: its phases are then separated by block barriers, not grid barriers, and its loads hit shared memory.
// Only small meshes fit (the element products dominate: 96 bytes per linear tetrahedron), and those are the meshes
// whose iterations are bound by latency. The dot products keep the fixed shape of kEnergyBlocks virtual blocks,
// which asks for at most kEnergyBlocks x kEnergyThreads degrees of freedom.
bool plan_cg_block(const BatchShape& batch, const sim::GpuOptions& options, const DeviceLaunchLimits& device,
                   LaunchPlan& plan) {
  if (!options.cg_single_block || 3LL * batch.vertex_count > static_cast<long long>(kEnergyBlocks) * kEnergyThreads)
    return true;
  const std::optional<long long> limit = device.cg_block_shared_limit();
  if (!limit) return false;
  // The element products alone past the limit: no layout (whose offsets are ints) is computed for such a mesh.
  if (batch.element_nodes > *limit / static_cast<long long>(3 * sizeof(double))) return true;
  const CgBlockLayout layout = cg_block_layout(batch.vertex_count, batch.element_nodes);
  const long long bytes = layout.doubles * static_cast<long long>(sizeof(double));
  if (bytes > *limit) return true;
  plan.cg_block = layout;
  plan.cg_block_bytes = bytes;
  return true;
}

template <typename Real>
std::optional<LaunchPlan> plan_in(const BatchShape& batch, const sim::GpuOptions& options,
                                  const DeviceLaunchLimits& device) {
  LaunchPlan plan;
  plan.gather_lanes = gather_lanes(batch, options);
  // The checks' result slots: the first non-finite vertex, then per scene the inversion count and first.
  plan.check_slot_stride = 1 + (batch.element_count > 0 ? 2 * batch.scene_count : 0);
  // Chunks of forward or semi-implicit Euler run as one persistent launch each where no strain table is looked up
  // and no point state updated between steps, no nodal pass precedes the element pass (its shares and gather would
  // be two more grid barriers per step), the element kind is one the persistent kernel holds
  // (kernels::element_kind_runs_persistent), each probe vertex is listed once and the batch fits the grid or clusters;
  // otherwise one launch per kernel (steps of meshes too large for either are long enough that launches cost little).
  plan.cg_fused_stages = options.cg_fused_stages && batch.implicit_scheme && batch.vertex_count > 0 &&
                         3LL * batch.vertex_count <= kFusedStageDofs;
  if (options.persistent && batch.implicit_scheme && batch.vertex_count > 0) {
    if (!plan_cg_block(batch, options, device, plan)) return std::nullopt;
    if (plan.cg_block_bytes == 0 && !plan_cg_grid(batch, device, plan)) return std::nullopt;
  }
  if (!options.persistent || batch.vertex_count <= 0 || batch.strain_table || batch.point_state || batch.nodal_pass ||
      batch.element_kind_not_persistent || !batch.probe_vertices_unique || !batch.fused_scheme)
    return plan;
  // GpuOptions::persistent_kind: the preferred launch first, the other where it does not fit.
  const bool clusters_first = options.persistent_kind == sim::GpuOptions::PersistentKind::Clusters;
  if (clusters_first && !plan_clusters<Real>(batch, device, plan)) return std::nullopt;
  if (plan.cluster_blocks.empty() && !plan_grid<Real>(batch, options, device, plan)) return std::nullopt;
  if (!clusters_first && plan.grid_blocks == 0 && !plan_clusters<Real>(batch, device, plan)) return std::nullopt;
  // On the grid, a check per checkpoint slot that fits kPersistentCheckpointBytes, up to kMostPersistentChecks;
  // clusters, whose checks are their launches' ends, one.
  if (plan.grid_blocks > 0) {
    const std::size_t checkpoint_bytes = 6 * sizeof(Real) * static_cast<std::size_t>(batch.vertex_count);
    plan.persistent_checks =
        std::clamp<std::size_t>(kPersistentCheckpointBytes / checkpoint_bytes, 1, kMostPersistentChecks);
  }
  return plan;
}

}  // namespace

CgBlockLayout cg_block_layout(int vertex_count, long long element_nodes) {
  const int dofs = 3 * std::max(vertex_count, 0);
  const int padded = (dofs + kEnergyThreads - 1) / kEnergyThreads * kEnergyThreads;
  CgBlockLayout layout;
  long long next = 0;
  const auto take = [&next](long long count) {
    const long long at = next;
    next += count;
    return static_cast<int>(at);
  };
  layout.x = take(dofs);
  layout.r = take(dofs);
  layout.z = take(dofs);
  layout.p = take(dofs);
  layout.ap = take(dofs);
  layout.inverse_jacobi = take(dofs);
  layout.diagonal = take(std::max(vertex_count, 0));
  layout.product = take(3 * std::max(element_nodes, 0LL));
  layout.terms = take(2LL * padded);
  layout.alpha_partial = take(kEnergyBlocks);
  layout.residual_partial = take(2 * kEnergyBlocks);
  layout.doubles = next;
  return layout;
}

int cg_iterations_before_read(int previous_step_iterations, int iterations_so_far, int limit) {
  const int remaining = std::max(0, limit - std::max(0, iterations_so_far));
  if (remaining == 0) return 0;
  const int wanted = iterations_so_far <= 0 ? previous_step_iterations : iterations_so_far;
  return std::min(remaining, std::max(wanted, kCgLeastIterationsPerRead));
}

std::optional<LaunchPlan> plan_launches(const BatchShape& batch, const sim::GpuOptions& options,
                                        const DeviceLaunchLimits& device) {
  return batch.double_precision ? plan_in<double>(batch, options, device) : plan_in<float>(batch, options, device);
}

}  // namespace fmpc::gpu
