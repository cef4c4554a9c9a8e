#pragma once
// The CUDA engine of a batch (runtime/integrate/stepping_engine.h), by job: gpu_engine_upload.cpp (the batch's
// arrays on the device and the launch plan), gpu_engine_steps.cpp (a step's schedule, graph and persistent launches),
// gpu_engine_steppers.cpp (one stepper per explicit integrator family), gpu_engine_implicit.cpp (implicit Euler's
// conjugate gradient), gpu_engine_checks.cpp (the checkpoint, non-finite and inversion checks) and
// gpu_engine_readback.cpp (states, probe readings, energies). Each instantiates its members for float and double.
// Internal to runtime/gpu/: users hold a sim::Simulation.
#include <cuda_runtime_api.h>

#include <array>
#include <cstddef>
#include <map>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include "runtime/gpu/batch_concatenation.h"
#include "runtime/gpu/device_arrays.h"
#include "runtime/gpu/gpu_launch.h"
#include "runtime/gpu/gpu_simulation.h"
#include "runtime/gpu/launch_plan.h"
#include "runtime/integrate/stepping_engine.h"

namespace fmpc::gpu {

// Longer chunks replay the same graph several times: a graph's size (and its instantiation time) grows with its
// kernel count, while the launch overhead saved per step does not improve beyond a few hundred steps.
constexpr std::size_t kMaxStepsPerGraph = 256;

// A persistent launch's most steps (about 3 s of the 20^3 box): longer stretches between checks run as several.
constexpr std::size_t kMostPersistentLaunchSteps = std::size_t{1} << 20;

// Page-locked staging for downloads (download_ranges): 4 MiB of float, 8 of double.
constexpr std::size_t kDownloadStagingEntries = std::size_t{1} << 20;

// The CUDA engine of a batch (runtime/integrate/stepping_engine.h): upload, launch choice, the integrators'
// enqueueing with persistent and graph launches, the checks' data and the checkpoint, read-back.
template <typename Real>
class GpuEngine final : public sim::SteppingEngine {
 public:
  GpuEngine(const std::vector<sim::SimulationSetup>& scenes, const std::vector<sim::StabilityReport>& stability,
            const GpuOptions& options)
      : scenes_(scenes), stability_(stability), options_(options) {}

  ~GpuEngine() override {
    // The device's own memory, stream and graphs are released on it, whichever thread destroys the engine; a
    // destructor cannot report, and a failure here leaves the frees below to fail alike.
    if (options_.device >= 0) cudaSetDevice(options_.device);
    graphs_.clear();
    if (stream_ != nullptr) cudaStreamDestroy(stream_);
  }

  bool upload(DiagnosticList& diagnostics);

  // The springs' incidence records, where the stiffness stays fixed during the run (no strain table): in the sliced
  // layout for the kernels with one thread per vertex (kernels::SlicedSpringsView), else in CSR order for the
  // persistent kernels (cooperative or in clusters) and the kernels whose lanes share a vertex (gather_lanes > 1).
  // Only the one the launches use is built.
  bool upload_spring_records(const ConcatenatedScenes& c, DiagnosticList& diagnostics);

  // The element terms: the geometry and each term's parameters in Real for the element pass and in double for
  // implicit Euler and the energy sums, the corner CSR and the corner forces. The strain table (uploaded with the
  // single-scene features) is attached to the views of the terms whose law reads one afterwards.
  bool upload_elements(const ConcatenatedScenes& c, DiagnosticList& diagnostics);

  // Every scene's probe: its vertices (batch indices), start positions and own external forces, concatenated, and
  // one ProbeScene each. Nothing is allocated when no scene has a probe.
  bool upload_probes(DiagnosticList& diagnostics);

  // The launch plan (runtime/gpu/launch_plan.h: the per-step kernel's lanes, and whether chunks of forward or
  // semi-implicit Euler run as one persistent launch each, on a cooperative grid or in thread-block clusters), with
  // the device's answers about its kernels; then what the plan's launches need uploaded or allocated.
  bool plan_launches(const ConcatenatedScenes& c, DiagnosticList& diagnostics);

  // Where a persistent launch writes its checks' results: check_results_, a slot of plan_.check_slot_stride each.
  PersistentChecks persistent_checks() const;

  // The strain table and implicit Euler's buffers (a batch of one scene only; create() refuses them in larger
  // batches). Nothing is allocated for what the scene does not use.
  bool upload_single_scene_features(DiagnosticList& diagnostics);

  const char* label() const override { return "GPU "; }
  std::size_t steps_taken() const override { return steps_taken_; }
  // A persistent launch on the cooperative grid takes plan_.persistent_checks; otherwise one check per run.
  std::size_t checks_per_run() const override { return plan_.grid_blocks > 0 ? plan_.persistent_checks : 1; }
  std::size_t most_steps_per_run() const override { return kMostPersistentLaunchSteps; }
  bool non_finite_is_exact() const override { return false; }
  sim::SimulationLaunches launches() const override { return {persistent_launch(), cluster_launch()}; }
  bool reduces_in_place() const override { return true; }

  bool run(const std::vector<std::size_t>& ends, DiagnosticList& diagnostics) override;

  // A persistent launch's check before its last is only in its checkpoint slot: the checks read that slot, and a
  // checkpoint saved there is that slot (save_checkpoint).
  void select_check(std::size_t check) override;

  std::vector<sim::Point3> positions(std::size_t scene, DiagnosticList& diagnostics) const override;
  std::vector<sim::Point3> velocities(std::size_t scene, DiagnosticList& diagnostics) const override;

  bool scene_states(std::vector<std::vector<sim::Point3>>& positions, std::vector<std::vector<sim::Point3>>* velocities,
                    DiagnosticList& diagnostics) const override;

  std::vector<double> current_stiffness(std::size_t scene, DiagnosticList& diagnostics) const override;

  // The held state's position arrays at the scene's first vertex, after the stream has finished.
  std::optional<sim::DevicePositions> device_positions(std::size_t scene, DiagnosticList& diagnostics) const override;

  // Every sample of a probed scene reads it (100 per run): positions and velocities with one synchronisation into
  // buffers kept between readings, and without a strain table the stiffness as uploaded (rounded to Real), made once
  // for the scene instead of downloaded. Fresh buffers and the stiffness made per reading cost about 0.3 ms per
  // sample of the 20^3 box, mostly page faults (H100 machine).
  sim::ProbeReading probe_reading(std::size_t scene, DiagnosticList& diagnostics) const override;

  int implicit_max_iterations_used() const override { return implicit_log_.report().iterations_max; }
  sim::ImplicitSolverReport implicit_solver(std::size_t) const override { return implicit_log_.report(); }
  std::vector<sim::ImplicitStepRecord> take_implicit_steps(std::size_t) override { return implicit_log_.take(); }
  bool persistent_launch() const { return plan_.persistent(); }
  bool cluster_launch() const { return !plan_.cluster_blocks.empty(); }

  std::optional<double> kinetic_energy(std::size_t scene, DiagnosticList& diagnostics) const override;
  std::optional<double> largest_displacement(std::size_t scene, DiagnosticList& diagnostics) const override;
  std::optional<double> elastic_energy(std::size_t scene, DiagnosticList& diagnostics) const override;
  std::optional<double> potential_energy(std::size_t scene, DiagnosticList& diagnostics) const override;

  // Rigid tools and the material (gpu_engine_contact.cpp): a batch with tools is one scene (batch_accepts). The
  // contact stiffness and the tools' shapes are written into allocations made once, whose pointers loads_ (and so
  // every captured graph) keeps; a pose costs one copy of kMostTools shapes on the stream.
  bool set_contact(std::size_t scene, const std::vector<double>& stiffness, const std::vector<double>& damping,
                   DiagnosticList& diagnostics) override;
  bool set_tool_shapes(std::size_t scene, const std::vector<kernels::ToolShape<double>>& shapes,
                       DiagnosticList& diagnostics) override;
  // The scenes' material arrays copied again into their allocations (Real and double), and the springs' records
  // rebuilt from them; graphs are captured again on their next use.
  bool refresh_material(std::size_t scene, DiagnosticList& diagnostics) override;

 private:
  bool synchronize(DiagnosticList& diagnostics) const;

  sim::Integrator scheme() const { return scenes_.front().integrator; }
  // Forward or semi-implicit Euler: one fused kernel per step from state buffer `current_` into the other.
  bool fused_scheme() const {
    return scheme() == sim::Integrator::ForwardEuler || scheme() == sim::Integrator::SemiImplicitEuler;
  }

  // Inverted elements per scene now: counts and each scene's smallest inverted element (local index, -1: none).
  bool count_inverted(std::vector<unsigned int>& counts, std::vector<int>& firsts,
                      DiagnosticList& diagnostics) override;

  // Enqueues `count` steps on the stream (directly or while capturing); `parity` is the Euler state buffer read
  // first and is updated to the one holding the result. Around each step, as the CPU backend: the probe before it,
  // the strain table's lookup, the step, the probe after it.
  bool enqueue_steps(std::size_t count, int& parity, DiagnosticList& diagnostics);

  // The integrator families' steppers (gpu_engine_steppers.cpp; implicit Euler's is implicit_solve), one step each
  // on the stream. Euler reads state_[parity] and writes the other buffer, then flips parity; with fused_probes it
  // applies the probe entries from the vertices' own threads after the step (offset: the step's index in the chunk;
  // probe_next: whether another step of the chunk follows).
  bool enqueue_euler_step(int offset, bool probe_next, bool fused_probes, int& parity, DiagnosticList& diagnostics);
  bool enqueue_verlet_step(DiagnosticList& diagnostics);
  bool enqueue_runge_kutta4_step(DiagnosticList& diagnostics);

  bool enqueue_probe(int offset, bool before_step, const DeviceState<Real>& state, DiagnosticList& diagnostics);

  ProbeArguments<Real> probe_arguments(const DeviceState<Real>& state) const;

  bool enqueue_strain_lookup(const DeviceState<Real>& state, DiagnosticList& diagnostics);

  // The stateful element terms' update after an accepted step, at `state` (the step's end); with `jump`, the history
  // of a jump from rest to it (once, after upload: sim::prony_constants at dt = 0).
  bool enqueue_point_state_update(const DeviceState<Real>& state, bool jump, DiagnosticList& diagnostics);

  // The probe kernels' time origin for the chunk about to be enqueued or replayed.
  bool set_step_base(DiagnosticList& diagnostics);

  ImplicitArguments<Real> implicit_arguments();

  bool read_cg_scalars(const ImplicitArguments<Real>& a, ConjugateGradientScalars& scalars,
                       DiagnosticList& diagnostics);

  // One implicit Euler step: assemble, then Eigen's preconditioned conjugate gradient (same iteration, same
  // stopping rule, same warning as the CPU backend) stopping on the device, in one block (LaunchPlan::cg_block,
  // small meshes: the start and the update too), one cooperative launch (LaunchPlan::cg_grid_blocks) or chunks of
  // per-iteration launches, then v += dv, x += h v; with tools, the
  // contact's linear part solved again until its active set stays, as on the CPU. The host reads the solver's
  // scalars once per launch or chunk, so implicit steps are never captured into graphs. A cooperative solve
  // without tools decides nothing on the host: its scalars stay in their own slot of cg_scalars_ and are read with
  // the others at the end of the run (record_deferred_solves), so the host never waits between such steps.
  bool implicit_solve(DiagnosticList& diagnostics);
  // The solver log's record of one solve (and its warning), as the CPU backend writes it.
  void record_solve(std::size_t step, int iterations, const ConjugateGradientScalars& scalars,
                    DiagnosticList& diagnostics);
  // The deferred solves' scalars read in one copy and recorded in step order; run() ends with it.
  bool record_deferred_solves(DiagnosticList& diagnostics);
  // One solve of the system (x = dv) into `scalars`, assembled first (linearise: the step's first solve; a later
  // contact round's redoes only the vertices' part, launch_implicit_assemble).
  bool conjugate_gradient(const ImplicitArguments<Real>& a, bool linearise, ConjugateGradientScalars& scalars,
                          DiagnosticList& diagnostics);

  VerletArguments<Real> verlet_arguments() const;

  RungeKutta4Arguments<Real> runge_kutta4_arguments() const;

  bool run_steps(std::size_t count, bool allow_graph, DiagnosticList& diagnostics);

  // Forward or semi-implicit Euler's arguments but the state buffers and the lanes.
  FusedStepArguments<Real> fused_arguments() const;

  // Persistent launches from the state held through the checks after `ends` (steps_taken_ after each, increasing;
  // at most plan_.persistent_checks of them, one in clusters): one launch, or where a single check is more than
  // kMostPersistentLaunchSteps away, launches without checks up to the last. Where the state held is the checkpoint
  // it goes to slot 0, the state of each check but the last to the slot after it (advance); the checks' results are
  // downloaded.
  bool run_persistent(const std::vector<std::size_t>& ends, DiagnosticList& diagnostics);

  // One persistent launch of `count` steps with checks after checks[j] of them (the last `count`; none: no checks).
  bool launch_persistent(std::size_t count, const std::vector<std::size_t>& checks, DiagnosticList& diagnostics);

  // Replays `count` steps from a graph captured on first use (one per length and starting Euler buffer).
  bool launch_graph(std::size_t count, DiagnosticList& diagnostics);

  bool capture(std::size_t count, cudaGraphExec_t& executable, DiagnosticList& diagnostics);

  bool save_checkpoint(DiagnosticList& diagnostics) override;

  bool restore_checkpoint(DiagnosticList& diagnostics) override;

  // Checkpoint slot `slot` (plan_.persistent_checks of them on the cooperative grid: plan_launches).
  MutableStateView<Real> checkpoint_slot(int slot) const;

  // The n_ vertices' state copied from `from` to `to` on the stream.
  bool copy_state(const MutableStateView<Real>& to, const kernels::StateView<Real>& from, DiagnosticList& diagnostics);

  // The smallest vertex index with a non-finite position or velocity, n_ when there is none.
  std::optional<int> first_non_finite_vertex(DiagnosticList& diagnostics) override;

  bool scene_exists(std::size_t scene, DiagnosticList& diagnostics) const;

  std::vector<sim::Point3> download(std::size_t scene, const DeviceArray<Real>& x, const DeviceArray<Real>& y,
                                    const DeviceArray<Real>& z, DiagnosticList& diagnostics) const;

  std::vector<sim::Point3> download_range(std::size_t begin, std::size_t count, const DeviceArray<Real>& x,
                                          const DeviceArray<Real>& y, const DeviceArray<Real>& z,
                                          DiagnosticList& diagnostics) const;

  // Entries [begin, begin + count) of each triple of arrays (x, y, z) as points into out[t] (resized, so a buffer
  // kept between calls is not allocated again); false after a device error (reported). Through page-locked staging
  // of kDownloadStagingEntries Reals, one synchronisation per piece that fills it (a sample of the 20^3 box's
  // positions and velocities is one), where copies into pageable memory each wait for the stream.
  bool download_ranges(std::size_t begin, std::size_t count,
                       const std::vector<std::array<const DeviceArray<Real>*, 3>>& triples,
                       std::vector<std::vector<sim::Point3>>& out, DiagnosticList& diagnostics) const;

  // energy_result_ (a reduction's), through page-locked memory: every sample reads three (largest displacement,
  // kinetic and elastic energy), and a copy into pageable memory waits on its own.
  std::optional<double> download_result(DiagnosticList& diagnostics) const;

  // The sum of `term` over [begin, end); ElementPotential's of element term `element_term`.
  std::optional<double> energy_sum(EnergyTerm term, int begin, int end, DiagnosticList& diagnostics,
                                   int element_term = 0) const;

  const std::vector<sim::SimulationSetup>& scenes_;  // the Simulation's
  const std::vector<sim::StabilityReport>& stability_;
  const GpuOptions options_;
  std::vector<int> vertex_begin_, spring_begin_;
  int n_ = 0;
  cudaStream_t stream_ = nullptr;
  DeviceArray<int> offset_, spring_, neighbour_, first_, second_, vertex_scene_, first_non_finite_;
  DeviceArray<Real> rest_length_, stiffness_, damping_, mass_, scene_h_;
  DeviceArray<Real> rest_x_, rest_y_, rest_z_, force_x_, force_y_, force_z_;
  DeviceArray<double> energy_mass_, energy_rest_length_, energy_stiffness_;
  DeviceArray<double> energy_force_x_, energy_force_y_, energy_force_z_, energy_partial_, energy_result_;
  DeviceArray<unsigned char> fixed_;
  DeviceArray<int> probe_vertices_, probe_entry_scene_, probe_entry_;
  bool probe_vertices_unique_ = true;
  // How the steps launch (plan_launches): the per-step kernel's lanes, the persistent grid or clusters, the checks.
  LaunchPlan plan_;
  DeviceArray<int> neighbour_block_offset_, neighbour_block_;  // BlockNeighbours
  DeviceArray<unsigned> block_steps_done_;
  DeviceArray<ClusterBlock> cluster_blocks_array_;
  // PersistentChecks' results (persistent runs): a slot of plan_.check_slot_stride per check of a launch.
  DeviceArray<unsigned int> check_results_;
  PinnedArray<unsigned int> check_results_host_;
  int checks_slot_ = 0;  // the check whose results are pending
  // Whether check_results_host_'s slot checks_slot_ holds (once the stream is synchronised) the checks at the state
  // now held (advance: or at the check acted on): set by a persistent launch, cleared by anything that moves the
  // state and once the inversion count has been read.
  bool checks_pending_ = false;
  mutable PinnedArray<Real> download_staging_;  // download_ranges', allocated on first use
  mutable PinnedArray<double> result_host_;     // download_result's
  // probe_reading's buffers: the state downloaded, the uploaded stiffness of scene probe_stiffness_scene_ (none: a
  // strain table's, downloaded at each reading).
  mutable std::vector<std::vector<sim::Point3>> probe_state_;
  mutable std::vector<double> probe_stiffness_;
  mutable std::optional<std::size_t> probe_stiffness_scene_;
  DeviceArray<ProbeScene> probe_scenes_;
  DeviceArray<double> probe_start_x_, probe_start_y_, probe_start_z_, probe_base_x_, probe_base_y_, probe_base_z_;
  DeviceArray<unsigned long long> step_base_;
  DeviceArray<double> table_strain_, table_modulus_, stiffness_per_modulus_;
  DeviceArray<double> implicit_rest_, implicit_blocks_, implicit_diagonal_, implicit_jacobi_, implicit_rhs_;
  DeviceArray<double> cg_x_, cg_r_, cg_z_, cg_p_, cg_ap_, cg_partial_;
  // A slot per solve not yet read (kDeferredSolves; the first for a solve the host reads at once).
  DeviceArray<ConjugateGradientScalars> cg_scalars_;
  PinnedArray<ConjugateGradientScalars> cg_scalars_host_;
  int deferred_solves_ = 0;
  std::size_t deferred_first_step_ = 0;
  int cg_previous_iterations_ = 0;  // the last solve's iterations: the first chunk's length (per-iteration launches)
  unsigned long long step_base_host_ = 0;
  sim::ImplicitSolverLog implicit_log_;  // implicit Euler's solves (a batch of one scene)
  DeviceState<Real> state_[2];
  // The state at the last check (checkpoint_step_): slot checkpoint_slot_ of checkpoint_ (checkpoint_slot), which
  // has plan_.persistent_checks slots on the cooperative grid.
  DeviceState<Real> checkpoint_;
  int checkpoint_slot_ = 0;
  DeviceVector3<Real> acceleration_, predicted_, checkpoint_acceleration_;
  DeviceVector3<Real> stage_position_a_, stage_position_b_, stage_velocity_[3], stage_acceleration_[3];
  ForceModelView<Real> model_{};
  ImplicitElements elements_{};
  std::vector<int> element_begin_;
  int element_count_ = 0;
  DeviceArray<int> corners_, element_scene_, corner_offset_, corner_index_, corner_slot_, inverted_first_;
  DeviceArray<unsigned char> corner_rank_;  // the element pass's slots as ranks (corner_ranks); empty: corner_slot_
  // Each element's shape where rest_inverse_ (rest_inverse_d_) holds the shapes' table (rest_shapes); empty: none.
  DeviceArray<unsigned char> rest_shape_, rest_shape_d_;
  DeviceArray<int> nodes_;  // the element kind's nodes per element (the element pass's; corners_: the tetrahedra's)
  // What the inversion counts read (kernels::element_inverted): the element kind's nodes where the batch has element
  // terms, else the tetrahedra's corners (corners_, uploaded only then) as kernels::kTetrahedronKind.
  const int* inversion_nodes_ = nullptr;
  int inversion_kind_ = 0;
  // The springs' records: in the sliced layout (then vertex_order_ and sliced_row_ are set) or in CSR order.
  DeviceArray<kernels::SpringIncidence<Real>> incidence_;
  DeviceArray<int> vertex_order_;
  DeviceArray<kernels::SlicedRow> sliced_row_;
  DeviceArray<double> start_x_, start_y_, start_z_;  // the start positions, for largest_displacement
  DeviceArray<unsigned int> inverted_count_;
  // The element terms' arrays (upload_elements): the geometry in Real and in double, each term's parameters and
  // damping in both and its implicit linearisation.
  struct DeviceTermArrays {
    DeviceArray<Real> parameter[kernels::kMostLawParameters];
    DeviceArray<double> parameter_d[kernels::kMostLawParameters];
    DeviceArray<Real> damping;
    DeviceArray<double> damping_d;
    DeviceArray<Real> prony_weight[kernels::kMostPronyTerms];  // per element where the term's weight varies
    DeviceArray<unsigned char> linearisation;
    DeviceArray<Real> state, checkpoint_state;  // per-point state (view.state) and its checkpoint
    // A kind with a nodal pass: per vertex, the element pass's nodal field (view.nodal_pressure, nodal_dilatation)
    // and the energy's in double (elements_.terms[t]'s, filled by elastic_energy).
    DeviceArray<Real> nodal_pressure, nodal_dilatation;
    DeviceArray<double> nodal_pressure_d, nodal_dilatation_d;
  };
  DeviceArray<Real> rest_inverse_, rest_volume_;
  DeviceArray<double> rest_inverse_d_, rest_volume_d_;
  DeviceTermArrays term_arrays_[kMostElementTerms];
  DeviceArray<kernels::CornerForce<Real>> corner_force_;
  DeviceArray<kernels::CornerForce<double>> nodal_shares_d_;  // the energy's nodal pass's shares (a nodal kind only)
  DeviceArray<double> element_rhs_part_, element_diagonal_part_, element_product_;
  kernels::VertexLoads<Real> loads_{};
  // The tools' contact (set_contact, set_tool_shapes): loads_.contact points at these.
  DeviceArray<kernels::ToolShape<Real>> tools_;
  DeviceArray<Real> contact_stiffness_, contact_damping_;  // the damping allocated only where the scene has it
  DeviceArray<double> contact_blocks_, contact_rhs_;       // implicit Euler's contact part: 6 and 3 per vertex
  DeviceArray<unsigned char> contact_active_;              // implicit Euler's contact set per vertex
  DeviceArray<unsigned int> contact_changes_;
  std::vector<kernels::ToolShape<Real>> tool_shapes_;
  StepSize<Real> step_{};
  std::map<std::pair<std::size_t, int>, std::unique_ptr<GraphExecutable>> graphs_;
  int current_ = 0;
  std::size_t steps_taken_ = 0;
  std::size_t checkpoint_step_ = 0;
  bool checkpoint_in_state_ = false;  // the checkpoint is the state held (persistent runs: save_checkpoint)
  bool have_acceleration_ = false;
  bool checkpoint_has_acceleration_ = false;
  // The last run's check ends, and the check select_check made current (inner: before the launch's last).
  std::vector<std::size_t> run_ends_;
  std::size_t selected_check_ = 0;
  bool selected_inner_ = false;
};

}  // namespace fmpc::gpu
