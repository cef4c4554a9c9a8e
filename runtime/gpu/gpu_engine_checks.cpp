// The run supervisor's checks on the device: the checkpoint, the first non-finite vertex and the inverted elements.
#include "runtime/gpu/cuda_check.h"
#include "runtime/gpu/gpu_engine.h"

namespace fmpc::gpu {

template <typename Real>
bool GpuEngine<Real>::synchronize(DiagnosticList& diagnostics) const {
  FMPC_CUDA_CHECK(cudaStreamSynchronize(stream_), diagnostics, false);
  return true;
}

template <typename Real>
bool GpuEngine<Real>::count_inverted(std::vector<unsigned int>& counts, std::vector<int>& firsts,
                                     DiagnosticList& diagnostics) {
  const std::size_t scenes = scenes_.size();
  if (checks_pending_) {
    // The persistent kernel counted at the state now held.
    if (!synchronize(diagnostics)) return false;
    checks_pending_ = false;
    const unsigned int* results = check_results_host_.data() + checks_slot_ * plan_.check_slot_stride;
    counts.assign(results + 1, results + 1 + scenes);
    firsts.resize(scenes);
    for (std::size_t scene = 0; scene < scenes; ++scene) {
      const int first = static_cast<int>(results[1 + scenes + scene]);
      firsts[scene] = counts[scene] > 0 ? first - element_begin_[scene] : -1;
    }
    return true;
  }
  counts.assign(scenes, 0u);
  firsts.assign(scenes, element_count_);
  FMPC_CUDA_CHECK(cudaMemcpyAsync(inverted_count_.data(), counts.data(), scenes * sizeof(unsigned int),
                                  cudaMemcpyHostToDevice, stream_),
                  diagnostics, false);
  FMPC_CUDA_CHECK(
      cudaMemcpyAsync(inverted_first_.data(), firsts.data(), scenes * sizeof(int), cudaMemcpyHostToDevice, stream_),
      diagnostics, false);
  FMPC_CUDA_CHECK(launch_count_inverted(inversion_nodes_, inversion_kind_, element_count_,
                                        scenes > 1 ? element_scene_.data() : nullptr, state_[current_].view(),
                                        inverted_count_.data(), inverted_first_.data(), stream_),
                  diagnostics, false);
  FMPC_CUDA_CHECK(cudaMemcpyAsync(counts.data(), inverted_count_.data(), scenes * sizeof(unsigned int),
                                  cudaMemcpyDeviceToHost, stream_),
                  diagnostics, false);
  FMPC_CUDA_CHECK(
      cudaMemcpyAsync(firsts.data(), inverted_first_.data(), scenes * sizeof(int), cudaMemcpyDeviceToHost, stream_),
      diagnostics, false);
  if (!synchronize(diagnostics)) return false;
  for (std::size_t scene = 0; scene < scenes; ++scene)
    firsts[scene] = counts[scene] > 0 ? firsts[scene] - element_begin_[scene] : -1;
  return true;
}

template <typename Real>
bool GpuEngine<Real>::save_checkpoint(DiagnosticList& diagnostics) {
  checkpoint_step_ = steps_taken_;
  checkpoint_has_acceleration_ = have_acceleration_;
  implicit_log_.save(steps_taken_);
  // Persistent runs change the state only in their launches, which store the state they start from into the
  // checkpoint (PersistentEulerArguments::checkpoints): until the next one, the state held is the checkpoint. Six
  // copies per check were a fifth of the 20^3 box's time between checks (H100). At a check before the launch's
  // last, the launch stored that check's state in slot check + 1.
  if (persistent_launch()) {
    checkpoint_in_state_ = !selected_inner_;
    if (selected_inner_) checkpoint_slot_ = static_cast<int>(selected_check_) + 1;
    return true;
  }
  if (!copy_state(checkpoint_slot(checkpoint_slot_), state_[current_].view(), diagnostics)) return false;
  for (DeviceTermArrays& arrays : term_arrays_)
    if (arrays.state.size() > 0)
      FMPC_CUDA_CHECK(copy_async(arrays.checkpoint_state, arrays.state, stream_), diagnostics, false);
  if (scheme() == sim::Integrator::VelocityVerlet) {
    FMPC_CUDA_CHECK(copy_async(checkpoint_acceleration_.x, acceleration_.x, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(copy_async(checkpoint_acceleration_.y, acceleration_.y, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(copy_async(checkpoint_acceleration_.z, acceleration_.z, stream_), diagnostics, false);
  }
  return true;
}

template <typename Real>
bool GpuEngine<Real>::restore_checkpoint(DiagnosticList& diagnostics) {
  checks_pending_ = false;
  selected_inner_ = false;
  implicit_log_.restore();
  if (checkpoint_in_state_) {
    steps_taken_ = checkpoint_step_;
    have_acceleration_ = checkpoint_has_acceleration_;
    return true;
  }
  if (!copy_state(state_[current_].mutable_view(), read_only(checkpoint_slot(checkpoint_slot_)), diagnostics))
    return false;
  for (DeviceTermArrays& arrays : term_arrays_)
    if (arrays.state.size() > 0)
      FMPC_CUDA_CHECK(copy_async(arrays.state, arrays.checkpoint_state, stream_), diagnostics, false);
  if (scheme() == sim::Integrator::VelocityVerlet) {
    FMPC_CUDA_CHECK(copy_async(acceleration_.x, checkpoint_acceleration_.x, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(copy_async(acceleration_.y, checkpoint_acceleration_.y, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(copy_async(acceleration_.z, checkpoint_acceleration_.z, stream_), diagnostics, false);
  }
  steps_taken_ = checkpoint_step_;
  have_acceleration_ = checkpoint_has_acceleration_;
  return true;
}

template <typename Real>
MutableStateView<Real> GpuEngine<Real>::checkpoint_slot(int slot) const {
  return offset_state(checkpoint_.mutable_view(), static_cast<long long>(slot) * n_);
}

template <typename Real>
bool GpuEngine<Real>::copy_state(const MutableStateView<Real>& to, const kernels::StateView<Real>& from,
                                 DiagnosticList& diagnostics) {
  FMPC_CUDA_CHECK(launch_copy_state(to, from, n_, stream_), diagnostics, false);
  return true;
}

template <typename Real>
std::optional<int> GpuEngine<Real>::first_non_finite_vertex(DiagnosticList& diagnostics) {
  if (checks_pending_) {
    if (!synchronize(diagnostics)) return std::nullopt;
    return static_cast<int>(check_results_host_.data()[checks_slot_ * plan_.check_slot_stride]);
  }
  int first = n_;
  FMPC_CUDA_CHECK(cudaMemcpyAsync(first_non_finite_.data(), &first, sizeof(int), cudaMemcpyHostToDevice, stream_),
                  diagnostics, std::nullopt);
  FMPC_CUDA_CHECK(launch_find_non_finite(state_[current_].view(), n_, first_non_finite_.data(), stream_), diagnostics,
                  std::nullopt);
  FMPC_CUDA_CHECK(cudaMemcpyAsync(&first, first_non_finite_.data(), sizeof(int), cudaMemcpyDeviceToHost, stream_),
                  diagnostics, std::nullopt);
  if (!synchronize(diagnostics)) return std::nullopt;
  return first;
}

#define FMPC_GPU_ENGINE_CHECKS_MEMBERS(Real)                                                                        \
  template bool GpuEngine<Real>::synchronize(DiagnosticList& diagnostics) const;                                    \
  template bool GpuEngine<Real>::count_inverted(std::vector<unsigned int>& counts, std::vector<int>& firsts,        \
                                                DiagnosticList& diagnostics);                                       \
  template bool GpuEngine<Real>::save_checkpoint(DiagnosticList& diagnostics);                                      \
  template bool GpuEngine<Real>::restore_checkpoint(DiagnosticList& diagnostics);                                   \
  template MutableStateView<Real> GpuEngine<Real>::checkpoint_slot(int slot) const;                                 \
  template bool GpuEngine<Real>::copy_state(const MutableStateView<Real>& to, const kernels::StateView<Real>& from, \
                                            DiagnosticList& diagnostics);                                           \
  template std::optional<int> GpuEngine<Real>::first_non_finite_vertex(DiagnosticList& diagnostics);
FMPC_GPU_ENGINE_CHECKS_MEMBERS(float)
FMPC_GPU_ENGINE_CHECKS_MEMBERS(double)
#undef FMPC_GPU_ENGINE_CHECKS_MEMBERS

}  // namespace fmpc::gpu
