#pragma once
// Host-side declarations of the kernel launches in kernels/explicit_step.cu, persistent_step.cu, implicit_step.cu and
// reductions.cu: templates over the real type, instantiated there for float and double. Every launcher returns the
// launch's cudaError_t (cudaGetLastError after <<<>>>), never exits; runtime/gpu/ turns it into a Diagnostic.
//
// A batch of scenes is one concatenated network: scene s owns a contiguous range of vertices and springs, its CSR
// entries point at its own vertices only, so one thread per vertex serves every scene in one launch. Per-scene time
// steps are read through vertex_scene (null for a single scene, which then uses `h`).
#include <cuda_runtime_api.h>

#include "kernels/element_laws.h"
#include "kernels/implicit_math.h"
#include "kernels/integrator_math.h"
#include "kernels/internal_force_math.h"
#include "kernels/spring_math.h"
#include "kernels/strain_table_math.h"
#include "kernels/tetrahedron_math.h"
#include "runtime/gpu/launch_shapes.h"

namespace fmpc::gpu {

using kernels::kMostElementTerms;

// A force model on the device: the springs (Springs, SpringsAndElements), and the element terms (kernels/
// element_term.h) with the corner forces their passes write (the first term's, then each later one's added) and the
// per-vertex gather reads (Elements, SpringsAndElements).
template <typename Real>
struct ForceModelView {
  GatherKind kind;
  kernels::SpringNetworkView<Real> springs;
  kernels::ElementTermView<Real> terms[kMostElementTerms];
  int term_count;
  int element_count;
  kernels::CornerForceView<Real> corners;    // corners.force == corner_force
  kernels::CornerForce<Real>* corner_force;  // 4 per element
  // float: the element pass's register bound, 2 or 3 blocks per SM (GpuOptions); 0: the element kind's default.
  int element_blocks = 0;
  // Thread r of the kernels with one thread per vertex takes vertex vertex_order[r] (springs.sliced's order); null:
  // vertex r. A permutation within each block, so a block covers the same vertices either way.
  const int* vertex_order = nullptr;
  // An element kind with a nodal pass (kernels::element_kind_has_nodal_pass): per term, the arrays behind
  // terms[t].nodal_pressure and nodal_dilatation, which launch_element_forces' nodal pass writes for the batch's
  // vertex_count vertices before the element pass reads them; null for the other kinds.
  Real* nodal_pressure[kMostElementTerms] = {};
  Real* nodal_dilatation[kMostElementTerms] = {};
  int vertex_count = 0;
};

// One term's nodal pass (kernels/elements/linear_nodal_pressure.h) in Real at a state in StateReal: every element's
// shares at its corner slots (kernels::element_nodal_shares, into `shares`: the engine's corner forces, which the
// element pass then overwrites, or a buffer of the energy's own), then every vertex's pressure and dilatation
// (kernels::nodal_pressure_at, summed in the corners' CSR order): the CPU engine's nodal_pass, two launches.
template <typename Real>
struct NodalPassArguments {
  kernels::ElementTermView<Real> term;  // its nodal_pressure and nodal_dilatation are not read
  kernels::CornerForce<Real>* shares;   // one per corner slot
  const int* corner_offset;             // the corners' CSR (kernels::CornerForceView)
  const int* corner_index;
  Real* pressure;  // per vertex
  Real* dilatation;
  int vertex_count;
};
// Instantiated for <float, float> and <double, double> (the element pass's) and <double, float> (a float run's
// energy, summed in double as the host sums it).
template <typename Real, typename StateReal>
cudaError_t launch_nodal_pass(const NodalPassArguments<Real>& arguments, const kernels::StateView<StateReal>& state,
                              cudaStream_t stream);

// The springs' incidence records (kernels::SpringIncidence) of every CSR entry, from the network's arrays; run once
// after upload, and only where the stiffness stays fixed during the run (no strain table).
template <typename Real>
cudaError_t launch_spring_incidence(const kernels::SpringNetworkView<Real>& network, int entries,
                                    kernels::SpringIncidence<Real>* incidence, cudaStream_t stream);

// Fills the sliced layout's records (network.sliced.row set) from the network's CSR arrays, one thread per row,
// whose vertex is vertex_order[row] (kernels::write_sliced_row); run once after upload, like launch_spring_incidence.
template <typename Real>
cudaError_t launch_sliced_springs(const kernels::SpringNetworkView<Real>& network, const int* vertex_order,
                                  int vertex_count, kernels::SpringIncidence<Real>* record, cudaStream_t stream);

// The element pass at `state`: every element's corner forces (kernels::element_node_forces), one launch per term
// with its law a template argument, the later terms' forces added to the first's; nothing without terms. A kind with
// a nodal pass runs it first for every term (launch_nodal_pass, as the CPU engine's accelerations). Enqueued before
// every per-vertex kernel that gathers at that state.
template <typename Real>
cudaError_t launch_element_forces(const ForceModelView<Real>& model, const kernels::StateView<Real>& state,
                                  cudaStream_t stream);

// The stateful terms' per-point state update after an accepted step at `state` (kernels::element_state_update), one
// launch per term with state; nothing for the others.
template <typename Real>
cudaError_t launch_point_state_update(const ForceModelView<Real>& model, const kernels::StateView<Real>& state,
                                      cudaStream_t stream);

template <typename Real>
struct MutableStateView {
  Real* x;
  Real* y;
  Real* z;
  Real* vx;
  Real* vy;
  Real* vz;
};

template <typename Real>
FMPC_HD kernels::StateView<Real> read_only(const MutableStateView<Real>& s) {
  return {s.x, s.y, s.z, s.vx, s.vy, s.vz};
}

// The state `offset` entries further into each of s's arrays (a checkpoint slot of several in one allocation).
template <typename Real>
FMPC_HD MutableStateView<Real> offset_state(const MutableStateView<Real>& s, long long offset) {
  return {s.x + offset, s.y + offset, s.z + offset, s.vx + offset, s.vy + offset, s.vz + offset};
}

template <typename Real>
struct MutableVector3View {
  Real* x;
  Real* y;
  Real* z;
};

// The step size of each vertex: scene_h[vertex_scene[v]] in a batch, h otherwise.
template <typename Real>
struct StepSize {
  const int* vertex_scene;  // null: every vertex uses h
  const Real* scene_h;
  Real h;
};

template <typename Real>
struct ProbeArguments {
  const int* vertices;     // every probing scene's probe vertices, concatenated (batch vertex indices)
  const int* entry_scene;  // per entry: its scene's index in `scenes`
  int count;               // entries
  const double* start_x;   // the probe vertices' start positions (m)
  const double* start_y;
  const double* start_z;
  const double* base_force_x;  // force probes: the vertices' own external force (N), read where has_base_force
  const double* base_force_y;
  const double* base_force_z;
  const ProbeScene* scenes;
  const unsigned long long* step_base;
  MutableStateView<Real> state;    // displacement probes write here
  MutableVector3View<Real> force;  // force probes write here
};
template <typename Real>
cudaError_t launch_apply_probe(const ProbeArguments<Real>& arguments, int offset, bool before_step,
                               cudaStream_t stream);

enum class FusedScheme : int { ForwardEuler = 0, SemiImplicitEuler = 1 };

template <typename Real>
struct FusedStepArguments {
  ForceModelView<Real> model;
  kernels::VertexLoads<Real> loads;
  kernels::StateView<Real> in;  // state at t
  MutableStateView<Real> out;   // state at t + h (a different buffer: neighbours read `in` while `out` is written)
  int vertex_count;
  FusedScheme scheme;
  StepSize<Real> step;
  int lanes;  // threads per vertex: 0 or 1 (one thread walks its vertex's entries), or valid_lanes
  // Probe entries applied by their vertex's own thread (the one that updates it), after the step at probe_offset
  // and, where probe_next, before the next step: the probe kernels' values in the persistent kernel's order, so
  // consecutive steps need no probe launches between them. probe_entry (per vertex: its entry, -1 for none) null:
  // none; probe.state is ignored (the thread writes `out`).
  ProbeArguments<Real> probe;
  const int* probe_entry;
  int probe_offset;
  bool probe_next;
};

// One fused kernel per step: gather the model's forces (springs over their CSR adjacency, elements' corner forces
// from the element pass launched before it), add the loads, update the vertex. With lanes > 1, that many threads
// share a vertex's entries and add the terms in CSR order (as the persistent kernel): the same bits, more loads in
// flight per vertex (the gather of a large mesh is latency-bound with one thread walking about 14 entries).
template <typename Real>
cudaError_t launch_fused_step(const FusedStepArguments<Real>& arguments, cudaStream_t stream);

// Velocity Verlet, two kernels per step (the second gathers at positions the first one wrote):
//   drift: x += h v + h^2/2 a, predicted = v + h a            (own vertex only)
//   kick:  a1 = a(x, predicted), v += h/2 (a + a1), a = a1     (gathers x and predicted of the neighbours)
// `acceleration` alone computes a = a(x, v), for the first step.
template <typename Real>
struct VerletArguments {
  ForceModelView<Real> model;
  kernels::VertexLoads<Real> loads;
  MutableStateView<Real> state;           // x and v, updated in place
  MutableVector3View<Real> acceleration;  // a at the current positions
  MutableVector3View<Real> predicted;     // the velocity predictor v + h a
  int vertex_count;
  StepSize<Real> step;
};
template <typename Real>
cudaError_t launch_acceleration(const VerletArguments<Real>& arguments, cudaStream_t stream);
template <typename Real>
cudaError_t launch_verlet_drift(const VerletArguments<Real>& arguments, cudaStream_t stream);
template <typename Real>
cudaError_t launch_verlet_kick(const VerletArguments<Real>& arguments, cudaStream_t stream);

// Classical RK4 as four gather kernels per step. Stage s (0..3) gathers the acceleration at the stage state
// (stage_position[s], stage_velocity[s]) (stage 0: the state itself), stores it, and writes the next stage's state
// of its own vertex: position + c_{s+1} k_v, velocity + c_{s+1} k_a (c = h/2, h/2, h). Stage 3 combines the four
// slopes with runge_kutta4_combine into the state. Stage positions alternate between two buffers so that no kernel
// writes what its neighbours read.
template <typename Real>
struct RungeKutta4Arguments {
  ForceModelView<Real> model;
  kernels::VertexLoads<Real> loads;
  MutableStateView<Real> state;                    // y0, combined in place by stage 3
  MutableVector3View<Real> stage_position[4];      // [0] unused (the state); [1] and [3] share a buffer
  MutableVector3View<Real> stage_velocity[4];      // k_v of each stage; [0] unused (the state's velocity)
  MutableVector3View<Real> stage_acceleration[3];  // k_a of stages 0..2 (stage 3's stays in registers)
  int vertex_count;
  StepSize<Real> step;
};
template <typename Real>
cudaError_t launch_runge_kutta4_stage(const RungeKutta4Arguments<Real>& arguments, int stage, cudaStream_t stream);

// The checks advance makes after a chunk, made by the persistent kernels (at the end of a launch on its final state,
// and the cooperative grid's at each check within it: PersistentEulerArguments::check_count), one download per
// launch instead of two kernels and their copies per check: what launch_find_non_finite and launch_count_inverted
// compute, with their presets written by the kernel itself. first_non_finite null: no checks. The pointers are check
// 0's results; check j's are slot_stride entries further (one buffer of slot_stride x checks).
struct PersistentChecks {
  int* first_non_finite;
  const int* nodes;  // the element kind's nodes, its kNodes per element (kernels::element_inverted)
  int element_kind;  // index in kernels::ElementKinds
  int element_count;
  const int* element_scene;  // null: every element is scene 0's
  int scene_count;
  unsigned int* inverted_count;  // per scene
  int* inverted_first;           // per scene
  int slot_stride;
};

// Forward or semi-implicit Euler for `steps` steps in one cooperative launch (issue 13, small meshes): the grid stays
// resident and barriers separate the steps instead of kernel boundaries, which removes the launch gaps. Block b takes
// `rows` consecutive vertices and keeps their state in registers and in its shared memory, with their CSR records.
// Each step its threads first compute the terms of all its springs side by side (a small mesh's step is otherwise
// bound by one thread's chain of dependent loads over its vertex's entries), then one thread per vertex adds its
// vertex's terms in CSR order and runs the fused step's per-vertex functions and the probe's per-entry function in
// the per-step order (probe before the step, element pass, gather and update, probe after): the results are bitwise
// those of launch_fused_step with launch_apply_probe around it. The probe before step k + 1 is applied right after
// the probe after step k by the vertex's own thread. With springs alone a block waits before each step only for the
// blocks whose vertices its springs reach (BlockNeighbours), not for the whole grid; with elements a grid barrier
// follows the element pass (the gather reads its corner forces) and each update (the next element pass reads every
// vertex). No strain table (its lookup needs a third barrier; those runs take the per-step path).
//
// Why waiting on the neighbours alone is safe: block b at step s reads the state of step s of its own and its
// neighbours' vertices (state[s % 2]) and writes step s + 1 into state[(s + 1) % 2], which holds step s - 1. The
// springs make "reads a vertex of" symmetric, so the blocks that read b's step s - 1 are the blocks b waits for, and
// b starts step s only once each of them has published step s, after its reads of step s - 1.
struct BlockNeighbours {
  const int* offset;     // per block + 1: its range of `block`
  const int* block;      // the other blocks owning a neighbour of one of its vertices, ascending
  unsigned* steps_done;  // per block: the steps of this launch it has published (reset at the launch's start)
};
template <typename Real>
struct PersistentEulerArguments {
  // in, out, probe_offset and probe_next are ignored: the kernel alternates state[0] and state[1] and applies the
  // probe entries around every step of the chunk.
  FusedStepArguments<Real> step;
  MutableStateView<Real> state[2];
  int first_parity;  // the buffer holding the state at the chunk's start
  int steps;
  // The chunk's first step, for the probe's times: by value, so that no copy to the device precedes each launch
  // (step.probe.step_base is not read).
  unsigned long long step_base;
  int blocks;  // grid size: at most persistent_euler_block_limit's
  int rows;    // vertices per block: block b takes [b rows, (b + 1) rows); 1..kPersistentThreads
  // The launch's checks: check_count of them, the last at its end (the cluster kernel takes one); check j before it
  // comes after step first_check + j check_every (counted from 1), on the state a launch ending there would hold
  // (before the probe's prescription for the next step).
  PersistentChecks checks;
  int check_count;
  int first_check;
  int check_every;
  // The advance's checkpoints, which the host would otherwise copy after each check: slot k of each array at
  // checkpoints + k checkpoint_stride. Slot 0 takes the state the launch starts from (before the probe) where
  // store_start; slot j + 1 the state at check j before the last.
  MutableStateView<Real> checkpoints;
  long long checkpoint_stride;
  bool store_start;
  int block_records;           // the most CSR entries of a block (with springs)
  int most_neighbour_blocks;   // the most blocks a block waits for (springs alone)
  BlockNeighbours neighbours;  // springs alone
};
// The most blocks of kPersistentThreads threads with `shared_bytes` of dynamic shared memory each that a persistent
// launch may use (and raises the kernel's shared memory limit to `shared_bytes`, which its launches then need), every
// block resident at once (cudaOccupancyMaxActiveBlocksPerMultiprocessor x multiprocessors); 0 where the device cannot
// launch cooperative kernels or a block cannot have that much shared memory. A launch with more blocks fails
// (cudaErrorCooperativeLaunchTooLarge).
template <typename Real>
cudaError_t persistent_euler_block_limit(GatherKind kind, long long shared_bytes, int& blocks);
template <typename Real>
cudaError_t launch_persistent_euler(const PersistentEulerArguments<Real>& arguments, cudaStream_t stream);

// Springs alone in thread-block clusters (Hopper, issue 13's small meshes and cohorts): each cluster advances a group
// of whole scenes for the whole chunk with their state on chip, in its blocks' shared memory, and the cluster's
// hardware barrier replaces the grid barrier of launch_persistent_euler; clusters never wait on each other, so a
// batch of many scenes needs no grid-wide barrier and may exceed what the GPU holds at once. Thread r of a block
// takes vertex first_vertex + r, keeps its position and velocity in registers and publishes them every step into a
// double-buffered copy in its block's shared memory. Before each step a block of a cluster of several copies its
// window, the contiguous range of vertices its gathers read (its own and their neighbours), from its cluster's
// published copies into its own shared memory: consecutive threads read consecutive vertices, which distributed
// shared memory serves in whole requests, where each thread's gather reading its neighbours remotely made a request
// per value (62,710 steps/s on the 20^3 box against 95,382 with windows; H100). Each block copies its vertices' CSR
// records (model.springs.incidence) into shared memory once per launch. The terms are kernels::sum_spring_terms' in
// CSR order and the step, probe and checks the persistent kernel's functions: the same bits. At the end both global
// state buffers hold what the persistent kernel leaves there (the last state and the one before it).
template <typename Real>
struct ClusterEulerArguments {
  // step (with the CSR records: model.springs.incidence), state, first_parity, steps and checks as for
  // launch_persistent_euler; its blocks and rows are ignored.
  PersistentEulerArguments<Real> chunk;
  const ClusterBlock* block;  // per block of the grid; a cluster's blocks take consecutive vertices from its first
  int blocks;                 // the grid: clusters x cluster_blocks
  int cluster_blocks;         // blocks per cluster: 1..kClusterBlocks
  int rows;                   // threads per block: a multiple of 32 up to kClusterRows
  int window_capacity;        // the longest window of a cluster of several blocks, a multiple of 4 (0: none)
  int shared_bytes;           // cluster_euler_shared_bytes(rows, window_capacity, the most records of a block)
};
// Whether the device launches clusters of `blocks` blocks of `rows` threads with `shared_bytes` each, one cluster
// resident (compute capability 9.0 or newer; more than 8 blocks where the device allows non-portable sizes). False,
// with cudaSuccess, where it does not.
template <typename Real>
cudaError_t cluster_euler_fits(int blocks, int rows, long long shared_bytes, bool& fits);
template <typename Real>
cudaError_t launch_cluster_euler(const ClusterEulerArguments<Real>& arguments, cudaStream_t stream);

// k(strain) for every spring from the positions in `state` (kernels/strain_table_math.h), before every step.
template <typename Real>
struct StrainStiffnessArguments {
  kernels::StateView<Real> state;
  const int* first;
  const int* second;
  const double* rest_length;
  const double* stiffness_per_modulus;
  kernels::StrainTableView table;  // device pointers
  Real* stiffness;
  int spring_count;
};
template <typename Real>
cudaError_t launch_strain_stiffness(const StrainStiffnessArguments<Real>& arguments, cudaStream_t stream);

// Implicit Euler on the GPU (kernels/implicit_math.h): the system M - h df/dv - h^2 df/dx is applied matrix-free
// from per-spring blocks, and solved by a Jacobi-preconditioned conjugate gradient in double with Eigen's
// iteration and stopping rule (|r|^2 < tol^2 |b|^2, x0 = 0). Dot products use the fixed summation tree of the energy
// sums, so a run gives the same bits every time. The scalars and the stopping test stay on the device: the
// iteration that meets the tolerance or the cap sets `done`, and every later kernel of the step returns at once, so
// the host enqueues iterations in chunks and reads these scalars once per chunk (or, from the cooperative kernel,
// once per run: a slot per step), never once per iteration.
struct ConjugateGradientScalars {
  double rhs_norm2;  // |b|^2
  double threshold;  // max(tol^2 |b|^2, DBL_MIN) (NaN stays NaN, as std::max on the host)
  double rz;         // r . z of the current direction (Eigen's absNew)
  double p_ap;       // p . A p
  double alpha;      // rz / p_ap
  double rr;         // |r|^2 after the last update (|b|^2 before the first)
  double rz_next;    // r . z after the update
  double beta;       // rz_next / rz
  int iterations;    // matrix products so far, the converging one included (the CPU's count)
  int done;          // 1: at rest, converged, or at the cap; nothing more runs this step
  int at_rest;       // 1: |b| < 1e-150, dv = 0 (the CPU backend's rule)
  // Blocks of a fused stage launch (launch_cg_iterations) that have stored their partial sums; the last resets it.
  unsigned int arrivals;
};

// The element part of implicit Euler, in double: each term's linearisation of each element at the step's start (its
// law's Linearisation, e.g. a rotation or a volume gradient), and per corner 3 values each of h^2 K v0, of the
// diagonal of (h^2 + h beta) K_aa, and of (h^2 + h beta) K p for the conjugate gradient's current direction (fixed
// corners' p taken as zero), the terms summed in order, gathered per vertex over the corner CSR.
struct ImplicitElements {
  int count;  // elements; 0: none
  int term_count;
  kernels::ElementTermView<double> terms[kMostElementTerms];
  void* linearisation[kMostElementTerms];  // per term: one of its element kind's Linearisation<Law> per element
  double* rhs_part;                        // 3 per node of each element
  double* diagonal_part;                   // 3 per node of each element
  double* product;                         // 3 per node of each element
};

template <typename Real>
struct ImplicitArguments {
  ForceModelView<Real> model;
  ImplicitElements elements;  // count 0: none
  kernels::VertexLoads<Real> loads;
  MutableStateView<Real> state;
  const int* first;  // spring ends
  const int* second;
  const double* rest_length;    // double, as the CPU assembly reads them
  const double* mass;           // double
  const double* rest_position;  // x0 of the nodal damping, xyz interleaved (3 per vertex), double
  double h;
  int vertex_count;
  int spring_count;
  double* blocks;  // 12 per spring: K_s (6) then the system block (6)
  // A linear part of the system a caller fills (null: none): per vertex a symmetric block (6) added to its diagonal
  // block and 3 values added to b, on the free axes (the tools' contact, launch_contact_part).
  double* extra_blocks;
  double* extra_rhs;
  // The tools' contact (null without tools): per vertex its active set (bit t: tool t pushes it), and the count of
  // sets launch_contact_part changed.
  unsigned char* contact_active;
  unsigned int* contact_changes;
  double* diagonal;        // per vertex: m + h (gamma0 + gamma1 |x - x0|); 1 for fixed vertices
  double* inverse_jacobi;  // 3 per vertex
  double* rhs;             // 3 per vertex, b
  double* x;               // dv
  double* r;
  double* z;
  double* p;
  double* ap;
  ConjugateGradientScalars* scalars;
  double* partial;      // 4 * kEnergyBlocks (the cooperative kernel's second pair of partial sums after the first)
  double tolerance;     // relative residual |r| / |b| to reach
  int iteration_limit;  // the cap (sim::implicit_iteration_limit)
};
// Blocks of every spring and the linearisation of every element (where `linearise`), then b, the diagonal and the
// Jacobi preconditioner of every vertex. Without `linearise` the step's blocks and linearisation, which depend on its
// state alone, are kept and only the vertices' part is redone: after the tools' contact changed the linear part.
template <typename Real>
cudaError_t launch_implicit_assemble(const ImplicitArguments<Real>& arguments, bool linearise, cudaStream_t stream);
// x = 0, r = b, z = p = M^-1 r, scalars: rhs_norm2 = b.b, rz = r.z, the threshold, iterations 0, and done where
// the system is at rest, |b|^2 is not above the threshold (or NaN) or the cap is 0.
// fused: as one stage launch (LaunchPlan::cg_fused_stages).
template <typename Real>
cudaError_t launch_cg_start(const ImplicitArguments<Real>& arguments, bool fused, cudaStream_t stream);
// `count` iterations enqueued one launch per kernel, each a no-op once `done` is set: ap = A p (the elements'
// product first, then per vertex), alpha = rz / p.ap, x += alpha p, r -= alpha ap, z = M^-1 r, rr = r.r,
// rz_next = r.z, beta, the stopping test; then, unless done, p = z + beta p, rz = rz_next. fused: the rows with p.Ap
// and alpha, and the update with its sums and the test, each one launch (LaunchPlan::cg_fused_stages).
template <typename Real>
cudaError_t launch_cg_iterations(const ImplicitArguments<Real>& arguments, int count, bool fused, cudaStream_t stream);
// The whole conjugate gradient of a step (after launch_cg_start) in one cooperative launch of `blocks` blocks of
// kEnergyThreads threads with grid barriers: the same arithmetic in the same order as launch_cg_iterations, so the
// same bits. blocks: 1 to cg_persistent_block_limit's.
template <typename Real>
cudaError_t launch_cg_persistent(const ImplicitArguments<Real>& arguments, int blocks, cudaStream_t stream);
// Blocks of launch_cg_persistent resident at once on the device (0: no cooperative launches).
template <typename Real>
cudaError_t cg_persistent_block_limit(int& blocks);
// A step's whole solve in one block of kCgBlockThreads threads with `bytes` of shared memory at `layout`
// (LaunchPlan::cg_block): launch_cg_start's start, launch_cg_persistent's iterations with block barriers and, where
// `finish`, launch_implicit_finish's update; the same arithmetic in the same order, so the same bits; dv in x and
// the scalars written as those launches leave them.
template <typename Real>
cudaError_t launch_cg_block(const ImplicitArguments<Real>& arguments, const CgBlockLayout& layout, long long bytes,
                            bool finish, cudaStream_t stream);
// The most dynamic shared memory launch_cg_block's block may have (0: it cannot run kCgBlockThreads threads); lets
// the kernel ask for that much (once, before its first launch).
template <typename Real>
cudaError_t cg_block_shared_limit(long long& bytes);
// The tools' contact as the system's linear part (kernels/implicit_contact_math.h): every vertex's active set at
// the state (predicted false: the step's first set, every vertex's part written) or predicted from the solution in
// x (the vertices whose set changed are counted into *contact_changes, preset by the caller, and get their new part).
// Nothing without tools.
template <typename Real>
cudaError_t launch_contact_part(const ImplicitArguments<Real>& arguments, bool predicted, cudaStream_t stream);
// v += dv, x += h v on the free vertices (x and v in Real, as the CPU backend).
template <typename Real>
cudaError_t launch_implicit_finish(const ImplicitArguments<Real>& arguments, cudaStream_t stream);

// Writes into *first_vertex (device memory, preset to vertex_count) the smallest vertex index whose position or
// velocity is NaN or infinite (integer atomicMin: the answer does not depend on scheduling).
template <typename Real>
cudaError_t launch_find_non_finite(const kernels::StateView<Real>& state, int vertex_count, int* first_vertex,
                                   cudaStream_t stream);

// Copies a state's six arrays (vertex_count entries each) in one kernel: the checkpoint at every check. Six
// device-to-device copies per check cost the copy engine's scheduling each, and a haptic loop checks every tick.
template <typename Real>
cudaError_t launch_copy_state(const MutableStateView<Real>& to, const kernels::StateView<Real>& from, int vertex_count,
                              cudaStream_t stream);

// Inverted elements of kind `element_kind` (kernels::element_inverted: the kind's own test on its nodes, kNodes per
// element in `nodes`) at `state`, per scene: count[scene] += 1 (integer atomics: the count does not depend on
// scheduling) and first[scene] = the smallest inverted element index (atomicMin). element_scene null: every element
// is scene 0's. count and first are preset by the caller (0 and element_count).
template <typename Real>
cudaError_t launch_count_inverted(const int* nodes, int element_kind, int element_count, const int* element_scene,
                                  const kernels::StateView<Real>& state, unsigned int* count, int* first,
                                  cudaStream_t stream);


template <typename Real>
struct EnergyArguments {
  kernels::StateView<Real> state;
  const double* mass;  // kg, as given (not rounded to Real)
  const int* spring_first;
  const int* spring_second;
  const double* rest_length;
  const double* stiffness;
  kernels::SpringLawParameters<double> law;
  // With a strain table (table.strain not null): k = strain_table_stiffness(...) at the current length instead.
  kernels::StrainTableView table;
  const double* stiffness_per_modulus;
  double gravity_x, gravity_y, gravity_z;
  const double* force_x;  // null: no external forces
  const double* force_y;
  const double* force_z;
  // ElementPotential: one element term in double and the elements' corners.
  kernels::ElementTermView<double> element_term;
};

enum class EnergyTerm : int {
  Kinetic = 0,           // sum over vertices of m |v|^2 / 2
  SpringPotential = 1,   // sum over springs of spring_potential_energy
  LoadPotential = 2,     // sum over vertices of -(m g + f) . x
  ElementPotential = 3,  // sum over elements of element_term's law's energy
};

// Sums the term over [begin, end) into *result (device memory); `partial` holds kEnergyBlocks doubles.
// The vertices' start positions in double (the setup's initial positions, or its rest positions).
struct StartPositions {
  const double* x;
  const double* y;
  const double* z;
};

// The largest distance of a vertex in [begin, end) from its start, into *result (double), with partial[kEnergyBlocks]
// as scratch: the same bits as the host's sim::largest_displacement on the downloaded state.
template <typename Real>
cudaError_t launch_largest_displacement(const kernels::StateView<Real>& state, const StartPositions& start, int begin,
                                        int end, double* partial, double* result, cudaStream_t stream);

template <typename Real>
cudaError_t launch_energy_sum(const EnergyArguments<Real>& arguments, EnergyTerm term, int begin, int end,
                              double* partial, double* result, cudaStream_t stream);

}  // namespace fmpc::gpu
