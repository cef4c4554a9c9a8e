// Rigid tools and the material on the device: the contact stiffness and the tools' shapes written into allocations
// made once (loads_ and the captured graphs keep their pointers), and a replaced material copied into the arrays it
// was uploaded to, with the springs' records rebuilt from them.
#include <type_traits>

#include "runtime/gpu/cuda_check.h"
#include "runtime/gpu/gpu_engine.h"

namespace fmpc::gpu {

namespace {

template <typename Real, typename Values>
std::vector<Real> to_real(const Values& values) {
  std::vector<Real> out(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) out[i] = static_cast<Real>(values[i]);
  return out;
}

template <typename Values>
std::vector<double> to_double(const Values& values) {
  return std::vector<double>(values.begin(), values.end());
}

}  // namespace

template <typename Real>
bool GpuEngine<Real>::set_contact(std::size_t, const std::vector<double>& stiffness, const std::vector<double>& damping,
                                  DiagnosticList& diagnostics) {
  if (contact_stiffness_.size() == 0) {
    FMPC_CUDA_CHECK(contact_stiffness_.upload(to_real<Real>(stiffness)), diagnostics, false);
    if (!damping.empty()) FMPC_CUDA_CHECK(contact_damping_.upload(to_real<Real>(damping)), diagnostics, false);
    FMPC_CUDA_CHECK(tools_.allocate(static_cast<std::size_t>(kernels::kMostTools)), diagnostics, false);
    if (scheme() == sim::Integrator::ImplicitEuler) {
      FMPC_CUDA_CHECK(contact_blocks_.allocate(6 * static_cast<std::size_t>(n_)), diagnostics, false);
      FMPC_CUDA_CHECK(contact_rhs_.allocate(3 * static_cast<std::size_t>(n_)), diagnostics, false);
      FMPC_CUDA_CHECK(contact_active_.allocate(static_cast<std::size_t>(n_)), diagnostics, false);
      FMPC_CUDA_CHECK(contact_changes_.allocate(1), diagnostics, false);
    }
    // Allocated on the legacy stream, which the non-blocking stream_ does not wait for.
    FMPC_CUDA_CHECK(cudaDeviceSynchronize(), diagnostics, false);
    loads_.contact.stiffness = contact_stiffness_.data();
    loads_.contact.damping = damping.empty() ? nullptr : contact_damping_.data();
    loads_.contact.tools = tools_.data();
    graphs_.clear();  // captured with the loads before the contact
    return true;
  }
  FMPC_CUDA_CHECK(contact_stiffness_.overwrite(to_real<Real>(stiffness), stream_), diagnostics, false);
  // The damping ratio is the setup's, fixed for the run: present from the start or never.
  if (!damping.empty())
    FMPC_CUDA_CHECK(contact_damping_.overwrite(to_real<Real>(damping), stream_), diagnostics, false);
  return synchronize(diagnostics);
}

template <typename Real>
bool GpuEngine<Real>::set_tool_shapes(std::size_t, const std::vector<kernels::ToolShape<double>>& shapes,
                                      DiagnosticList& diagnostics) {
  tool_shapes_.resize(shapes.size());
  for (std::size_t t = 0; t < shapes.size(); ++t) {
    const kernels::ToolShape<double>& s = shapes[t];
    tool_shapes_[t] = {static_cast<Real>(s.ax),    static_cast<Real>(s.ay), static_cast<Real>(s.az),
                       static_cast<Real>(s.bx),    static_cast<Real>(s.by), static_cast<Real>(s.bz),
                       static_cast<Real>(s.radius)};
  }
  // From pageable memory: the copy is staged before cudaMemcpyAsync returns and runs in the stream's order, after the
  // steps enqueued before it.
  FMPC_CUDA_CHECK(
      cudaMemcpyAsync(tools_.data(), tool_shapes_.data(), tool_shapes_.size() * sizeof(kernels::ToolShape<Real>),
                      cudaMemcpyHostToDevice, stream_),
      diagnostics, false);
  const int count = static_cast<int>(shapes.size());
  if (loads_.contact.tool_count != count) {
    loads_.contact.tool_count = count;
    graphs_.clear();  // captured with the old count
  }
  return true;
}

template <typename Real>
bool GpuEngine<Real>::refresh_material(std::size_t, DiagnosticList& diagnostics) {
  const ConcatenatedScenes c = concatenate(scenes_);
  FMPC_CUDA_CHECK(stiffness_.overwrite(to_real<Real>(c.stiffness), stream_), diagnostics, false);
  FMPC_CUDA_CHECK(energy_stiffness_.overwrite(to_double(c.stiffness), stream_), diagnostics, false);
  if (c.has_damping) FMPC_CUDA_CHECK(damping_.overwrite(to_real<Real>(c.damping), stream_), diagnostics, false);
  for (std::size_t t = 0; t < c.terms.size(); ++t) {
    const ConcatenatedScenes::Term& term = c.terms[t];
    DeviceTermArrays& arrays = term_arrays_[t];
    // The views' uniform values travel as kernel arguments: taken by the next launch (the graphs are dropped below).
    kernels::ElementTermView<Real>& view = model_.terms[t];
    kernels::ElementTermView<double>& view_d = elements_.terms[t];
    for (int p = 0; p < kernels::kMostLawParameters; ++p) {
      if (term.parameter[p].empty()) continue;
      const std::vector<Real> values = to_real<Real>(term.parameter[p]);
      const std::vector<double> values_d = to_double(term.parameter[p]);
      FMPC_CUDA_CHECK(arrays.parameter[p].overwrite(values, stream_), diagnostics, false);
      FMPC_CUDA_CHECK(arrays.parameter_d[p].overwrite(values_d, stream_), diagnostics, false);
      view.parameter[p] = per_element_of(values, arrays.parameter[p].data(), options_.compact_element_views);
      view_d.parameter[p] = per_element_of(values_d, arrays.parameter_d[p].data(), options_.compact_element_views);
    }
    if (!term.stiffness_damping.empty()) {
      const std::vector<Real> values = to_real<Real>(term.stiffness_damping);
      const std::vector<double> values_d = to_double(term.stiffness_damping);
      FMPC_CUDA_CHECK(arrays.damping.overwrite(values, stream_), diagnostics, false);
      FMPC_CUDA_CHECK(arrays.damping_d.overwrite(values_d, stream_), diagnostics, false);
      view.stiffness_damping = per_element_of(values, arrays.damping.data(), options_.compact_element_views);
      view_d.stiffness_damping = per_element_of(values_d, arrays.damping_d.data(), options_.compact_element_views);
    }
  }
  const sim::SimulationSetup& setup = scenes_.front();
  // The Prony constants travel in the views (kernel arguments): recomputed here, taken by the next launch (the graphs
  // captured with the old ones are dropped below).
  for (std::size_t t = 0; t < setup.elements.terms.size(); ++t)
    if (model_.terms[t].prony.count > 0)
      model_.terms[t].prony = sim::prony_constants_in<Real>(setup.elements.terms[t].prony, stability_.front().time_step,
                                                            setup.integrator == sim::Integrator::ImplicitEuler);
  if (setup.strain_stiffness) {
    const sim::StrainStiffnessTable& table = *setup.strain_stiffness;
    FMPC_CUDA_CHECK(table_strain_.overwrite(table.strain, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(table_modulus_.overwrite(table.modulus, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(stiffness_per_modulus_.overwrite(table.stiffness_per_modulus, stream_), diagnostics, false);
  }
  // The springs' records carry the stiffness and damping: rebuilt where the launches read them (no strain table).
  if (incidence_.size() > 0) {
    if (model_.vertex_order != nullptr) {
      FMPC_CUDA_CHECK(launch_sliced_springs(model_.springs, vertex_order_.data(), n_, incidence_.data(), stream_),
                      diagnostics, false);
    } else {
      FMPC_CUDA_CHECK(launch_spring_incidence(model_.springs, c.offset.back(), incidence_.data(), stream_), diagnostics,
                      false);
    }
  }
  graphs_.clear();
  probe_stiffness_scene_.reset();
  return synchronize(diagnostics);
}

template <typename Real>
std::optional<sim::DevicePositions> GpuEngine<Real>::device_positions(std::size_t scene,
                                                                      DiagnosticList& diagnostics) const {
  if (!scene_exists(scene, diagnostics) || !synchronize(diagnostics)) return std::nullopt;
  const DeviceState<Real>& s = state_[current_];
  const auto begin = static_cast<std::size_t>(vertex_begin_[scene]);
  sim::DevicePositions out;
  out.x = s.x.data() + begin;
  out.y = s.y.data() + begin;
  out.z = s.z.data() + begin;
  out.count = static_cast<std::size_t>(vertex_begin_[scene + 1]) - begin;
  out.double_precision = std::is_same_v<Real, double>;
  return out;
}

#define FMPC_GPU_ENGINE_CONTACT_MEMBERS(Real)                                                                        \
  template bool GpuEngine<Real>::set_contact(std::size_t, const std::vector<double>& stiffness,                      \
                                             const std::vector<double>& damping, DiagnosticList& diagnostics);       \
  template bool GpuEngine<Real>::set_tool_shapes(std::size_t, const std::vector<kernels::ToolShape<double>>& shapes, \
                                                 DiagnosticList& diagnostics);                                       \
  template bool GpuEngine<Real>::refresh_material(std::size_t, DiagnosticList& diagnostics);                         \
  template std::optional<sim::DevicePositions> GpuEngine<Real>::device_positions(std::size_t scene,                  \
                                                                                 DiagnosticList& diagnostics) const;
FMPC_GPU_ENGINE_CONTACT_MEMBERS(float)
FMPC_GPU_ENGINE_CONTACT_MEMBERS(double)
#undef FMPC_GPU_ENGINE_CONTACT_MEMBERS

}  // namespace fmpc::gpu
