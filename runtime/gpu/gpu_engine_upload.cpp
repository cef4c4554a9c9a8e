// The batch on the device: the concatenated arrays converted to Real (and kept in double for the energies and
// implicit Euler), the element terms, the probes, the single-scene features, the launch plan and what it needs.
#include <optional>
#include <type_traits>
#include <utility>

#include "runtime/fem/element_law_registry.h"
#include "runtime/gpu/cuda_check.h"
#include "runtime/gpu/gpu_engine.h"
#include "runtime/integrate/worker_pool.h"
#include "runtime/springs/sliced_springs.h"

namespace fmpc::gpu {

template <typename Real>
bool GpuEngine<Real>::upload(DiagnosticList& diagnostics) {
  const ConcatenatedScenes c = concatenate(scenes_);
  vertex_begin_ = c.vertex_begin;
  spring_begin_ = c.spring_begin;
  n_ = vertex_begin_.back();
  const sim::SimulationSetup& common = scenes_.front();
  FMPC_CUDA_CHECK(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking), diagnostics, false);
  FMPC_CUDA_CHECK(offset_.upload(c.offset), diagnostics, false);
  FMPC_CUDA_CHECK(spring_.upload(c.spring), diagnostics, false);
  FMPC_CUDA_CHECK(neighbour_.upload(c.neighbour), diagnostics, false);
  FMPC_CUDA_CHECK(first_.upload(c.first), diagnostics, false);
  FMPC_CUDA_CHECK(second_.upload(c.second), diagnostics, false);
  FMPC_CUDA_CHECK(rest_length_.upload(convert<Real>(c.rest_length, *c.pool)), diagnostics, false);
  FMPC_CUDA_CHECK(stiffness_.upload(convert<Real>(c.stiffness, *c.pool)), diagnostics, false);
  if (c.has_damping) FMPC_CUDA_CHECK(damping_.upload(convert<Real>(c.damping, *c.pool)), diagnostics, false);
  FMPC_CUDA_CHECK(mass_.upload(convert<Real>(c.mass, *c.pool)), diagnostics, false);
  FMPC_CUDA_CHECK(energy_mass_.upload(c.mass), diagnostics, false);
  FMPC_CUDA_CHECK(energy_rest_length_.upload(c.rest_length), diagnostics, false);
  FMPC_CUDA_CHECK(energy_stiffness_.upload(c.stiffness), diagnostics, false);
  FMPC_CUDA_CHECK(fixed_.upload(c.fixed), diagnostics, false);
  DeviceArray<Real>* rest[3] = {&rest_x_, &rest_y_, &rest_z_};
  DeviceArray<Real>* force[3] = {&force_x_, &force_y_, &force_z_};
  DeviceArray<double>* energy_force[3] = {&energy_force_x_, &energy_force_y_, &energy_force_z_};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    FMPC_CUDA_CHECK(rest[axis]->upload(convert<Real>(c.rest[axis], *c.pool)), diagnostics, false);
    if (c.has_forces) {
      FMPC_CUDA_CHECK(force[axis]->upload(convert<Real>(c.force[axis], *c.pool)), diagnostics, false);
      FMPC_CUDA_CHECK(energy_force[axis]->upload(c.force[axis]), diagnostics, false);
    }
  }
  std::vector<double> scene_h;
  for (const auto& report : stability_) scene_h.push_back(report.time_step);
  if (scenes_.size() > 1) {
    FMPC_CUDA_CHECK(vertex_scene_.upload(c.vertex_scene), diagnostics, false);
    FMPC_CUDA_CHECK(scene_h_.upload(convert<Real>(scene_h, *c.pool)), diagnostics, false);
  }
  const auto count = static_cast<std::size_t>(n_);
  const HostArray<double>* start[6] = {&c.position[0], &c.position[1], &c.position[2],
                                       &c.velocity[0], &c.velocity[1], &c.velocity[2]};
  const std::vector<DeviceArray<Real>*> first_state = state_[0].arrays();
  for (std::size_t i = 0; i < 6; ++i)
    FMPC_CUDA_CHECK(first_state[i]->upload(convert<Real>(*start[i], *c.pool)), diagnostics, false);
  DeviceArray<double>* start_positions[3] = {&start_x_, &start_y_, &start_z_};
  for (std::size_t axis = 0; axis < 3; ++axis)
    FMPC_CUDA_CHECK(start_positions[axis]->upload(c.position[axis]), diagnostics, false);
  const sim::Integrator scheme = common.integrator;
  if (fused_scheme()) {
    for (DeviceArray<Real>* array : state_[1].arrays()) FMPC_CUDA_CHECK(array->allocate(count), diagnostics, false);
  }
  if (scheme == sim::Integrator::VelocityVerlet) {
    FMPC_CUDA_CHECK(acceleration_.allocate(count), diagnostics, false);
    FMPC_CUDA_CHECK(predicted_.allocate(count), diagnostics, false);
    FMPC_CUDA_CHECK(checkpoint_acceleration_.allocate(count), diagnostics, false);
  }
  if (scheme == sim::Integrator::RungeKutta4) {
    for (auto* buffer : {&stage_position_a_, &stage_position_b_}) {
      FMPC_CUDA_CHECK(buffer->allocate(count), diagnostics, false);
    }
    for (auto& buffer : stage_velocity_) FMPC_CUDA_CHECK(buffer.allocate(count), diagnostics, false);
    for (auto& buffer : stage_acceleration_) FMPC_CUDA_CHECK(buffer.allocate(count), diagnostics, false);
  }
  for (DeviceArray<Real>* array : checkpoint_.arrays()) FMPC_CUDA_CHECK(array->allocate(count), diagnostics, false);
  FMPC_CUDA_CHECK(first_non_finite_.allocate(1), diagnostics, false);
  FMPC_CUDA_CHECK(energy_partial_.allocate(kEnergyBlocks), diagnostics, false);
  FMPC_CUDA_CHECK(energy_result_.allocate(1), diagnostics, false);
  element_begin_ = c.element_begin;
  element_count_ = element_begin_.back();
  if (element_count_ > 0) {
    // The tetrahedra's corners only where no element kind's nodes (nodes_, upload_elements) hold them.
    if (!c.has_elements) FMPC_CUDA_CHECK(corners_.upload(c.corners), diagnostics, false);
    if (scenes_.size() > 1) FMPC_CUDA_CHECK(element_scene_.upload(c.element_scene), diagnostics, false);
    FMPC_CUDA_CHECK(inverted_count_.allocate(scenes_.size()), diagnostics, false);
    FMPC_CUDA_CHECK(inverted_first_.allocate(scenes_.size()), diagnostics, false);
  }
  if (c.has_elements && !upload_elements(c, diagnostics)) return false;
  inversion_kind_ = c.has_elements ? c.element_kind : kernels::kTetrahedronKind;
  inversion_nodes_ = c.has_elements ? nodes_.data() : corners_.data();

  if (!upload_probes(diagnostics) || !upload_single_scene_features(diagnostics)) return false;

  model_.kind = gather_kind(common);
  model_.element_blocks =
      options_.element_blocks_per_sm == 2 || options_.element_blocks_per_sm == 3 ? options_.element_blocks_per_sm : 0;
  model_.springs = {offset_.data(),
                    spring_.data(),
                    neighbour_.data(),
                    rest_length_.data(),
                    stiffness_.data(),
                    c.has_damping ? damping_.data() : nullptr,
                    {common.law, static_cast<Real>(common.basafa_k2_over_k1), static_cast<Real>(common.basafa_xc)},
                    nullptr,
                    {}};  // the records: upload_spring_records
  loads_ = {mass_.data(),
            fixed_.data(),
            rest_x_.data(),
            rest_y_.data(),
            rest_z_.data(),
            force_x_.data(),
            force_y_.data(),
            force_z_.data(),
            static_cast<Real>(common.gravity[0]),
            static_cast<Real>(common.gravity[1]),
            static_cast<Real>(common.gravity[2]),
            static_cast<Real>(common.nodal_damping_gamma0),
            static_cast<Real>(common.nodal_damping_gamma1),
            static_cast<Real>(common.mass_damping),
            {nullptr, 0, nullptr, nullptr}};  // the tools' contact: set_contact
  step_ = {vertex_scene_.data(), scene_h_.data(), static_cast<Real>(scene_h.front())};
  if (!plan_launches(c, diagnostics) || !upload_spring_records(c, diagnostics)) return false;
  // DeviceArray's cudaMemset and cudaMemcpy from pageable memory run on the legacy stream, which the non-blocking
  // stream_ does not wait for (a pageable copy may return before its transfer lands): every kernel the upload
  // enqueues on stream_ comes after a device synchronisation, or a memset landing late zeroes what it wrote.
  FMPC_CUDA_CHECK(cudaDeviceSynchronize(), diagnostics, false);
  if (!enqueue_point_state_update(state_[current_], true, diagnostics)) return false;
  return synchronize(diagnostics);
}

template <typename Real>
bool GpuEngine<Real>::upload_spring_records(const ConcatenatedScenes& c, DiagnosticList& diagnostics) {
  const int entries = c.offset.back();
  if (scenes_.front().strain_stiffness || entries == 0) return true;
  const bool csr_records = fused_scheme() && (persistent_launch() || plan_.gather_lanes > 1);
  sim::SlicedSpringLayout layout;
  const bool sliced =
      options_.sliced_springs && !csr_records &&
      sim::slice_spring_entries(c.offset.data(), c.fixed.data(), n_, options_.slice_window, *c.pool, layout);
  FMPC_CUDA_CHECK(
      incidence_.allocate(sliced ? static_cast<std::size_t>(layout.entries) : static_cast<std::size_t>(entries)),
      diagnostics, false);
  if (sliced) {
    FMPC_CUDA_CHECK(vertex_order_.upload(layout.vertex_order), diagnostics, false);
    FMPC_CUDA_CHECK(sliced_row_.upload(layout.row), diagnostics, false);
  }
  // The allocation's memset and the uploads ran on the legacy stream (upload, above): the records kernels on stream_
  // must not start before they end. Without this a late memset zeroed records on a GPU shared with other processes
  // (springs dropped: the volume-term box went non-finite; docs/performance.md, fifteenth run).
  FMPC_CUDA_CHECK(cudaDeviceSynchronize(), diagnostics, false);
  if (sliced) {
    model_.springs.sliced = {sliced_row_.data(), incidence_.data()};
    FMPC_CUDA_CHECK(launch_sliced_springs(model_.springs, vertex_order_.data(), n_, incidence_.data(), stream_),
                    diagnostics, false);
    model_.vertex_order = vertex_order_.data();
  } else {
    FMPC_CUDA_CHECK(launch_spring_incidence(model_.springs, entries, incidence_.data(), stream_), diagnostics, false);
    model_.springs.incidence = incidence_.data();
  }
  FMPC_CUDA_CHECK(cudaStreamSynchronize(stream_), diagnostics, false);
  return true;
}

template <typename Real>
bool GpuEngine<Real>::upload_elements(const ConcatenatedScenes& c, DiagnosticList& diagnostics) {
  const bool implicit = scenes_.front().integrator == sim::Integrator::ImplicitEuler;
  // A kind the registry says CUDA does not run with this integrator (element_kind_limits; runtime/scene/scene_run.cpp
  // sends such scenes to the CPU).
  if (const char* refusal = sim::cuda_refusal(sim::element_kind_limits(c.element_kind), implicit)) {
    diagnostics.error(scenes_.front().source_range, std::string("fem.element ") +
                                                        sim::element_kind_row(c.element_kind).keyword + " " + refusal +
                                                        "; use the CPU backend");
    return false;
  }
  const bool nodal_pass = kernels::element_kind_has_nodal_pass(c.element_kind);
  const std::size_t count = static_cast<std::size_t>(element_count_);
  const std::size_t node_entries = c.nodes.size();
  FMPC_CUDA_CHECK(nodes_.upload(c.nodes), diagnostics, false);
  FMPC_CUDA_CHECK(corner_offset_.upload(c.corner_offset), diagnostics, false);
  FMPC_CUDA_CHECK(corner_index_.upload(c.corner_index), diagnostics, false);
  FMPC_CUDA_CHECK(corner_slot_.upload(c.corner_slot), diagnostics, false);
  // The compact views (GpuOptions::compact_element_views): slots as byte ranks, Dm^-1 per shape where the mesh has
  // at most 256 (rest_inverse_ then holds the shapes' table), one value for arrays of equal entries.
  const bool compact = options_.compact_element_views;
  const HostArray<unsigned char> ranks = compact ? corner_ranks(c) : HostArray<unsigned char>{};
  if (!ranks.empty()) FMPC_CUDA_CHECK(corner_rank_.upload(ranks), diagnostics, false);
  const HostArray<Real> rest_inverse = convert<Real>(c.rest_inverse, *c.pool);
  HostArray<Real> table;
  HostArray<double> table_d;
  HostArray<unsigned char> shape, shape_d;
  const bool shapes = compact && rest_shapes(rest_inverse, table, shape);
  const bool shapes_d = compact && rest_shapes(c.rest_inverse, table_d, shape_d);
  FMPC_CUDA_CHECK(rest_inverse_.upload(shapes ? table : rest_inverse), diagnostics, false);
  FMPC_CUDA_CHECK(rest_inverse_d_.upload(shapes_d ? table_d : c.rest_inverse), diagnostics, false);
  if (shapes) FMPC_CUDA_CHECK(rest_shape_.upload(shape), diagnostics, false);
  if (shapes_d) FMPC_CUDA_CHECK(rest_shape_d_.upload(shape_d), diagnostics, false);
  const HostArray<Real> rest_volume = convert<Real>(c.rest_volume, *c.pool);
  FMPC_CUDA_CHECK(rest_volume_.upload(rest_volume), diagnostics, false);
  FMPC_CUDA_CHECK(rest_volume_d_.upload(c.rest_volume), diagnostics, false);
  FMPC_CUDA_CHECK(corner_force_.allocate(node_entries), diagnostics, false);
  model_.term_count = static_cast<int>(c.terms.size());
  model_.element_count = element_count_;
  elements_ = {};
  elements_.count = element_count_;
  elements_.term_count = model_.term_count;
  for (std::size_t t = 0; t < c.terms.size(); ++t) {
    const ConcatenatedScenes::Term& term = c.terms[t];
    DeviceTermArrays& arrays = term_arrays_[t];
    kernels::ElementTermView<Real>& view = model_.terms[t];
    kernels::ElementTermView<double>& view_d = elements_.terms[t];
    view = {};
    view_d = {};
    view.law = view_d.law = term.law;
    view.element = view_d.element = c.element_kind;
    view.count = view_d.count = element_count_;
    view.corners = view_d.corners = nodes_.data();
    view.corner_slot = view_d.corner_slot = corner_slot_.data();
    if (!ranks.empty()) {
      view.corner_rank = view_d.corner_rank = corner_rank_.data();
      view.corner_offset = view_d.corner_offset = corner_offset_.data();
    }
    view.rest_inverse = rest_inverse_.data();
    view.rest_shape = shapes ? rest_shape_.data() : nullptr;
    view.rest_volume = per_element_of(rest_volume, rest_volume_.data(), compact);
    view_d.rest_inverse = rest_inverse_d_.data();
    view_d.rest_shape = shapes_d ? rest_shape_d_.data() : nullptr;
    view_d.rest_volume = per_element_of(c.rest_volume, rest_volume_d_.data(), compact);
    // The arrays are uploaded even where the views hold one value: a replaced material (refresh_material) may vary.
    for (int p = 0; p < kernels::kMostLawParameters; ++p) {
      if (term.parameter[p].empty()) continue;
      const HostArray<Real> values = convert<Real>(term.parameter[p], *c.pool);
      FMPC_CUDA_CHECK(arrays.parameter[p].upload(values), diagnostics, false);
      FMPC_CUDA_CHECK(arrays.parameter_d[p].upload(term.parameter[p]), diagnostics, false);
      view.parameter[p] = per_element_of(values, arrays.parameter[p].data(), compact);
      view_d.parameter[p] = per_element_of(term.parameter[p], arrays.parameter_d[p].data(), compact);
    }
    if (!term.stiffness_damping.empty()) {
      const HostArray<Real> values = convert<Real>(term.stiffness_damping, *c.pool);
      FMPC_CUDA_CHECK(arrays.damping.upload(values), diagnostics, false);
      FMPC_CUDA_CHECK(arrays.damping_d.upload(term.stiffness_damping), diagnostics, false);
      view.stiffness_damping = per_element_of(values, arrays.damping.data(), compact);
      view_d.stiffness_damping = per_element_of(term.stiffness_damping, arrays.damping_d.data(), compact);
    }
    view.strain_table = view_d.strain_table = {nullptr, nullptr, 0};
    const sim::ElementTerm& own = scenes_.front().elements.terms[t];
    const int width = sim::point_state_width(own);
    if (width > 0) {
      // Zeros, then the history of a jump to the start positions (as the CPU engine): prony_constants at dt = 0.
      const int points = element_count_ * sim::points_per_element(c.element_kind);
      const std::size_t values = static_cast<std::size_t>(width) * static_cast<std::size_t>(points);
      FMPC_CUDA_CHECK(arrays.state.upload(HostArray<Real>(values, Real(0))), diagnostics, false);
      FMPC_CUDA_CHECK(arrays.checkpoint_state.upload(HostArray<Real>(values, Real(0))), diagnostics, false);
      view.state = {arrays.state.data(), width, points};
      view.prony = sim::prony_constants_in<Real>(term.prony, stability_.front().time_step, implicit);
      for (std::size_t i = 0; i < term.prony.size() && i < static_cast<std::size_t>(kernels::kMostPronyTerms); ++i) {
        if (term.prony[i].element_weight.empty()) continue;
        FMPC_CUDA_CHECK(arrays.prony_weight[i].upload(convert<Real>(term.prony[i].element_weight, *c.pool)),
                        diagnostics, false);
        view.prony_weight[i] = arrays.prony_weight[i].data();
      }
    }
    if (nodal_pass) {
      const std::size_t vertices = static_cast<std::size_t>(n_);
      FMPC_CUDA_CHECK(arrays.nodal_pressure.allocate(vertices), diagnostics, false);
      FMPC_CUDA_CHECK(arrays.nodal_dilatation.allocate(vertices), diagnostics, false);
      FMPC_CUDA_CHECK(arrays.nodal_pressure_d.allocate(vertices), diagnostics, false);
      FMPC_CUDA_CHECK(arrays.nodal_dilatation_d.allocate(vertices), diagnostics, false);
      view.nodal_pressure = model_.nodal_pressure[t] = arrays.nodal_pressure.data();
      view.nodal_dilatation = model_.nodal_dilatation[t] = arrays.nodal_dilatation.data();
      view_d.nodal_pressure = arrays.nodal_pressure_d.data();
      view_d.nodal_dilatation = arrays.nodal_dilatation_d.data();
    }
    if (implicit) {
      const std::size_t bytes = kernels::visit_element_term(c.element_kind, term.law, [](auto kind, auto element_law) {
        return sizeof(typename decltype(kind)::template Linearisation<decltype(element_law)>);
      });
      FMPC_CUDA_CHECK(arrays.linearisation.allocate(bytes * count), diagnostics, false);
      elements_.linearisation[t] = arrays.linearisation.data();
    }
  }
  model_.corners = {corner_offset_.data(), corner_index_.data(), corner_force_.data()};
  model_.corner_force = corner_force_.data();
  model_.vertex_count = n_;
  if (nodal_pass) FMPC_CUDA_CHECK(nodal_shares_d_.allocate(node_entries), diagnostics, false);
  if (implicit) {
    for (DeviceArray<double>* array : {&element_rhs_part_, &element_diagonal_part_, &element_product_})
      FMPC_CUDA_CHECK(array->allocate(3 * node_entries), diagnostics, false);
    elements_.rhs_part = element_rhs_part_.data();
    elements_.diagonal_part = element_diagonal_part_.data();
    elements_.product = element_product_.data();
  }
  return true;
}

template <typename Real>
bool GpuEngine<Real>::upload_probes(DiagnosticList& diagnostics) {
  std::vector<int> vertices, entry_scene;
  std::vector<double> start[3], base[3];
  std::vector<ProbeScene> probes;
  bool any_base = false;
  for (std::size_t s = 0; s < scenes_.size(); ++s) {
    const sim::SimulationSetup& setup = scenes_[s];
    if (!setup.probe) continue;
    const sim::ProbeLoad& probe = *setup.probe;
    const bool based = force_probe(setup) && !setup.external_forces.empty();
    any_base = any_base || based;
    probes.push_back(ProbeScene{probe.target[0], probe.target[1], probe.target[2], probe.ramp_time, probe.cycles,
                                stability_[s].time_step, static_cast<int>(probe.vertices.size()), force_probe(setup),
                                based});
    for (const auto v : probe.vertices) {
      vertices.push_back(vertex_begin_[s] + v);
      entry_scene.push_back(static_cast<int>(probes.size() - 1));
      const sim::Point3& point = sim::start_position(setup, static_cast<std::size_t>(v));
      for (std::size_t axis = 0; axis < 3; ++axis) {
        start[axis].push_back(point[axis]);
        base[axis].push_back(based ? setup.external_forces[static_cast<std::size_t>(v)][axis] : 0.0);
      }
    }
  }
  if (probes.empty()) return true;
  FMPC_CUDA_CHECK(probe_vertices_.upload(vertices), diagnostics, false);
  FMPC_CUDA_CHECK(probe_entry_scene_.upload(entry_scene), diagnostics, false);
  FMPC_CUDA_CHECK(probe_scenes_.upload(probes), diagnostics, false);
  DeviceArray<double>* start_arrays[3] = {&probe_start_x_, &probe_start_y_, &probe_start_z_};
  DeviceArray<double>* base_arrays[3] = {&probe_base_x_, &probe_base_y_, &probe_base_z_};
  for (std::size_t axis = 0; axis < 3; ++axis) {
    FMPC_CUDA_CHECK(start_arrays[axis]->upload(start[axis]), diagnostics, false);
    if (any_base) FMPC_CUDA_CHECK(base_arrays[axis]->upload(base[axis]), diagnostics, false);
  }
  FMPC_CUDA_CHECK(step_base_.allocate(1), diagnostics, false);
  // The persistent kernel applies each probe vertex's entry from the vertex's own thread; a vertex listed twice
  // (never from a scene file) keeps the per-step path.
  std::vector<int> entry_of(static_cast<std::size_t>(n_), -1);
  probe_vertices_unique_ = true;
  for (std::size_t i = 0; i < vertices.size(); ++i) {
    int& entry = entry_of[static_cast<std::size_t>(vertices[i])];
    probe_vertices_unique_ = probe_vertices_unique_ && entry < 0;
    entry = static_cast<int>(i);
  }
  if (probe_vertices_unique_) FMPC_CUDA_CHECK(probe_entry_.upload(entry_of), diagnostics, false);
  return true;
}

template <typename Real>
bool GpuEngine<Real>::plan_launches(const ConcatenatedScenes& c, DiagnosticList& diagnostics) {
  BatchShape batch;
  batch.kind = model_.kind;
  batch.double_precision = std::is_same_v<Real, double>;
  batch.fused_scheme = fused_scheme();
  batch.implicit_scheme = scheme() == sim::Integrator::ImplicitEuler;
  batch.strain_table = scenes_.front().strain_stiffness.has_value();
  batch.point_state = sim::has_point_state(scenes_.front().elements);
  batch.nodal_pass = element_count_ > 0 && kernels::element_kind_has_nodal_pass(c.element_kind);
  batch.element_kind_not_persistent = element_count_ > 0 && !kernels::element_kind_runs_persistent(c.element_kind);
  batch.probe_vertices_unique = probe_vertices_unique_;
  batch.vertex_count = n_;
  batch.element_count = element_count_;
  batch.element_nodes = static_cast<long long>(c.nodes.size());
  batch.scene_count = scenes_.size();
  batch.offset = c.offset.data();
  batch.neighbour = c.neighbour.data();
  batch.vertex_begin = c.vertex_begin;
  batch.element_begin = c.element_begin;
  DeviceLaunchLimits device;
  device.persistent_blocks = [&](GatherKind kind, long long shared_bytes) -> std::optional<int> {
    int blocks = 0;
    FMPC_CUDA_CHECK(persistent_euler_block_limit<Real>(kind, shared_bytes, blocks), diagnostics, std::nullopt);
    return blocks;
  };
  device.cluster_fits = [&](int blocks, int rows, long long shared_bytes) -> std::optional<bool> {
    bool fits = false;
    FMPC_CUDA_CHECK(cluster_euler_fits<Real>(blocks, rows, shared_bytes, fits), diagnostics, std::nullopt);
    return fits;
  };
  device.cg_persistent_blocks = [&]() -> std::optional<int> {
    int blocks = 0;
    FMPC_CUDA_CHECK(cg_persistent_block_limit<Real>(blocks), diagnostics, std::nullopt);
    return blocks;
  };
  device.cg_block_shared_limit = [&]() -> std::optional<long long> {
    long long bytes = 0;
    FMPC_CUDA_CHECK(cg_block_shared_limit<Real>(bytes), diagnostics, std::nullopt);
    return bytes;
  };
  std::optional<LaunchPlan> plan = gpu::plan_launches(batch, options_, device);
  if (!plan) return false;
  plan_ = std::move(*plan);
  if (plan_.grid_blocks > 0 && model_.kind == GatherKind::Springs) {
    FMPC_CUDA_CHECK(neighbour_block_offset_.upload(plan_.neighbour_offset), diagnostics, false);
    FMPC_CUDA_CHECK(neighbour_block_.upload(plan_.neighbour_block), diagnostics, false);
    FMPC_CUDA_CHECK(block_steps_done_.allocate(static_cast<std::size_t>(plan_.grid_blocks) * kBlockStepsStride),
                    diagnostics, false);
  }
  if (!plan_.cluster_blocks.empty())
    FMPC_CUDA_CHECK(cluster_blocks_array_.upload(plan_.cluster_blocks), diagnostics, false);
  if (!plan_.persistent()) return true;
  // The persistent checks' results (a slot per check of a launch) and, on the cooperative grid, a checkpoint slot
  // per check.
  const std::size_t slots = plan_.persistent_checks * plan_.check_slot_stride;
  FMPC_CUDA_CHECK(check_results_.allocate(slots), diagnostics, false);
  FMPC_CUDA_CHECK(check_results_host_.allocate(slots), diagnostics, false);
  if (plan_.persistent_checks > 1)
    for (DeviceArray<Real>* array : checkpoint_.arrays())
      FMPC_CUDA_CHECK(array->allocate(plan_.persistent_checks * static_cast<std::size_t>(n_)), diagnostics, false);
  return true;
}

template <typename Real>
PersistentChecks GpuEngine<Real>::persistent_checks() const {
  PersistentChecks c{};
  unsigned int* results = check_results_.data();
  c.first_non_finite = reinterpret_cast<int*>(results);
  if (element_count_ > 0) {
    c.nodes = inversion_nodes_;
    c.element_kind = inversion_kind_;
    c.element_count = element_count_;
    c.element_scene = scenes_.size() > 1 ? element_scene_.data() : nullptr;
    c.scene_count = static_cast<int>(scenes_.size());
    c.inverted_count = results + 1;
    c.inverted_first = reinterpret_cast<int*>(results + 1 + scenes_.size());
  }
  c.slot_stride = static_cast<int>(plan_.check_slot_stride);
  return c;
}

template <typename Real>
bool GpuEngine<Real>::upload_single_scene_features(DiagnosticList& diagnostics) {
  const sim::SimulationSetup& setup = scenes_.front();
  const auto count = static_cast<std::size_t>(n_);
  if (setup.strain_stiffness) {
    const sim::StrainStiffnessTable& table = *setup.strain_stiffness;
    FMPC_CUDA_CHECK(table_strain_.upload(table.strain), diagnostics, false);
    FMPC_CUDA_CHECK(table_modulus_.upload(table.modulus), diagnostics, false);
    FMPC_CUDA_CHECK(stiffness_per_modulus_.upload(table.stiffness_per_modulus), diagnostics, false);
    const kernels::StrainTableView view{table_strain_.data(), table_modulus_.data(),
                                        static_cast<int>(table.strain.size())};
    for (std::size_t t = 0; t < setup.elements.terms.size(); ++t) {
      if (!sim::reads_strain_table(setup.elements.terms[t])) continue;
      model_.terms[t].strain_table = view;
      elements_.terms[t].strain_table = view;
    }
  }
  if (setup.integrator == sim::Integrator::ImplicitEuler) {
    std::vector<double> rest(3 * count);
    for (std::size_t v = 0; v < count; ++v)
      for (std::size_t axis = 0; axis < 3; ++axis) rest[3 * v + axis] = setup.rest_positions[v][axis];
    FMPC_CUDA_CHECK(implicit_rest_.upload(rest), diagnostics, false);
    FMPC_CUDA_CHECK(implicit_blocks_.allocate(12 * setup.springs.size()), diagnostics, false);
    FMPC_CUDA_CHECK(implicit_diagonal_.allocate(count), diagnostics, false);
    for (DeviceArray<double>* array : {&implicit_jacobi_, &implicit_rhs_, &cg_x_, &cg_r_, &cg_z_, &cg_p_, &cg_ap_})
      FMPC_CUDA_CHECK(array->allocate(3 * count), diagnostics, false);
    FMPC_CUDA_CHECK(cg_scalars_.allocate(kDeferredSolves), diagnostics, false);
    FMPC_CUDA_CHECK(cg_scalars_host_.allocate(kDeferredSolves), diagnostics, false);
    FMPC_CUDA_CHECK(cg_partial_.allocate(4 * kEnergyBlocks), diagnostics, false);
    implicit_log_ = sim::ImplicitSolverLog(sim::ImplicitMethod::ConjugateGradient, setup.implicit.tolerance,
                                           sim::implicit_iteration_limit(setup));
  }
  return true;
}

#define FMPC_GPU_ENGINE_UPLOAD_MEMBERS(Real)                                                                      \
  template bool GpuEngine<Real>::upload(DiagnosticList& diagnostics);                                             \
  template bool GpuEngine<Real>::upload_spring_records(const ConcatenatedScenes& c, DiagnosticList& diagnostics); \
  template bool GpuEngine<Real>::upload_elements(const ConcatenatedScenes& c, DiagnosticList& diagnostics);       \
  template bool GpuEngine<Real>::upload_probes(DiagnosticList& diagnostics);                                      \
  template bool GpuEngine<Real>::plan_launches(const ConcatenatedScenes& c, DiagnosticList& diagnostics);         \
  template PersistentChecks GpuEngine<Real>::persistent_checks() const;                                           \
  template bool GpuEngine<Real>::upload_single_scene_features(DiagnosticList& diagnostics);
FMPC_GPU_ENGINE_UPLOAD_MEMBERS(float)
FMPC_GPU_ENGINE_UPLOAD_MEMBERS(double)
#undef FMPC_GPU_ENGINE_UPLOAD_MEMBERS

}  // namespace fmpc::gpu
