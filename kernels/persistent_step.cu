// Forward and semi-implicit Euler over many steps in one launch (gpu_launch.h, launch_persistent_euler and
// launch_cluster_euler): the cooperative grid kernel and the thread-block cluster kernel, with the checks they take
// inside a launch. Each vertex's step is explicit_vertex_step (kernels/step_device.cuh) and the probe's
// kernels/probe_schedule.cuh: the per-step kernels' bits.
#include <cooperative_groups.h>

#include <cuda/atomic>
#include <type_traits>

#include "kernels/probe_schedule.cuh"
#include "kernels/step_device.cuh"

namespace fmpc::gpu {

namespace {

// State buffer 0 or 1 by selection: indexing the kernel parameter's array with a run-time index would copy it to
// local memory.
template <typename Real>
__device__ MutableStateView<Real> buffer(const PersistentEulerArguments<Real>& a, int parity) {
  return parity == 0 ? a.state[0] : a.state[1];
}

// The end-of-chunk checks' presets (PersistentChecks), written by a persistent kernel's threads before its first
// barrier, which publishes them.
__device__ void reset_chunk_checks(const PersistentChecks& c, int checks, int n, int thread, int stride) {
  if (c.first_non_finite == nullptr) return;
  for (int j = thread; j < checks; j += stride) c.first_non_finite[j * c.slot_stride] = n;
  for (int i = thread; i < checks * c.scene_count; i += stride) {
    const int j = i / c.scene_count, scene = i - j * c.scene_count;
    c.inverted_count[j * c.slot_stride + scene] = 0u;
    c.inverted_first[j * c.slot_stride + scene] = c.element_count;
  }
}

// Check j's results (PersistentChecks::slot_stride).
__device__ PersistentChecks check_slot(PersistentChecks c, int j) {
  const int offset = j * c.slot_stride;
  c.first_non_finite += offset;
  if (c.inverted_count != nullptr) {
    c.inverted_count += offset;
    c.inverted_first += offset;
  }
  return c;
}

// The end-of-chunk checks on the final state `end`, after a barrier that published it.
template <typename Real>
__device__ void run_chunk_checks(const PersistentChecks& c, const kernels::StateView<Real>& end, int n, int thread,
                                 int stride) {
  if (c.first_non_finite == nullptr) return;
  for (int v = thread; v < n; v += stride)
    if (non_finite_vertex(end, v)) atomicMin(c.first_non_finite, v);
  for (int e = thread; e < c.element_count; e += stride)
    count_if_inverted(c.nodes, c.element_kind, e, c.element_scene, end, c.inverted_count, c.inverted_first);
}

// Checkpoint slot k of a persistent launch (PersistentEulerArguments::checkpoints).
template <typename Real>
__device__ MutableStateView<Real> checkpoint_slot(const PersistentEulerArguments<Real>& a, int k) {
  return offset_state(a.checkpoints, k * a.checkpoint_stride);
}

// Six arrays of `stride` in shared memory (a persistent or cluster_euler_kernel block's state, a cluster block's

// per block, 258 blocks) ran 208,663-212,017 steps/s through fmpc simulate; bounded to 3 it takes 80 registers with
// 60 bytes of spills (24 rows, 386 blocks) and ran 195,931-200,902 (H100).
template <typename Real, GatherKind K>
struct PersistentOccupancy {
  static constexpr int min_blocks = std::is_same_v<Real, float> || K == GatherKind::Springs ? 2 : 1;
};

// Records per thread whose other ends block_spring_terms reads together: 4 for springs alone in float; 2 in double
// (4 spilled 162 bytes at the 128 registers of 2 blocks); 1 with elements, whose pass leaves no registers for more.
template <typename Real, GatherKind K>
constexpr int kPersistentTermBatch = K != GatherKind::Springs      ? 1
                                     : std::is_same_v<Real, float> ? 4
                                                                   : 2;

// A block's step count, published once its threads have written the step (BlockNeighbours::steps_done): release
// by one thread after the block's barrier, the pattern of cooperative groups' grid barrier without its single counter
// that every block of the grid increments.
__device__ void publish_block_steps(unsigned* steps_done, unsigned steps) {
  __syncthreads();
  if (threadIdx.x == 0)
    cuda::atomic_ref<unsigned, cuda::thread_scope_device>(steps_done[kBlockStepsStride * blockIdx.x])
        .store(steps, cuda::memory_order_release);
}

// Waits until each of the `count` blocks `waited` (shared memory) has published `steps` steps: one thread per block
// polls with acquire loads, then the block's barrier passes what they saw on to every thread. (Relaxed polls and one
// acquire fence after them ran the 20^3 box at 168,343 steps/s against 180,091 with acquire polls; H100.)
__device__ void wait_for_blocks(const unsigned* steps_done, const int* waited, int count, unsigned steps) {
  for (int i = static_cast<int>(threadIdx.x); i < count; i += static_cast<int>(blockDim.x)) {
    cuda::atomic_ref<const unsigned, cuda::thread_scope_device> done(steps_done[kBlockStepsStride * waited[i]]);
    while (done.load(cuda::memory_order_acquire) < steps) {
    }
  }
  __syncthreads();
}

// A persistent block's shared memory (persistent_euler_shared_bytes' layout): its CSR records, their terms, its
// vertices' state at the step's start, which vertex of the block each record belongs to, and the blocks it waits for.
template <typename Real>
struct PersistentShared {
  kernels::SpringIncidence<Real>* record;
  ProbeEntry* probe;  // per row: its vertex's probe entry, where it has one
  Real* term;         // three arrays of a.block_records: x, y, z
  Real* own;          // six arrays of a.rows: the block's vertices' state
  int* owner;
  int* waited;
};

template <typename Real>
__device__ PersistentShared<Real> persistent_shared(unsigned char* base, int records, int rows) {
  PersistentShared<Real> p;
  p.record = reinterpret_cast<kernels::SpringIncidence<Real>*>(base);
  p.probe = reinterpret_cast<ProbeEntry*>(p.record + records);
  p.term = reinterpret_cast<Real*>(p.probe + rows);
  p.own = p.term + 3 * records;
  p.owner = reinterpret_cast<int*>(p.own + 6 * rows);
  p.waited = p.owner + records;
  return p;
}

// The terms of a block's `entries` CSR records (kernels::entry_spring_force at the step's start: the block's own
// vertices from shared memory, the other ends from `in`), spread over the block's threads regardless of which vertex
// each belongs to; `Batch` records per thread read their other ends before any term is computed.
template <int Batch, typename Real>
__device__ void block_spring_terms(const kernels::SpringLawParameters<Real>& law, int entries,
                                   const PersistentShared<Real>& p, int rows, const kernels::StateView<Real>& in) {
  const kernels::StateView<Real> own = shared_state(static_cast<const Real*>(p.own), rows);
  Real* const tx = p.term;
  Real* const ty = tx + entries;
  Real* const tz = ty + entries;
  constexpr int stride = kPersistentThreads;
  for (int first = static_cast<int>(threadIdx.x); first < entries; first += Batch * stride) {
    kernels::VertexState<Real> other[Batch];
    FMPC_UNROLL_ALL
    for (int k = 0; k < Batch; ++k)
      if (first + k * stride < entries) other[k] = kernels::vertex_state(in, p.record[first + k * stride].neighbour);
    FMPC_UNROLL_ALL
    for (int k = 0; k < Batch; ++k) {
      const int e = first + k * stride;
      if (e >= entries) break;
      const kernels::VertexState<Real> self = kernels::vertex_state(own, p.owner[e]);
      kernels::entry_spring_force(law, p.record[e], other[k], self.x, self.y, self.z, self.vx, self.vy, self.vz, tx[e],
                                  ty[e], tz[e]);
    }
  }
}

// The element pass of every term over the grid, thread `thread` of `stride` on its elements: each term's pass writes or
// adds to the corner slots of the same elements, so the terms need no barrier between them. The term index is a
// constant in each unrolled iteration (indexing the parameter's array with a run-time index would copy it to local
// memory); the element kind and law are visited per element pass, over the kinds it holds
// (kernels::kPersistentElementKind; the launch plan gives the others no persistent launch, launch_persistent_euler
// refuses them). Inlined, and without the larger kinds' bodies: called, or with them, it cost every element
// instantiation a 2.2-3.7 KB stack frame (a copy of the kernel's parameters, then spills); now 136-176 bytes.
template <typename Real>
__device__ __forceinline__ void grid_element_pass(const ForceModelView<Real>& model, const kernels::StateView<Real>& in,
                                                  int thread, int stride) {
  FMPC_UNROLL_ALL
  for (int t = 0; t < kMostElementTerms; ++t) {
    if (t >= model.term_count) break;
    const kernels::ElementTermView<Real>& term = model.terms[t];
    kernels::visit_element_term_on_device(term.element, term.law, [&](auto kind, auto element_law) {
      using Element = decltype(kind);
      using Law = decltype(element_law);
      if constexpr (kernels::kPersistentElementKind<Element>) {
        for (int e = thread; e < term.count; e += stride) {
          if (t == 0) {
            kernels::element_node_forces<Element, Law, false>(e, term, in, model.corner_force);
          } else {
            kernels::element_node_forces<Element, Law, true>(e, term, in, model.corner_force);
          }
        }
      }
    });
  }
}

// launch_persistent_euler's kernel (gpu_launch.h): `steps` steps, block b on vertices [b rows, (b + 1) rows). Each
// step has two phases. First the block's threads compute the terms of all its vertices' springs side by side
// (block_spring_terms, into shared memory); then thread r adds vertex r's terms in CSR order (kernels::
// sum_spring_terms' order, so its bits), and its corner forces from the element pass, and updates the vertex in
// registers with explicit_vertex_step and the probe's schedule (probe_between_steps), storing
// it for the neighbours and into the block's shared copy. A vertex's sum is one thread's chain of additions, so the
// lanes of a warp share no vertex: the sums cost a warp's instruction per term for 32 vertices at once, where lanes
// shuffling the terms of one vertex cost three per term for a few. Plain loads and stores of the state: the barriers
// (grid, or the neighbours' published steps) order them at device scope, and nothing here reads it through the
// non-coherent read-only path. At a check before the launch's last (check_count) each thread stores its vertex into
// the check's checkpoint slot and flags it there if non-finite; with elements, a grid barrier, then the grid counts
// the inverted ones in that slot. A launch thus takes many checks (a whole advance of a small mesh) instead of the
// launch, the end-of-chunk barrier and the download per check that cost the 20^3 box about 17 us each (H100).
template <typename Real, GatherKind K>
__global__ void __launch_bounds__(kPersistentThreads, (PersistentOccupancy<Real, K>::min_blocks))
    persistent_euler_kernel(PersistentEulerArguments<Real> a) {
  cooperative_groups::grid_group grid = cooperative_groups::this_grid();
  extern __shared__ __align__(16) unsigned char persistent_shared_memory[];
  constexpr bool springs = K != GatherKind::Elements;
  const int thread = vertex_index();
  const int stride = static_cast<int>(gridDim.x) * static_cast<int>(blockDim.x);
  const int local = static_cast<int>(threadIdx.x);
  const FusedStepArguments<Real>& step = a.step;
  const kernels::SpringNetworkView<Real>& net = step.model.springs;
  const int n = step.vertex_count;
  const int rows = a.rows;
  const ProbeArguments<Real>& probe = step.probe;
  const int* const probe_entry_of = step.probe_entry;
  const bool probed = probe_entry_of != nullptr;
  const int block_first = static_cast<int>(blockIdx.x) * rows, block_end = min(n, block_first + rows);
  const int v = block_first + local;
  const bool owner = local < rows && v < n;
  const PersistentShared<Real> p = persistent_shared<Real>(persistent_shared_memory, a.block_records, rows);
  // The block's records (its vertices' entries are contiguous) and their vertices.
  int entry_first = 0, entries = 0, begin = 0, end = 0;
  if constexpr (springs) {
    entry_first = net.adjacency_offset[block_first];
    entries = net.adjacency_offset[block_end] - entry_first;
    for (int e = local; e < entries; e += kPersistentThreads)
      p.record[e] = kernels::spring_incidence(net, entry_first + e);
    if (owner) {
      begin = net.adjacency_offset[v] - entry_first;
      end = net.adjacency_offset[v + 1] - entry_first;
      for (int e = begin; e < end; ++e) p.owner[e] = local;
    }
  }
  int waited_count = 0;
  const BlockNeighbours& neighbours = a.neighbours;
  if constexpr (K == GatherKind::Springs) {
    const int first = neighbours.offset[blockIdx.x];
    waited_count = neighbours.offset[blockIdx.x + 1] - first;
    for (int i = local; i < waited_count; i += kPersistentThreads) p.waited[i] = neighbours.block[first + i];
    if (local == 0) neighbours.steps_done[kBlockStepsStride * blockIdx.x] = 0u;
  }
  const unsigned char held = owner ? step.loads.fixed[v] : kernels::kAllAxesFixed;
  const Real h = owner ? step_of(step.step, v) : Real(0);
  const int entry = owner && probed ? probe_entry_of[v] : -1;
  int parity = a.first_parity;
  const PersistentChecks& c = a.checks;
  reset_chunk_checks(c, a.check_count, n, thread, stride);
  int check = 0;                    // the next check's index
  int check_after = a.first_check;  // the steps after which it comes (before the last)
  const MutableStateView<Real> own = shared_state(p.own, rows);
  kernels::VertexState<Real> self{};
  // The vertex's load values for the launch (a force probe entry's force replaces its external force at each step).
  kernels::VertexLoadValues<Real> load{};
  if (owner) {
    self = kernels::vertex_state(read_only(buffer(a, parity)), v);
    if (a.store_start) store_vertex_state(checkpoint_slot(a, 0), v, self);
    if (entry >= 0) {
      // Read once for the launch: after every step's barrier each of these loads would go to L2, and the probe
      // vertices' blocks hold their neighbours back. The 20^3 box ran 206,103-209,177 steps/s with the entry read per
      // step, 252,854-264,211 read once, 295,895-299,349 without its probe (H100).
      p.probe[local] = probe_entry(probe, entry, a.step_base);
      ProbeForce<Real> force;
      if (probe_prescribe(p.probe[local], 0, true, self, force)) store_vertex_state(buffer(a, parity), v, self);
      store_probe_force(probe.force, v, force);
    }
    store_vertex_state(own, local, self);
    load = kernels::vertex_load_values(step.loads, v);
  }
  // Publishes the probe's state, the counters' reset, the checks' presets and the block's shared memory.
  grid.sync();
  for (int s = 0; s < a.steps; ++s) {
    const MutableStateView<Real> out = buffer(a, 1 - parity);
    const kernels::StateView<Real> in = read_only(buffer(a, parity));
    const bool checked = check + 1 < a.check_count && s + 1 == check_after;
    if constexpr (K != GatherKind::Springs) {
      grid_element_pass(step.model, in, thread, stride);
      grid.sync();
    } else if (s > 0) {
      wait_for_blocks(neighbours.steps_done, p.waited, waited_count, static_cast<unsigned>(s));
    }
    if constexpr (springs) {
      block_spring_terms<kPersistentTermBatch<Real, K>>(net.law, entries, p, rows, in);
      __syncthreads();
    }
    if (owner) {
      Real fx = Real(0), fy = Real(0), fz = Real(0);
      if (held != kernels::kAllAxesFixed) {
        // Unrolled so that the shared loads run ahead of the chain of additions.
        FMPC_UNROLL_GATHER
        for (int e = begin; e < end; ++e) {
          fx += p.term[e];
          fy += p.term[entries + e];
          fz += p.term[2 * entries + e];
        }
        if constexpr (K != GatherKind::Springs) {
          Real cx, cy, cz;
          kernels::gather_corner_force(v, step.model.corners, cx, cy, cz);
          if constexpr (springs) {
            fx += cx;
            fy += cy;
            fz += cz;
          } else {
            fx = cx;
            fy = cy;
            fz = cz;
          }
        }
      }
      explicit_vertex_step(step.scheme, h, held, load, step.loads, fx, fy, fz, self);
      // The check stores the state a launch ending after this step would hold: the probe's prescription after the
      // step applied, the one before the next not yet.
      const auto at_step_end = [&](const kernels::VertexState<Real>& x) {
        if (!checked) return;
        const MutableStateView<Real> checkpoint = checkpoint_slot(a, check + 1);
        store_vertex_state(checkpoint, v, x);
        if (non_finite_vertex(read_only(checkpoint), v)) atomicMin(check_slot(c, check).first_non_finite, v);
      };
      if (entry >= 0) {
        ProbeForce<Real> force;
        probe_between_steps(p.probe[local], s, s + 1 < a.steps, self, force, at_step_end);
        store_probe_force(probe.force, v, force);
        if (force.set) {
          load.force_x = force.x;
          load.force_y = force.y;
          load.force_z = force.z;
        }
      } else {
        at_step_end(self);
      }
      store_vertex_state(out, v, self);
      store_vertex_state(own, local, self);
    }
    if constexpr (K == GatherKind::Springs) {
      publish_block_steps(neighbours.steps_done, static_cast<unsigned>(s + 1));
    } else {
      grid.sync();
    }
    if (checked) {
      if (c.element_count > 0) {
        if constexpr (K == GatherKind::Springs) grid.sync();  // the elements' corners are other blocks' vertices
        const PersistentChecks at = check_slot(c, check);
        const kernels::StateView<Real> checkpoint = read_only(checkpoint_slot(a, check + 1));
        for (int e = thread; e < c.element_count; e += stride)
          count_if_inverted(c.nodes, c.element_kind, e, c.element_scene, checkpoint, at.inverted_count, at.inverted_first);
      }
      ++check;
      check_after += a.check_every;
    }
    parity = 1 - parity;
  }
  if constexpr (K == GatherKind::Springs) grid.sync();  // the checks read every block's vertices
  run_chunk_checks(check_slot(c, a.check_count - 1), read_only(buffer(a, parity)), n, thread, stride);
}

// launch_cluster_euler's kernel (gpu_launch.h): clusters of a.cluster_blocks blocks of a.rows threads, thread r of
// a block on vertex first_vertex + r (ClusterBlock). Per step a block of a cluster of several copies its window (the
// vertices its gathers read, a contiguous range) from its cluster's published copies of the step's start,
// coalesced; a block alone in its cluster reads its own published copy. Then each thread gathers, updates its
// vertex in registers (explicit_vertex_step on sum_spring_terms' forces, then
// the probe after the step and before the next) and publishes it into the other copy; one cluster barrier per step.
// Clusters never wait on each other: a grid larger than the GPU runs in waves. The gather reads one entry at a time
// (sum_spring_terms' batches of 2, 4 and 8 entries measured slower here: 82,724, 78,967 and 73,224 steps/s on the
// 20^3 box against 94,019, the cohort 40.5 and 64.9 us per step against 36.1; H100).
template <typename Real>
__global__ void __launch_bounds__(kClusterRows, 1) cluster_euler_kernel(ClusterEulerArguments<Real> a) {
#if defined(__CUDA_ARCH__) && __CUDA_ARCH__ < 900
  // Built for an architecture without clusters (CMAKE_CUDA_ARCHITECTURES below 90) and JIT-compiled on a newer GPU:
  // no silent empty step.
  __trap();
#else
  namespace cg = cooperative_groups;
  cg::cluster_group cluster = cg::this_cluster();
  extern __shared__ __align__(16) unsigned char cluster_shared[];
  const PersistentEulerArguments<Real>& chunk = a.chunk;
  const FusedStepArguments<Real>& step = chunk.step;
  const kernels::SpringNetworkView<Real>& net = step.model.springs;
  const int rows = a.rows;
  const bool alone = a.cluster_blocks == 1;
  const int rank = static_cast<int>(cluster.block_rank());
  const ClusterBlock me = a.block[blockIdx.x];
  const int cluster_first = a.block[static_cast<int>(blockIdx.x) - rank].first_vertex;
  const int local = static_cast<int>(threadIdx.x);
  const int v = me.first_vertex + local;
  const bool owner = v < me.end_vertex;
  Real* const published = reinterpret_cast<Real*>(cluster_shared);  // [2][6][rows]
  Real* const window = published + 12 * rows;                       // [6][window_capacity]
  // A block alone reads its own copy: its window is its own vertices.
  const int stride = alone ? rows : a.window_capacity;
  kernels::SpringIncidence<Real>* const record = reinterpret_cast<kernels::SpringIncidence<Real>*>(
      cluster_shared + cluster_euler_state_bytes<Real>(rows, a.window_capacity));
  // The block's records in CSR order, their neighbours as window indices.
  const int first_entry = net.adjacency_offset[me.first_vertex];
  const int entries = net.adjacency_offset[me.end_vertex] - first_entry;
  for (int e = local; e < entries; e += rows) {
    kernels::SpringIncidence<Real> r = net.incidence[first_entry + e];
    r.neighbour -= me.window_first;
    record[e] = r;
  }
  const int own_first = owner ? net.adjacency_offset[v] - first_entry : 0;
  const int own_count = owner ? net.adjacency_offset[v + 1] - net.adjacency_offset[v] : 0;
  const unsigned char held = owner ? step.loads.fixed[v] : kernels::kAllAxesFixed;
  const Real h = owner ? step_of(step.step, v) : Real(0);
  const int entry = owner && step.probe_entry != nullptr ? step.probe_entry[v] : -1;
  int parity = chunk.first_parity;
  kernels::VertexState<Real> self{};
  if (owner) self = kernels::vertex_state(read_only(buffer(chunk, parity)), v);
  if (owner && chunk.store_start) store_vertex_state(checkpoint_slot(chunk, 0), v, self);
  if (entry >= 0) {
    ProbeForce<Real> force;
    probe_prescribe(probe_entry(step.probe, entry, chunk.step_base), 0, true, self, force);
    store_probe_force(step.probe.force, v, force);
  }
  if (owner) store_vertex_state(shared_state(published, rows), local, self);
  cluster.sync();
  int current = 0;
  for (int s = 0; s < chunk.steps; ++s) {
    const Real* const start = published + current * 6 * rows;
    if (!alone) {
      for (int i = local; i < me.window_count; i += rows) {
        const int u = me.window_first + i - cluster_first, from = u / rows;
        const Real* const copy = from == rank ? start : cluster.map_shared_rank(start, from);
        store_vertex_state(shared_state(window, stride), i,
                           kernels::vertex_state(shared_state(copy, rows), u - from * rows));
      }
      __syncthreads();
    }
    const Real* const source = alone ? start : window;
    if (owner) {
      Real fx = Real(0), fy = Real(0), fz = Real(0);
      kernels::VertexLoadValues<Real> load{};
      if (held != kernels::kAllAxesFixed) {
        kernels::sum_spring_terms(
            own_count, net.law, self, [&](int j) { return record[own_first + j]; },
            [&](const kernels::SpringIncidence<Real>& r) {
              return kernels::vertex_state(shared_state(source, stride), r.neighbour);
            },
            fx, fy, fz);
        load = kernels::vertex_load_values(step.loads, v);
      }
      explicit_vertex_step(step.scheme, h, held, load, step.loads, fx, fy, fz, self);
      if (entry >= 0) {
        ProbeForce<Real> force;
        probe_between_steps(probe_entry(step.probe, entry, chunk.step_base), s, s + 1 < chunk.steps, self, force,
                            [](const kernels::VertexState<Real>&) {});
        store_probe_force(step.probe.force, v, force);
      }
      store_vertex_state(shared_state(published + (1 - current) * 6 * rows, rows), local, self);
    }
    cluster.sync();
    current = 1 - current;
    parity = 1 - parity;
  }
  if (owner) {
    store_vertex_state(buffer(chunk, parity), v, self);
    store_vertex_state(
        buffer(chunk, 1 - parity), v,
        kernels::vertex_state(read_only(shared_state(published + (1 - current) * 6 * rows, rows)), local));
  }
  // The checks' presets come from reset_checks_kernel, launched before (clusters do not wait on each other).
  const PersistentChecks& c = chunk.checks;
  if (c.first_non_finite == nullptr) return;
  const kernels::StateView<Real> end = read_only(buffer(chunk, parity));
  if (owner && non_finite_vertex(end, v)) atomicMin(c.first_non_finite, v);
  if (me.element_first == me.element_end) return;
  cluster.sync();  // the elements' corners may be other blocks' vertices
  for (int e = me.element_first + local; e < me.element_end; e += rows)
    count_if_inverted(c.nodes, c.element_kind, e, c.element_scene, end, c.inverted_count, c.inverted_first);
#endif
}

// PersistentChecks' presets (reset_chunk_checks), for the kernels whose blocks do not all run at once.
__global__ void reset_checks_kernel(PersistentChecks c, int checks, int vertex_count) {
  reset_chunk_checks(c, checks, vertex_count, static_cast<int>(threadIdx.x), static_cast<int>(blockDim.x));
}

// Raises persistent_euler_kernel's dynamic shared memory limit to `shared_bytes` where it is lower (beyond the default
// 48 KB), never lowers it: simulations alive side by side share the kernel, so their launches need not set it again.
template <typename Real, GatherKind K>
cudaError_t persistent_shared_limit(long long shared_bytes) {
  const void* kernel = reinterpret_cast<const void*>(persistent_euler_kernel<Real, K>);
  cudaFuncAttributes attributes{};
  const cudaError_t status = cudaFuncGetAttributes(&attributes, kernel);
  if (status != cudaSuccess || attributes.maxDynamicSharedSizeBytes >= shared_bytes) return status;
  return cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, static_cast<int>(shared_bytes));
}

// A launch's checks (PersistentEulerArguments::check_count): at least one, the last at the end and the others
// before it; more than one only with their results and checkpoint slots.
template <typename Real>
bool valid_checks(const PersistentEulerArguments<Real>& a) {
  if (a.check_count < 1) return false;
  if (a.check_count == 1) return true;
  const long long last_inner = a.first_check + static_cast<long long>(a.check_count - 2) * a.check_every;
  return a.first_check >= 1 && (a.check_count == 2 || a.check_every >= 1) && last_inner < a.steps &&
         a.checks.first_non_finite != nullptr && a.checks.slot_stride >= 1 && a.checkpoints.x != nullptr &&
         a.checkpoint_stride >= static_cast<long long>(a.step.vertex_count);
}

// Sets cluster_euler_kernel's attributes for `shared_bytes` of dynamic shared memory and, beyond 8 blocks, Hopper's
// non-portable cluster sizes, and fills the launch configuration of `grid` blocks in clusters of `blocks`.
template <typename Real>
cudaError_t cluster_launch_config(int grid, int blocks, int rows, long long shared_bytes, cudaStream_t stream,
                                  cudaLaunchAttribute& attribute, cudaLaunchConfig_t& config) {
  const void* kernel = reinterpret_cast<const void*>(cluster_euler_kernel<Real>);
  cudaError_t status =
      cudaFuncSetAttribute(kernel, cudaFuncAttributeMaxDynamicSharedMemorySize, static_cast<int>(shared_bytes));
  if (status == cudaSuccess && blocks > 8)
    status = cudaFuncSetAttribute(kernel, cudaFuncAttributeNonPortableClusterSizeAllowed, 1);
  attribute.id = cudaLaunchAttributeClusterDimension;
  attribute.val.clusterDim.x = static_cast<unsigned>(blocks);
  attribute.val.clusterDim.y = 1;
  attribute.val.clusterDim.z = 1;
  config = {};
  config.gridDim = dim3(static_cast<unsigned>(grid));
  config.blockDim = dim3(static_cast<unsigned>(rows));
  config.dynamicSmemBytes = static_cast<std::size_t>(shared_bytes);
  config.stream = stream;
  config.attrs = &attribute;
  config.numAttrs = 1;
  return status;
}

// Whether a term of `model` has an element kind the persistent kernel does not hold (kernels::kPersistentElementKind).
template <typename Real>
bool element_kind_not_persistent(const ForceModelView<Real>& model) {
  if (model.kind == GatherKind::Springs) return false;
  for (int t = 0; t < model.term_count && t < kMostElementTerms; ++t)
    if (!kernels::element_kind_runs_persistent(model.terms[t].element)) return true;
  return false;
}

}  // namespace

template <typename Real>
cudaError_t persistent_euler_block_limit(GatherKind kind, long long shared_bytes, int& blocks) {
  blocks = 0;
  int device = 0, cooperative = 0, multiprocessors = 0, shared_limit = 0;
  cudaError_t status = cudaGetDevice(&device);
  if (status == cudaSuccess) status = cudaDeviceGetAttribute(&cooperative, cudaDevAttrCooperativeLaunch, device);
  if (status == cudaSuccess) status = cudaDeviceGetAttribute(&multiprocessors, cudaDevAttrMultiProcessorCount, device);
  if (status == cudaSuccess)
    status = cudaDeviceGetAttribute(&shared_limit, cudaDevAttrMaxSharedMemoryPerBlockOptin, device);
  if (status != cudaSuccess || cooperative == 0 || shared_bytes < 0 || shared_bytes > shared_limit) return status;
  return with_kind(kind, [&](auto k) {
    constexpr GatherKind K = decltype(k)::value;
    int per_multiprocessor = 0;
    cudaError_t occupancy = persistent_shared_limit<Real, K>(shared_bytes);
    if (occupancy == cudaSuccess)
      occupancy =
          cudaOccupancyMaxActiveBlocksPerMultiprocessor(&per_multiprocessor, persistent_euler_kernel<Real, K>,
                                                        kPersistentThreads, static_cast<std::size_t>(shared_bytes));
    blocks = per_multiprocessor * multiprocessors;
    return occupancy;
  });
}

template <typename Real>
cudaError_t launch_persistent_euler(const PersistentEulerArguments<Real>& arguments, cudaStream_t stream) {
  if (arguments.step.vertex_count <= 0 || arguments.steps <= 0) return cudaSuccess;
  if (arguments.blocks <= 0 || arguments.rows <= 0 || arguments.rows > kPersistentThreads ||
      static_cast<long long>(arguments.blocks) * arguments.rows < arguments.step.vertex_count ||
      arguments.block_records < 0 || arguments.most_neighbour_blocks < 0 ||
      (arguments.step.model.kind == GatherKind::Springs && arguments.neighbours.steps_done == nullptr) ||
      !valid_checks(arguments) || element_kind_not_persistent(arguments.step.model)) {
    return cudaErrorInvalidValue;
  }
  const unsigned blocks = static_cast<unsigned>(arguments.blocks);
  const long long shared_bytes =
      persistent_euler_shared_bytes<Real>(arguments.rows, arguments.block_records, arguments.most_neighbour_blocks);
  return with_kind(arguments.step.model.kind, [&](auto kind) {
    constexpr GatherKind K = decltype(kind)::value;
    PersistentEulerArguments<Real> copy = arguments;
    void* parameters[] = {&copy};
    return cudaLaunchCooperativeKernel(reinterpret_cast<const void*>(persistent_euler_kernel<Real, K>), dim3(blocks),
                                       dim3(kPersistentThreads), parameters, static_cast<std::size_t>(shared_bytes),
                                       stream);
  });
}

template <typename Real>
cudaError_t cluster_euler_fits(int blocks, int rows, long long shared_bytes, bool& fits) {
  fits = false;
  int device = 0, cluster_launch = 0, major = 0, shared_limit = 0;
  cudaError_t status = cudaGetDevice(&device);
  if (status == cudaSuccess) status = cudaDeviceGetAttribute(&cluster_launch, cudaDevAttrClusterLaunch, device);
  if (status == cudaSuccess) status = cudaDeviceGetAttribute(&major, cudaDevAttrComputeCapabilityMajor, device);
  if (status == cudaSuccess)
    status = cudaDeviceGetAttribute(&shared_limit, cudaDevAttrMaxSharedMemoryPerBlockOptin, device);
  if (status != cudaSuccess || cluster_launch == 0 || major < 9) return status;
  if (blocks < 1 || blocks > kClusterBlocks || rows < 32 || rows > kClusterRows || rows % 32 != 0 ||
      shared_bytes > shared_limit) {
    return cudaSuccess;
  }
  cudaLaunchAttribute attribute{};
  cudaLaunchConfig_t config{};
  status = cluster_launch_config<Real>(blocks, blocks, rows, shared_bytes, nullptr, attribute, config);
  // A device without non-portable sizes refuses the attribute: no fit, not an error.
  if (status == cudaErrorInvalidValue || status == cudaErrorNotSupported) {
    cudaGetLastError();
    return cudaSuccess;
  }
  if (status != cudaSuccess) return status;
  int clusters = 0;
  status =
      cudaOccupancyMaxActiveClusters(&clusters, reinterpret_cast<const void*>(cluster_euler_kernel<Real>), &config);
  if (status == cudaErrorInvalidValue || status == cudaErrorInvalidClusterSize) {
    cudaGetLastError();
    return cudaSuccess;
  }
  fits = status == cudaSuccess && clusters >= 1;
  return status;
}

template <typename Real>
cudaError_t launch_cluster_euler(const ClusterEulerArguments<Real>& arguments, cudaStream_t stream) {
  const PersistentEulerArguments<Real>& chunk = arguments.chunk;
  if (chunk.step.vertex_count <= 0 || chunk.steps <= 0) return cudaSuccess;
  if (arguments.blocks < 1 || arguments.rows < 32 || arguments.rows > kClusterRows || arguments.rows % 32 != 0 ||
      arguments.cluster_blocks < 1 || arguments.cluster_blocks > kClusterBlocks ||
      arguments.blocks % arguments.cluster_blocks != 0 || chunk.step.model.kind != GatherKind::Springs ||
      chunk.step.model.springs.incidence == nullptr || arguments.window_capacity < 0 ||
      arguments.window_capacity % 4 != 0 || chunk.check_count != 1) {
    return cudaErrorInvalidValue;
  }
  if (chunk.checks.first_non_finite != nullptr) {
    reset_checks_kernel<<<1, kThreadsPerBlock, 0, stream>>>(chunk.checks, 1, chunk.step.vertex_count);
    const cudaError_t reset = cudaGetLastError();
    if (reset != cudaSuccess) return reset;
  }
  cudaLaunchAttribute attribute{};
  cudaLaunchConfig_t config{};
  const cudaError_t status = cluster_launch_config<Real>(arguments.blocks, arguments.cluster_blocks, arguments.rows,
                                                         arguments.shared_bytes, stream, attribute, config);
  if (status != cudaSuccess) return status;
  return cudaLaunchKernelEx(&config, cluster_euler_kernel<Real>, arguments);
}

#define FMPC_PERSISTENT_STEP_LAUNCHERS(Real)                                                               \
  template cudaError_t persistent_euler_block_limit<Real>(GatherKind, long long, int&);                    \
  template cudaError_t launch_persistent_euler<Real>(const PersistentEulerArguments<Real>&, cudaStream_t); \
  template cudaError_t cluster_euler_fits<Real>(int, int, long long, bool&);                               \
  template cudaError_t launch_cluster_euler<Real>(const ClusterEulerArguments<Real>&, cudaStream_t);
FMPC_PERSISTENT_STEP_LAUNCHERS(float)
FMPC_PERSISTENT_STEP_LAUNCHERS(double)

}  // namespace fmpc::gpu
