// How the steps run: the schedule of one step (the probe before it, the strain table's lookup, the integrator
// family's stepper, the probe after it) enqueued directly or replayed from CUDA graphs, or chunks of forward and
// semi-implicit Euler as persistent launches with their checks.
#include <algorithm>

#include "runtime/gpu/cuda_check.h"
#include "runtime/gpu/gpu_engine.h"

namespace fmpc::gpu {

template <typename Real>
bool GpuEngine<Real>::run(const std::vector<std::size_t>& ends, DiagnosticList& diagnostics) {
  run_ends_ = ends;
  selected_inner_ = false;
  const bool ran = persistent_launch() ? run_persistent(ends, diagnostics)
                                       : run_steps(ends.front() - steps_taken_, options_.use_graphs, diagnostics);
  if (!ran) {
    deferred_solves_ = 0;
    return false;
  }
  return record_deferred_solves(diagnostics);
}

template <typename Real>
void GpuEngine<Real>::select_check(std::size_t check) {
  if (!persistent_launch()) return;
  steps_taken_ = run_ends_[check];
  checks_slot_ = static_cast<int>(check);
  checks_pending_ = true;
  selected_check_ = check;
  selected_inner_ = check + 1 < run_ends_.size();
}

template <typename Real>
bool GpuEngine<Real>::enqueue_steps(std::size_t count, int& parity, DiagnosticList& diagnostics) {
  // Forward and semi-implicit Euler apply the probe entries from the vertices' own threads (FusedStepArguments::
  // probe_entry) after each step and before the next: one probe launch before the first step instead of two per step.
  const bool fused_probes = fused_scheme() && probe_scenes_.size() > 0 && probe_vertices_unique_;
  for (std::size_t i = 0; i < count; ++i) {
    const int offset = static_cast<int>(i);
    if ((!fused_probes || i == 0) && !enqueue_probe(offset, true, state_[parity], diagnostics)) return false;
    if (!enqueue_strain_lookup(state_[parity], diagnostics)) return false;
    bool stepped = false;
    switch (scheme()) {
      case sim::Integrator::ForwardEuler:
      case sim::Integrator::SemiImplicitEuler:
        stepped = enqueue_euler_step(offset, i + 1 < count, fused_probes, parity, diagnostics);
        break;
      case sim::Integrator::VelocityVerlet:
        stepped = enqueue_verlet_step(diagnostics);
        break;
      case sim::Integrator::RungeKutta4:
        stepped = enqueue_runge_kutta4_step(diagnostics);
        break;
      case sim::Integrator::ImplicitEuler:
        stepped = implicit_solve(diagnostics);
        break;
    }
    if (!stepped) return false;
    if (!fused_probes && !enqueue_probe(offset, false, state_[parity], diagnostics)) return false;
    if (!enqueue_point_state_update(state_[parity], false, diagnostics)) return false;
  }
  return true;
}

template <typename Real>
bool GpuEngine<Real>::enqueue_point_state_update(const DeviceState<Real>& state, bool jump,
                                                 DiagnosticList& diagnostics) {
  if (!sim::has_point_state(scenes_.front().elements)) return true;
  ForceModelView<Real> model = model_;
  if (jump)
    for (int t = 0; t < model.term_count; ++t)
      if (model.terms[t].prony.count > 0)
        model.terms[t].prony = sim::prony_constants_in<Real>(scenes_.front().elements.terms[t].prony, 0.0, false);
  FMPC_CUDA_CHECK(launch_point_state_update(model, state.view(), stream_), diagnostics, false);
  return true;
}

template <typename Real>
bool GpuEngine<Real>::enqueue_probe(int offset, bool before_step, const DeviceState<Real>& state,
                                    DiagnosticList& diagnostics) {
  if (probe_scenes_.size() == 0) return true;
  FMPC_CUDA_CHECK(launch_apply_probe(probe_arguments(state), offset, before_step, stream_), diagnostics, false);
  return true;
}

template <typename Real>
ProbeArguments<Real> GpuEngine<Real>::probe_arguments(const DeviceState<Real>& state) const {
  ProbeArguments<Real> a{};
  a.vertices = probe_vertices_.data();
  a.entry_scene = probe_entry_scene_.data();
  a.count = static_cast<int>(probe_vertices_.size());
  a.start_x = probe_start_x_.data();
  a.start_y = probe_start_y_.data();
  a.start_z = probe_start_z_.data();
  a.base_force_x = probe_base_x_.data();
  a.base_force_y = probe_base_y_.data();
  a.base_force_z = probe_base_z_.data();
  a.scenes = probe_scenes_.data();
  a.step_base = step_base_.data();
  a.state = state.mutable_view();
  a.force = {force_x_.data(), force_y_.data(), force_z_.data()};
  return a;
}

template <typename Real>
bool GpuEngine<Real>::enqueue_strain_lookup(const DeviceState<Real>& state, DiagnosticList& diagnostics) {
  if (!scenes_.front().strain_stiffness) return true;
  StrainStiffnessArguments<Real> a{};
  a.state = state.view();
  a.first = first_.data();
  a.second = second_.data();
  a.rest_length = energy_rest_length_.data();
  a.stiffness_per_modulus = stiffness_per_modulus_.data();
  a.table = {table_strain_.data(), table_modulus_.data(), static_cast<int>(table_strain_.size())};
  a.stiffness = stiffness_.data();
  a.spring_count = spring_begin_.back();
  FMPC_CUDA_CHECK(launch_strain_stiffness(a, stream_), diagnostics, false);
  return true;
}

template <typename Real>
bool GpuEngine<Real>::set_step_base(DiagnosticList& diagnostics) {
  if (probe_scenes_.size() == 0) return true;
  step_base_host_ = steps_taken_;
  FMPC_CUDA_CHECK(
      cudaMemcpyAsync(step_base_.data(), &step_base_host_, sizeof step_base_host_, cudaMemcpyHostToDevice, stream_),
      diagnostics, false);
  return true;
}

template <typename Real>
bool GpuEngine<Real>::run_steps(std::size_t count, bool allow_graph, DiagnosticList& diagnostics) {
  checks_pending_ = false;
  if (count == 0 || n_ == 0) {
    steps_taken_ += count;
    return true;
  }
  if (persistent_launch()) return run_persistent({steps_taken_ + count}, diagnostics);
  // Velocity Verlet's first step computes a(x0, v0) and implicit Euler reads its CG's scalars once per step (or per
  // chunk of iterations): those steps are enqueued directly, never captured.
  const bool direct = !allow_graph || count < 2 || scheme() == sim::Integrator::ImplicitEuler;
  if (direct || (scheme() == sim::Integrator::VelocityVerlet && !have_acceleration_)) {
    const std::size_t piece = direct ? count : 1;
    for (std::size_t done = 0; done < piece; ++done) {
      if (!set_step_base(diagnostics) || !enqueue_steps(1, current_, diagnostics)) return false;
      ++steps_taken_;
    }
    count -= piece;
  }
  for (std::size_t done = 0; done < count;) {
    const std::size_t piece = std::min(count - done, kMaxStepsPerGraph);
    if (!launch_graph(piece, diagnostics)) return false;
    done += piece;
  }
  return true;
}

template <typename Real>
bool GpuEngine<Real>::run_persistent(const std::vector<std::size_t>& ends, DiagnosticList& diagnostics) {
  while (ends.back() - steps_taken_ > kMostPersistentLaunchSteps) {
    if (!launch_persistent(kMostPersistentLaunchSteps, {}, diagnostics)) return false;
  }
  std::vector<std::size_t> counts(ends.size());
  for (std::size_t check = 0; check < ends.size(); ++check) counts[check] = ends[check] - steps_taken_;
  if (!launch_persistent(counts.back(), counts, diagnostics)) return false;
  FMPC_CUDA_CHECK(
      cudaMemcpyAsync(check_results_host_.data(), check_results_.data(),
                      ends.size() * plan_.check_slot_stride * sizeof(unsigned int), cudaMemcpyDeviceToHost, stream_),
      diagnostics, false);
  checks_slot_ = static_cast<int>(ends.size()) - 1;
  checks_pending_ = true;
  return true;
}

template <typename Real>
bool GpuEngine<Real>::launch_persistent(std::size_t count, const std::vector<std::size_t>& checks,
                                        DiagnosticList& diagnostics) {
  PersistentEulerArguments<Real> a{};
  a.step = fused_arguments();
  a.state[0] = state_[0].mutable_view();
  a.state[1] = state_[1].mutable_view();
  a.first_parity = current_;
  a.steps = static_cast<int>(count);
  a.step_base = steps_taken_;
  if (probe_scenes_.size() > 0) {
    a.step.probe = probe_arguments(state_[current_]);
    a.step.probe_entry = probe_entry_.data();
  }
  a.blocks = plan_.grid_blocks;
  a.rows = plan_.grid_rows;
  if (!checks.empty()) a.checks = persistent_checks();
  a.check_count = std::max(1, static_cast<int>(checks.size()));
  a.first_check = checks.empty() ? static_cast<int>(count) : static_cast<int>(checks.front());
  a.check_every = checks.size() > 2 ? static_cast<int>(checks[1] - checks[0]) : 0;
  a.checkpoints = checkpoint_.mutable_view();
  a.checkpoint_stride = static_cast<long long>(n_);
  a.store_start = checkpoint_in_state_;
  a.block_records = plan_.grid_block_records;
  a.most_neighbour_blocks = plan_.grid_most_waited;
  a.neighbours = {neighbour_block_offset_.data(), neighbour_block_.data(), block_steps_done_.data()};
  if (cluster_launch()) {
    const ClusterEulerArguments<Real> cluster{a,
                                              cluster_blocks_array_.data(),
                                              static_cast<int>(plan_.cluster_blocks.size()),
                                              plan_.cluster_size,
                                              plan_.cluster_rows,
                                              plan_.cluster_window_capacity,
                                              plan_.cluster_shared_bytes};
    FMPC_CUDA_CHECK(launch_cluster_euler(cluster, stream_), diagnostics, false);
  } else {
    FMPC_CUDA_CHECK(launch_persistent_euler(a, stream_), diagnostics, false);
  }
  if (checkpoint_in_state_) checkpoint_slot_ = 0;
  checkpoint_in_state_ = false;
  if (count % 2 == 1) current_ = 1 - current_;
  steps_taken_ += count;
  return true;
}

template <typename Real>
bool GpuEngine<Real>::launch_graph(std::size_t count, DiagnosticList& diagnostics) {
  const std::pair<std::size_t, int> key{count, current_};
  auto found = graphs_.find(key);
  if (found == graphs_.end()) {
    // A few chunk lengths recur (the check interval and a remainder); an unbounded variety is not kept.
    if (graphs_.size() >= 8) graphs_.clear();
    cudaGraphExec_t executable = nullptr;
    if (!capture(count, executable, diagnostics)) return false;
    found = graphs_.emplace(key, std::make_unique<GraphExecutable>(executable)).first;
  }
  if (!set_step_base(diagnostics)) return false;
  FMPC_CUDA_CHECK(cudaGraphLaunch(found->second->get(), stream_), diagnostics, false);
  if (fused_scheme() && count % 2 == 1) current_ = 1 - current_;
  steps_taken_ += count;
  return true;
}

template <typename Real>
bool GpuEngine<Real>::capture(std::size_t count, cudaGraphExec_t& executable, DiagnosticList& diagnostics) {
  FMPC_CUDA_CHECK(cudaStreamBeginCapture(stream_, cudaStreamCaptureModeThreadLocal), diagnostics, false);
  int parity = current_;
  const bool enqueued = enqueue_steps(count, parity, diagnostics);
  cudaGraph_t graph = nullptr;
  // Capture must be ended even after a failed launch, or the stream stays unusable.
  const cudaError_t ended = cudaStreamEndCapture(stream_, &graph);
  if (!enqueued) {
    if (graph != nullptr) cudaGraphDestroy(graph);
    return false;
  }
  FMPC_CUDA_CHECK(ended, diagnostics, false);
  const cudaError_t instantiated = cudaGraphInstantiate(&executable, graph, 0);
  cudaGraphDestroy(graph);
  FMPC_CUDA_CHECK(instantiated, diagnostics, false);
  return true;
}

#define FMPC_GPU_ENGINE_STEPS_MEMBERS(Real)                                                                          \
  template bool GpuEngine<Real>::run(const std::vector<std::size_t>& ends, DiagnosticList& diagnostics);             \
  template void GpuEngine<Real>::select_check(std::size_t check);                                                    \
  template bool GpuEngine<Real>::enqueue_steps(std::size_t count, int& parity, DiagnosticList& diagnostics);         \
  template bool GpuEngine<Real>::enqueue_probe(int offset, bool before_step, const DeviceState<Real>& state,         \
                                               DiagnosticList& diagnostics);                                         \
  template ProbeArguments<Real> GpuEngine<Real>::probe_arguments(const DeviceState<Real>& state) const;              \
  template bool GpuEngine<Real>::enqueue_strain_lookup(const DeviceState<Real>& state, DiagnosticList& diagnostics); \
  template bool GpuEngine<Real>::enqueue_point_state_update(const DeviceState<Real>& state, bool jump,               \
                                                            DiagnosticList& diagnostics);                            \
  template bool GpuEngine<Real>::set_step_base(DiagnosticList& diagnostics);                                         \
  template bool GpuEngine<Real>::run_steps(std::size_t count, bool allow_graph, DiagnosticList& diagnostics);        \
  template bool GpuEngine<Real>::run_persistent(const std::vector<std::size_t>& ends, DiagnosticList& diagnostics);  \
  template bool GpuEngine<Real>::launch_persistent(std::size_t count, const std::vector<std::size_t>& checks,        \
                                                   DiagnosticList& diagnostics);                                     \
  template bool GpuEngine<Real>::launch_graph(std::size_t count, DiagnosticList& diagnostics);                       \
  template bool GpuEngine<Real>::capture(std::size_t count, cudaGraphExec_t& executable, DiagnosticList& diagnostics);
FMPC_GPU_ENGINE_STEPS_MEMBERS(float)
FMPC_GPU_ENGINE_STEPS_MEMBERS(double)
#undef FMPC_GPU_ENGINE_STEPS_MEMBERS

}  // namespace fmpc::gpu
