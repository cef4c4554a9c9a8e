// What the supervisor and the scene runner read back: states, stiffness, probe readings and the energy sums.
#include <string>

#include "runtime/gpu/cuda_check.h"
#include "runtime/gpu/gpu_engine.h"

namespace fmpc::gpu {

template <typename Real>
std::vector<sim::Point3> GpuEngine<Real>::positions(std::size_t scene, DiagnosticList& diagnostics) const {
  const DeviceState<Real>& s = state_[current_];
  return download(scene, s.x, s.y, s.z, diagnostics);
}

template <typename Real>
std::vector<sim::Point3> GpuEngine<Real>::velocities(std::size_t scene, DiagnosticList& diagnostics) const {
  const DeviceState<Real>& s = state_[current_];
  return download(scene, s.vx, s.vy, s.vz, diagnostics);
}

template <typename Real>
bool GpuEngine<Real>::scene_states(std::vector<std::vector<sim::Point3>>& positions,
                                   std::vector<std::vector<sim::Point3>>* velocities,
                                   DiagnosticList& diagnostics) const {
  const DeviceState<Real>& s = state_[current_];
  const auto split = [&](const std::vector<sim::Point3>& all, std::vector<std::vector<sim::Point3>>& out) {
    out.assign(scenes_.size(), {});
    for (std::size_t scene = 0; scene < scenes_.size(); ++scene)
      out[scene].assign(all.begin() + vertex_begin_[scene], all.begin() + vertex_begin_[scene + 1]);
  };
  std::vector<std::array<const DeviceArray<Real>*, 3>> triples{{&s.x, &s.y, &s.z}};
  if (velocities != nullptr) triples.push_back({&s.vx, &s.vy, &s.vz});
  std::vector<std::vector<sim::Point3>> all;
  if (!download_ranges(0, static_cast<std::size_t>(n_), triples, all, diagnostics)) return false;
  split(all[0], positions);
  if (velocities != nullptr) split(all[1], *velocities);
  return true;
}

template <typename Real>
std::vector<double> GpuEngine<Real>::current_stiffness(std::size_t scene, DiagnosticList& diagnostics) const {
  if (!scene_exists(scene, diagnostics)) return {};
  const auto begin = static_cast<std::size_t>(spring_begin_[scene]);
  const auto count = static_cast<std::size_t>(spring_begin_[scene + 1]) - begin;
  std::vector<Real> host(count);
  if (count > 0) {
    FMPC_CUDA_CHECK(
        cudaMemcpyAsync(host.data(), stiffness_.data() + begin, count * sizeof(Real), cudaMemcpyDeviceToHost, stream_),
        diagnostics, {});
    if (!synchronize(diagnostics)) return {};
  }
  return std::vector<double>(host.begin(), host.end());
}

template <typename Real>
sim::ProbeReading GpuEngine<Real>::probe_reading(std::size_t scene, DiagnosticList& diagnostics) const {
  if (scene >= scenes_.size() || !scenes_[scene].probe) return {};
  const sim::SimulationSetup& setup = scenes_[scene];
  const double time = static_cast<double>(steps_taken_) * stability_[scene].time_step;
  const DeviceState<Real>& s = state_[current_];
  const auto begin = static_cast<std::size_t>(vertex_begin_[scene]);
  if (!download_ranges(begin, static_cast<std::size_t>(vertex_begin_[scene + 1]) - begin,
                       {{&s.x, &s.y, &s.z}, {&s.vx, &s.vy, &s.vz}}, probe_state_, diagnostics))
    return {};
  if (setup.strain_stiffness) {
    probe_stiffness_ = current_stiffness(scene, diagnostics);
    probe_stiffness_scene_.reset();
  } else if (probe_stiffness_scene_ != scene) {
    probe_stiffness_.resize(setup.springs.stiffness.size());
    for (std::size_t k = 0; k < probe_stiffness_.size(); ++k)
      probe_stiffness_[k] = static_cast<double>(static_cast<Real>(setup.springs.stiffness[k]));
    probe_stiffness_scene_ = scene;
  }
  // A stateful term's history (a viscoelastic scene runs alone: its state is this scene's).
  sim::ElementTermStates states;
  for (std::size_t t = 0; t < setup.elements.terms.size(); ++t) {
    const DeviceArray<Real>& state = term_arrays_[t].state;
    std::vector<Real> values(state.size());
    if (!values.empty())
      FMPC_CUDA_CHECK(cudaMemcpyAsync(values.data(), state.data(), values.size() * sizeof(Real),
                                      cudaMemcpyDeviceToHost, stream_),
                      diagnostics, {});
    if (!values.empty() && !synchronize(diagnostics)) return {};
    states.emplace_back(values.begin(), values.end());
  }
  return sim::read_probe(setup, time, probe_state_[0], probe_state_[1], probe_stiffness_, &states);
}

template <typename Real>
std::optional<double> GpuEngine<Real>::kinetic_energy(std::size_t scene, DiagnosticList& diagnostics) const {
  return energy_sum(EnergyTerm::Kinetic, vertex_begin_.at(scene), vertex_begin_.at(scene + 1), diagnostics);
}

template <typename Real>
std::optional<double> GpuEngine<Real>::largest_displacement(std::size_t scene, DiagnosticList& diagnostics) const {
  const StartPositions start{start_x_.data(), start_y_.data(), start_z_.data()};
  FMPC_CUDA_CHECK(
      launch_largest_displacement(state_[current_].view(), start, vertex_begin_.at(scene), vertex_begin_.at(scene + 1),
                                  energy_partial_.data(), energy_result_.data(), stream_),
      diagnostics, std::nullopt);
  return download_result(diagnostics);
}

template <typename Real>
std::optional<double> GpuEngine<Real>::elastic_energy(std::size_t scene, DiagnosticList& diagnostics) const {
  const auto springs =
      energy_sum(EnergyTerm::SpringPotential, spring_begin_.at(scene), spring_begin_.at(scene + 1), diagnostics);
  if (!springs) return std::nullopt;
  // The terms' energies in list order, as the host's element_elastic_energy adds them.
  double elements = 0.0;
  for (int term = 0; term < elements_.term_count && elements_.count > 0; ++term) {
    const auto energy = energy_sum(EnergyTerm::ElementPotential, element_begin_.at(scene), element_begin_.at(scene + 1),
                                   diagnostics, term);
    if (!energy) return std::nullopt;
    elements += *energy;
  }
  return *springs + elements;
}

template <typename Real>
std::optional<double> GpuEngine<Real>::potential_energy(std::size_t scene, DiagnosticList& diagnostics) const {
  const auto elastic = elastic_energy(scene, diagnostics);
  if (!elastic) return std::nullopt;
  const auto loads =
      energy_sum(EnergyTerm::LoadPotential, vertex_begin_.at(scene), vertex_begin_.at(scene + 1), diagnostics);
  if (!loads) return std::nullopt;
  return *elastic + *loads;
}

template <typename Real>
bool GpuEngine<Real>::scene_exists(std::size_t scene, DiagnosticList& diagnostics) const {
  if (scene < scenes_.size()) return true;
  diagnostics.error(SourceRange{}, "scene " + std::to_string(scene) + " does not exist; the batch has " +
                                       std::to_string(scenes_.size()));
  return false;
}

template <typename Real>
std::vector<sim::Point3> GpuEngine<Real>::download(std::size_t scene, const DeviceArray<Real>& x,
                                                   const DeviceArray<Real>& y, const DeviceArray<Real>& z,
                                                   DiagnosticList& diagnostics) const {
  if (!scene_exists(scene, diagnostics)) return {};
  const auto begin = static_cast<std::size_t>(vertex_begin_[scene]);
  return download_range(begin, static_cast<std::size_t>(vertex_begin_[scene + 1]) - begin, x, y, z, diagnostics);
}

template <typename Real>
std::vector<sim::Point3> GpuEngine<Real>::download_range(std::size_t begin, std::size_t count,
                                                         const DeviceArray<Real>& x, const DeviceArray<Real>& y,
                                                         const DeviceArray<Real>& z,
                                                         DiagnosticList& diagnostics) const {
  std::vector<std::vector<sim::Point3>> out;
  if (!download_ranges(begin, count, {{&x, &y, &z}}, out, diagnostics)) return {};
  return std::move(out.front());
}

template <typename Real>
bool GpuEngine<Real>::download_ranges(std::size_t begin, std::size_t count,
                                      const std::vector<std::array<const DeviceArray<Real>*, 3>>& triples,
                                      std::vector<std::vector<sim::Point3>>& out, DiagnosticList& diagnostics) const {
  out.resize(triples.size());
  for (std::vector<sim::Point3>& points : out) points.resize(count);
  if (count == 0 || triples.empty()) return true;
  if (download_staging_.size() == 0)
    FMPC_CUDA_CHECK(download_staging_.allocate(kDownloadStagingEntries), diagnostics, false);
  const std::size_t arrays = 3 * triples.size();
  const std::size_t piece_most = download_staging_.size() / arrays;
  for (std::size_t first = 0; first < count; first += piece_most) {
    const std::size_t piece = std::min(piece_most, count - first);
    Real* const staged = download_staging_.data();
    for (std::size_t array = 0; array < arrays; ++array)
      FMPC_CUDA_CHECK(cudaMemcpyAsync(staged + array * piece, triples[array / 3][array % 3]->data() + begin + first,
                                      piece * sizeof(Real), cudaMemcpyDeviceToHost, stream_),
                      diagnostics, false);
    if (!synchronize(diagnostics)) return false;
    for (std::size_t t = 0; t < triples.size(); ++t) {
      const Real* const x = staged + 3 * t * piece;
      for (std::size_t i = 0; i < piece; ++i)
        out[t][first + i] = {static_cast<double>(x[i]), static_cast<double>(x[piece + i]),
                             static_cast<double>(x[2 * piece + i])};
    }
  }
  return true;
}

template <typename Real>
std::optional<double> GpuEngine<Real>::download_result(DiagnosticList& diagnostics) const {
  if (result_host_.size() == 0) FMPC_CUDA_CHECK(result_host_.allocate(1), diagnostics, std::nullopt);
  FMPC_CUDA_CHECK(
      cudaMemcpyAsync(result_host_.data(), energy_result_.data(), sizeof(double), cudaMemcpyDeviceToHost, stream_),
      diagnostics, std::nullopt);
  if (!synchronize(diagnostics)) return std::nullopt;
  return *result_host_.data();
}

template <typename Real>
std::optional<double> GpuEngine<Real>::energy_sum(EnergyTerm term, int begin, int end, DiagnosticList& diagnostics,
                                                  int element_term) const {
  const sim::SimulationSetup& common = scenes_.front();
  EnergyArguments<Real> a{};
  a.state = state_[current_].view();
  a.mass = energy_mass_.data();
  a.spring_first = first_.data();
  a.spring_second = second_.data();
  a.rest_length = energy_rest_length_.data();
  a.stiffness = energy_stiffness_.data();
  a.law = {common.law, common.basafa_k2_over_k1, common.basafa_xc};
  a.gravity_x = common.gravity[0];
  a.gravity_y = common.gravity[1];
  a.gravity_z = common.gravity[2];
  a.force_x = energy_force_x_.data();
  a.force_y = energy_force_y_.data();
  a.force_z = energy_force_z_.data();
  if (term == EnergyTerm::ElementPotential) {
    a.element_term = elements_.terms[element_term];
    // A kind with a nodal pass: the term's nodal field in double at the state held (the host's nodal_field).
    if (a.element_term.nodal_pressure != nullptr) {
      const DeviceTermArrays& arrays = term_arrays_[element_term];
      const NodalPassArguments<double> nodal{a.element_term,
                                             nodal_shares_d_.data(),
                                             corner_offset_.data(),
                                             corner_index_.data(),
                                             arrays.nodal_pressure_d.data(),
                                             arrays.nodal_dilatation_d.data(),
                                             n_};
      FMPC_CUDA_CHECK(launch_nodal_pass(nodal, a.state, stream_), diagnostics, std::nullopt);
    }
  }
  if (common.strain_stiffness) {
    a.table = {table_strain_.data(), table_modulus_.data(), static_cast<int>(table_strain_.size())};
    a.stiffness_per_modulus = stiffness_per_modulus_.data();
  }
  FMPC_CUDA_CHECK(launch_energy_sum(a, term, begin, end, energy_partial_.data(), energy_result_.data(), stream_),
                  diagnostics, std::nullopt);
  return download_result(diagnostics);
}

#define FMPC_GPU_ENGINE_READBACK_MEMBERS(Real)                                                                         \
  template std::vector<sim::Point3> GpuEngine<Real>::positions(std::size_t scene, DiagnosticList& diagnostics) const;  \
  template std::vector<sim::Point3> GpuEngine<Real>::velocities(std::size_t scene, DiagnosticList& diagnostics) const; \
  template bool GpuEngine<Real>::scene_states(std::vector<std::vector<sim::Point3>>& positions,                        \
                                              std::vector<std::vector<sim::Point3>>* velocities,                       \
                                              DiagnosticList& diagnostics) const;                                      \
  template std::vector<double> GpuEngine<Real>::current_stiffness(std::size_t scene, DiagnosticList& diagnostics)      \
      const;                                                                                                           \
  template sim::ProbeReading GpuEngine<Real>::probe_reading(std::size_t scene, DiagnosticList& diagnostics) const;     \
  template std::optional<double> GpuEngine<Real>::kinetic_energy(std::size_t scene, DiagnosticList& diagnostics)       \
      const;                                                                                                           \
  template std::optional<double> GpuEngine<Real>::largest_displacement(std::size_t scene, DiagnosticList& diagnostics) \
      const;                                                                                                           \
  template std::optional<double> GpuEngine<Real>::elastic_energy(std::size_t scene, DiagnosticList& diagnostics)       \
      const;                                                                                                           \
  template std::optional<double> GpuEngine<Real>::potential_energy(std::size_t scene, DiagnosticList& diagnostics)     \
      const;                                                                                                           \
  template bool GpuEngine<Real>::scene_exists(std::size_t scene, DiagnosticList& diagnostics) const;                   \
  template std::vector<sim::Point3> GpuEngine<Real>::download(std::size_t scene, const DeviceArray<Real>& x,           \
                                                              const DeviceArray<Real>& y, const DeviceArray<Real>& z,  \
                                                              DiagnosticList& diagnostics) const;                      \
  template std::vector<sim::Point3> GpuEngine<Real>::download_range(                                                   \
      std::size_t begin, std::size_t count, const DeviceArray<Real>& x, const DeviceArray<Real>& y,                    \
      const DeviceArray<Real>& z, DiagnosticList& diagnostics) const;                                                  \
  template bool GpuEngine<Real>::download_ranges(                                                                      \
      std::size_t begin, std::size_t count, const std::vector<std::array<const DeviceArray<Real>*, 3>>& triples,       \
      std::vector<std::vector<sim::Point3>>& out, DiagnosticList& diagnostics) const;                                  \
  template std::optional<double> GpuEngine<Real>::download_result(DiagnosticList& diagnostics) const;                  \
  template std::optional<double> GpuEngine<Real>::energy_sum(EnergyTerm term, int begin, int end,                      \
                                                             DiagnosticList& diagnostics, int element_term) const;
FMPC_GPU_ENGINE_READBACK_MEMBERS(float)
FMPC_GPU_ENGINE_READBACK_MEMBERS(double)
#undef FMPC_GPU_ENGINE_READBACK_MEMBERS

}  // namespace fmpc::gpu
