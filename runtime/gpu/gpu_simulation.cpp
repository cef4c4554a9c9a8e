#include "runtime/gpu/gpu_simulation.h"

#include <cuda_runtime_api.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include "runtime/gpu/gpu_launch.h"
#include "runtime/integrate/stepping_engine.h"
#include "runtime/integrate/worker_pool.h"
#include "runtime/springs/sliced_springs.h"

// Checks a CUDA call; on failure appends an error naming the call and CUDA's reason, and returns `failure` from
// the enclosing function. Never exits.
#define FMPC_CUDA_CHECK(call, diagnostics, failure)                                                   \
  do {                                                                                                \
    const cudaError_t fmpc_cuda_status = (call);                                                      \
    if (fmpc_cuda_status != cudaSuccess) {                                                            \
      (diagnostics)                                                                                   \
          .error(::fmpc::SourceRange{}, std::string("CUDA: ") + #call +                               \
                                            " failed: " + cudaGetErrorName(fmpc_cuda_status) + " (" + \
                                            cudaGetErrorString(fmpc_cuda_status) + ")");              \
      return failure;                                                                                 \
    }                                                                                                 \
  } while (false)

namespace fmpc::gpu {

namespace {

// Longer chunks replay the same graph several times: a graph's size (and its instantiation time) grows with its
// kernel count, while the launch overhead saved per step does not improve beyond a few hundred steps.
constexpr std::size_t kMaxStepsPerGraph = 256;

// A persistent launch on the cooperative grid takes a check per checkpoint slot that fits this (advance; the 20^3
// box's float state, 217 KiB, fits many), up to kMostPersistentChecks (4,096 steps at the 64 between checks).
constexpr std::size_t kPersistentCheckpointBytes = std::size_t{64} << 20;
constexpr std::size_t kMostPersistentChecks = 64;
// A persistent launch's most steps (about 3 s of the 20^3 box): longer stretches between checks run as several.
constexpr std::size_t kMostPersistentLaunchSteps = std::size_t{1} << 20;

// Page-locked staging for downloads (download_ranges): 4 MiB of float, 8 of double.
constexpr std::size_t kDownloadStagingEntries = std::size_t{1} << 20;

// Device memory owned by one object; freed on destruction.
template <typename T>
class DeviceArray {
 public:
  DeviceArray() = default;
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  ~DeviceArray() { release(); }
  template <typename Allocator>
  cudaError_t upload(const std::vector<T, Allocator>& host) {
    const cudaError_t status = allocate(host.size());
    if (status != cudaSuccess || size_ == 0) return status;
    return cudaMemcpy(data_, host.data(), size_ * sizeof(T), cudaMemcpyHostToDevice);
  }
  // Zero-filled.
  cudaError_t allocate(std::size_t size) {
    release();
    size_ = size;
    if (size_ == 0) return cudaSuccess;
    void* raw = nullptr;
    const cudaError_t status = cudaMalloc(&raw, size_ * sizeof(T));
    if (status != cudaSuccess) {
      size_ = 0;
      return status;
    }
    data_ = static_cast<T*>(raw);
    return cudaMemset(data_, 0, size_ * sizeof(T));
  }
  T* data() const { return data_; }
  std::size_t size() const { return size_; }

 private:
  void release() {
    if (data_ != nullptr) cudaFree(data_);
    data_ = nullptr;
    size_ = 0;
  }
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

// Page-locked host memory owned by one object (device-to-host copies into it are asynchronous); freed on destruction.
template <typename T>
class PinnedArray {
 public:
  PinnedArray() = default;
  PinnedArray(const PinnedArray&) = delete;
  PinnedArray& operator=(const PinnedArray&) = delete;
  ~PinnedArray() { release(); }
  cudaError_t allocate(std::size_t size) {
    release();
    if (size == 0) return cudaSuccess;
    void* raw = nullptr;
    const cudaError_t status = cudaMallocHost(&raw, size * sizeof(T));
    if (status != cudaSuccess) return status;
    data_ = static_cast<T*>(raw);
    size_ = size;
    return cudaSuccess;
  }
  T* data() const { return data_; }
  std::size_t size() const { return size_; }

 private:
  void release() {
    if (data_ != nullptr) cudaFreeHost(data_);
    data_ = nullptr;
    size_ = 0;
  }
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

template <typename Real>
struct DeviceVector3 {
  DeviceArray<Real> x, y, z;
  cudaError_t allocate(std::size_t n) {
    cudaError_t status = x.allocate(n);
    if (status == cudaSuccess) status = y.allocate(n);
    if (status == cudaSuccess) status = z.allocate(n);
    return status;
  }
  MutableVector3View<Real> view() const { return {x.data(), y.data(), z.data()}; }
};

template <typename Real>
struct DeviceState {
  DeviceArray<Real> x, y, z, vx, vy, vz;
  kernels::StateView<Real> view() const { return {x.data(), y.data(), z.data(), vx.data(), vy.data(), vz.data()}; }
  MutableStateView<Real> mutable_view() const {
    return {x.data(), y.data(), z.data(), vx.data(), vy.data(), vz.data()};
  }
  std::vector<DeviceArray<Real>*> arrays() { return {&x, &y, &z, &vx, &vy, &vz}; }
  std::vector<const DeviceArray<Real>*> arrays() const { return {&x, &y, &z, &vx, &vy, &vz}; }
};

// An instantiated CUDA graph, destroyed with its owner.
class GraphExecutable {
 public:
  explicit GraphExecutable(cudaGraphExec_t executable) : executable_(executable) {}
  GraphExecutable(const GraphExecutable&) = delete;
  GraphExecutable& operator=(const GraphExecutable&) = delete;
  ~GraphExecutable() {
    if (executable_ != nullptr) cudaGraphExecDestroy(executable_);
  }
  cudaGraphExec_t get() const { return executable_; }

 private:
  cudaGraphExec_t executable_;
};

template <typename Real>
cudaError_t copy_async(DeviceArray<Real>& to, const DeviceArray<Real>& from, cudaStream_t stream) {
  if (from.size() == 0) return cudaSuccess;
  return cudaMemcpyAsync(to.data(), from.data(), from.size() * sizeof(Real), cudaMemcpyDeviceToDevice, stream);
}

// Host arrays whose resize leaves trivial values uninitialised, so that the pool's workers touch their pages first:
// std::vector's zero fill ran on one thread, page faults included (creating the simulation of a 97M-spring box took
// 29.8 s on the H100 machine's 16 cores, most of it copying on one thread).
template <typename T>
struct UninitialisedAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = UninitialisedAllocator<U>;
  };
  UninitialisedAllocator() = default;
  template <typename U>
  UninitialisedAllocator(const UninitialisedAllocator<U>&) {}
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    if constexpr (sizeof...(Args) == 0)
      ::new (static_cast<void*>(p)) U;
    else
      ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
template <typename T>
using HostArray = std::vector<T, UninitialisedAllocator<T>>;

// The host-side concatenation of a batch (see gpu_launch.h): everything in double, converted on upload.
struct ConcatenatedScenes {
  std::vector<int> vertex_begin{0}, spring_begin{0}, element_begin{0};  // scene_count + 1 entries each
  HostArray<int> offset, spring, neighbour, first, second, vertex_scene;
  HostArray<double> rest_length, stiffness, damping, mass;
  HostArray<unsigned char> fixed;
  HostArray<double> rest[3], position[3], velocity[3], force[3];
  bool has_forces = false;
  bool has_damping = false;  // false: no scene has dashpots, and no damping array is uploaded
  // Tetrahedra (every scene's, for inversion counts) and, when the scenes have element terms, their geometry, the
  // corner CSR (each scene's corners point at its own elements) and each term's parameters and damping (the scenes
  // of a batch have the same terms: create() refuses others).
  HostArray<int> corners, element_scene, corner_offset, corner_index, corner_slot;
  HostArray<double> rest_inverse, rest_volume;
  struct Term {
    int law = 0;
    HostArray<double> parameter[kernels::kMostLawParameters];
    HostArray<double> stiffness_damping;  // empty: no scene damps this term
  };
  std::vector<Term> terms;
  bool has_elements = false;
  // The staging's threads, which also convert the arrays on upload (one pool, not one per array).
  std::unique_ptr<sim::WorkerPool> pool;
};

bool force_probe(const sim::SimulationSetup& setup) {
  return setup.probe && setup.probe->mode == sim::ProbeLoad::Mode::Force;
}

// out[at + i] = value(i) for i in [0, count), on the pool.
template <typename T, typename Value>
void fill_on_pool(sim::WorkerPool& pool, HostArray<T>& out, std::size_t at, std::size_t count, const Value& value) {
  T* to = out.data() + at;
  pool.run(
      count,
      [&](std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) to[i] = value(i);
      },
      1 << 16);
}

ConcatenatedScenes concatenate(const std::vector<sim::SimulationSetup>& scenes) {
  ConcatenatedScenes c;
  std::size_t vertices = 0, entries = 0, springs = 0, elements = 0, corners = 0;
  for (const auto& setup : scenes) {
    c.has_forces = c.has_forces || !setup.external_forces.empty() || force_probe(setup);
    c.has_damping = c.has_damping || !setup.springs.damping.empty();
    c.has_elements = c.has_elements || !setup.elements.empty();
    vertices += setup.rest_positions.size();
    entries += setup.springs.adjacency_spring.size();
    springs += setup.springs.size();
    elements += setup.tetrahedra.size();
    if (!setup.elements.empty()) corners += setup.elements.geometry.corner_index.size();
  }
  c.offset.reserve(vertices + 1);  // and the end offset, pushed last
  for (auto* array : {&c.offset, &c.vertex_scene}) array->resize(vertices);
  for (auto* array : {&c.spring, &c.neighbour}) array->resize(entries);
  for (auto* array : {&c.first, &c.second}) array->resize(springs);
  for (auto* array : {&c.rest_length, &c.stiffness}) array->resize(springs);
  if (c.has_damping) c.damping.resize(springs);
  c.mass.resize(vertices);
  c.fixed.resize(vertices);
  for (std::size_t axis = 0; axis < 3; ++axis) {
    for (auto* array : {&c.rest[axis], &c.position[axis], &c.velocity[axis]}) array->resize(vertices);
    if (c.has_forces) c.force[axis].resize(vertices);
  }
  c.corners.resize(4 * elements);
  c.element_scene.resize(elements);
  if (c.has_elements) {
    c.corner_offset.reserve(vertices + 1);
    c.corner_offset.resize(vertices);
    c.corner_index.resize(corners);
    c.corner_slot.resize(corners);
    c.rest_inverse.resize(9 * elements);
    c.rest_volume.resize(elements);
    const std::vector<sim::ElementTerm>& first = scenes.front().elements.terms;
    c.terms.resize(first.size());
    for (std::size_t t = 0; t < first.size(); ++t) {
      ConcatenatedScenes::Term& term = c.terms[t];
      term.law = first[t].law;
      for (int p = 0; p < kernels::kMostLawParameters; ++p)
        if (!first[t].parameter[p].empty()) term.parameter[p].resize(elements);
      bool damped = false;
      for (const auto& setup : scenes) damped = damped || !setup.elements.terms[t].stiffness_damping.empty();
      if (damped) term.stiffness_damping.resize(elements);
    }
  }
  c.pool = std::make_unique<sim::WorkerPool>(sim::resolve_thread_count(0, entries + 4 * elements + vertices));
  sim::WorkerPool& pool = *c.pool;
  int entry_base = 0, corner_base = 0;
  for (std::size_t s = 0; s < scenes.size(); ++s) {
    const sim::SimulationSetup& setup = scenes[s];
    const sim::SpringNetwork& net = setup.springs;
    const int vertex_base = c.vertex_begin.back(), spring_base = c.spring_begin.back();
    const int element_base = c.element_begin.back();
    const auto scene = static_cast<int>(s);
    const auto vb = static_cast<std::size_t>(vertex_base), sb = static_cast<std::size_t>(spring_base);
    const auto eb = static_cast<std::size_t>(element_base);
    const std::size_t n = setup.rest_positions.size(), m = setup.tetrahedra.size();
    fill_on_pool(pool, c.corners, 4 * eb, 4 * m,
                 [&](std::size_t i) { return vertex_base + setup.tetrahedra[i / 4][i % 4]; });
    fill_on_pool(pool, c.element_scene, eb, m, [&](std::size_t) { return scene; });
    if (!setup.elements.empty()) {
      const sim::ElementGeometry& field = setup.elements.geometry;
      const int corners_before = corner_base;
      const auto cbase = static_cast<std::size_t>(corner_base);
      fill_on_pool(pool, c.corner_offset, vb, n,
                   [&](std::size_t v) { return corners_before + field.corner_offset[v]; });
      fill_on_pool(pool, c.corner_index, cbase, field.corner_index.size(),
                   [&](std::size_t k) { return 4 * element_base + field.corner_index[k]; });
      fill_on_pool(pool, c.corner_slot, cbase, field.corner_slot.size(),
                   [&](std::size_t k) { return corners_before + field.corner_slot[k]; });
      corner_base += static_cast<int>(field.corner_index.size());
      fill_on_pool(pool, c.rest_inverse, 9 * eb, 9 * m, [&](std::size_t i) { return field.rest_inverse[i]; });
      fill_on_pool(pool, c.rest_volume, eb, m, [&](std::size_t e) { return field.rest_volume[e]; });
      const auto copy_or_zero = [&](HostArray<double>& to, const std::vector<double>& from) {
        fill_on_pool(pool, to, eb, m, [&](std::size_t e) { return from.empty() ? 0.0 : from[e]; });
      };
      for (std::size_t term = 0; term < c.terms.size(); ++term) {
        const sim::ElementTerm& own = setup.elements.terms[term];
        for (int p = 0; p < kernels::kMostLawParameters; ++p)
          if (!c.terms[term].parameter[p].empty()) copy_or_zero(c.terms[term].parameter[p], own.parameter[p]);
        if (!c.terms[term].stiffness_damping.empty()) copy_or_zero(c.terms[term].stiffness_damping, own.stiffness_damping);
      }
    }
    const int entries_before = entry_base;
    const auto entry_at = static_cast<std::size_t>(entry_base);
    fill_on_pool(pool, c.offset, vb, n, [&](std::size_t v) { return entries_before + net.adjacency_offset[v]; });
    fill_on_pool(pool, c.spring, entry_at, net.adjacency_spring.size(),
                 [&](std::size_t e) { return spring_base + net.adjacency_spring[e]; });
    sim::write_adjacency_neighbours(net, vertex_base, c.neighbour.data() + entry_at, pool);
    entry_base += static_cast<int>(net.adjacency_spring.size());
    fill_on_pool(pool, c.first, sb, net.size(), [&](std::size_t k) { return vertex_base + net.first[k]; });
    fill_on_pool(pool, c.second, sb, net.size(), [&](std::size_t k) { return vertex_base + net.second[k]; });
    fill_on_pool(pool, c.rest_length, sb, net.size(), [&](std::size_t k) { return net.rest_length[k]; });
    fill_on_pool(pool, c.stiffness, sb, net.size(), [&](std::size_t k) { return net.stiffness[k]; });
    if (c.has_damping)
      fill_on_pool(pool, c.damping, sb, net.size(),
                   [&](std::size_t k) { return net.damping.empty() ? 0.0 : net.damping[k]; });
    fill_on_pool(pool, c.mass, vb, n, [&](std::size_t v) { return setup.mass[v]; });
    // Held axes at the start (a displacement probe's vertices are held only after the initial velocities are taken,
    // as in the CPU backend), then the full mask.
    std::vector<unsigned char> fixed(n, 0);
    for (std::size_t v = 0; v < n && setup.fixed_axes.size() == n; ++v) fixed[v] = setup.fixed_axes[v];
    for (const auto v : setup.fixed_vertices) fixed[static_cast<std::size_t>(v)] = kernels::kAllAxesFixed;
    const std::vector<unsigned char> held = sim::held_axes(setup);
    fill_on_pool(pool, c.fixed, vb, n, [&](std::size_t v) { return held[v]; });
    const std::vector<sim::Point3>& start =
        setup.initial_positions.empty() ? setup.rest_positions : setup.initial_positions;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      fill_on_pool(pool, c.rest[axis], vb, n, [&](std::size_t v) { return setup.rest_positions[v][axis]; });
      fill_on_pool(pool, c.position[axis], vb, n, [&](std::size_t v) { return start[v][axis]; });
      // As the CPU backend: held axes start at rest.
      fill_on_pool(pool, c.velocity[axis], vb, n, [&](std::size_t v) {
        return setup.initial_velocities.empty() || kernels::axis_fixed(fixed[v], static_cast<int>(axis))
                   ? 0.0
                   : setup.initial_velocities[v][axis];
      });
      if (c.has_forces)
        fill_on_pool(pool, c.force[axis], vb, n, [&](std::size_t v) {
          return setup.external_forces.empty() ? 0.0 : setup.external_forces[v][axis];
        });
    }
    fill_on_pool(pool, c.vertex_scene, vb, n, [&](std::size_t) { return scene; });

    c.vertex_begin.push_back(vertex_base + static_cast<int>(n));
    c.spring_begin.push_back(spring_base + static_cast<int>(net.size()));
    c.element_begin.push_back(element_base + static_cast<int>(m));
  }
  c.offset.push_back(entry_base);
  if (c.has_elements) c.corner_offset.push_back(corner_base);
  return c;
}

// The gather a batch's scenes share (create() refuses batches that differ in it).
GatherKind gather_kind(const sim::SimulationSetup& setup) {
  if (setup.elements.empty()) return GatherKind::Springs;
  return setup.springs.size() > 0 ? GatherKind::SpringsAndElements : GatherKind::Elements;
}

// Whether two setups have the same element terms, law for law (their parameters may differ).
bool same_element_laws(const sim::SimulationSetup& a, const sim::SimulationSetup& b) {
  if (a.elements.terms.size() != b.elements.terms.size()) return false;
  for (std::size_t t = 0; t < a.elements.terms.size(); ++t)
    if (a.elements.terms[t].law != b.elements.terms[t].law) return false;
  return true;
}

template <typename Real, typename Allocator>
HostArray<Real> convert(const std::vector<double, Allocator>& values, sim::WorkerPool& pool) {
  HostArray<Real> out(values.size());
  fill_on_pool(pool, out, 0, values.size(), [&](std::size_t i) { return static_cast<Real>(values[i]); });
  return out;
}

// The first field in which `scene` differs from scene 0 among those a batch shares, or nullptr.
const char* shared_field_mismatch(const sim::SimulationSetup& scene, const sim::SimulationSetup& reference) {
  const bool springs = scene.springs.size() > 0, reference_springs = reference.springs.size() > 0;
  if (springs != reference_springs || (!springs && !same_element_laws(scene, reference))) return "force model";
  if (gather_kind(scene) != gather_kind(reference)) return "volume term (on in one scene, off in the other)";
  if (!same_element_laws(scene, reference)) return "element terms";
  if (scene.integrator != reference.integrator) return "integrator";
  if (scene.precision != reference.precision) return "precision";
  if (scene.law != reference.law) return "spring law";
  if (scene.law == kernels::SpringLaw::BasafaFarahmand &&
      (scene.basafa_k2_over_k1 != reference.basafa_k2_over_k1 || scene.basafa_xc != reference.basafa_xc)) {
    return "Basafa-Farahmand parameters";
  }
  if (scene.gravity != reference.gravity) return "gravity";
  if (scene.nodal_damping_gamma0 != reference.nodal_damping_gamma0 ||
      scene.nodal_damping_gamma1 != reference.nodal_damping_gamma1) {
    return "nodal damping";
  }
  if (scene.mass_damping != reference.mass_damping) return "mass damping (Rayleigh alpha)";
  if (scene.on_inversion != reference.on_inversion) return "on_inversion policy";
  return nullptr;
}

// The CUDA engine of a batch (runtime/integrate/stepping_engine.h): upload, launch choice, the integrators'
// enqueueing with persistent and graph launches, the checks' data and the checkpoint, read-back.
template <typename Real>
class GpuEngine final : public sim::SteppingEngine {
 public:
  GpuEngine(const std::vector<sim::SimulationSetup>& scenes, const std::vector<sim::StabilityReport>& stability,
            const GpuOptions& options)
      : scenes_(scenes), stability_(stability), options_(options) {}

  ~GpuEngine() override {
    graphs_.clear();
    if (stream_ != nullptr) cudaStreamDestroy(stream_);
  }

  bool upload(DiagnosticList& diagnostics) {
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
      FMPC_CUDA_CHECK(corners_.upload(c.corners), diagnostics, false);
      if (scenes_.size() > 1) FMPC_CUDA_CHECK(element_scene_.upload(c.element_scene), diagnostics, false);
      FMPC_CUDA_CHECK(inverted_count_.allocate(scenes_.size()), diagnostics, false);
      FMPC_CUDA_CHECK(inverted_first_.allocate(scenes_.size()), diagnostics, false);
    }
    if (c.has_elements && !upload_elements(c, diagnostics)) return false;

    if (!upload_probes(diagnostics) || !upload_single_scene_features(diagnostics)) return false;

    model_.kind = gather_kind(common);
    model_.element_blocks = options_.element_blocks_per_sm == 2 ? 2 : 3;
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
              static_cast<Real>(common.mass_damping)};
    step_ = {vertex_scene_.data(), scene_h_.data(), static_cast<Real>(scene_h.front())};
    if (!choose_launches(c, diagnostics) || !upload_spring_records(c, diagnostics)) return false;
    // cudaMemcpy from pageable memory and cudaMemset may still run on the legacy stream, which the non-blocking
    // stream_ does not wait for.
    FMPC_CUDA_CHECK(cudaDeviceSynchronize(), diagnostics, false);
    return synchronize(diagnostics);
  }

  // The springs' incidence records, where the stiffness stays fixed during the run (no strain table): in the sliced
  // layout for the kernels with one thread per vertex (kernels::SlicedSpringsView), else in CSR order for the
  // persistent kernels (cooperative or in clusters) and the kernels whose lanes share a vertex (gather_lanes > 1).
  // Only the one the launches use is built.
  bool upload_spring_records(const ConcatenatedScenes& c, DiagnosticList& diagnostics) {
    const int entries = c.offset.back();
    if (scenes_.front().strain_stiffness || entries == 0) return true;
    const bool csr_records = fused_scheme() && (persistent_launch() || gather_lanes_ > 1);
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

  // The element terms: the geometry and each term's parameters in Real for the element pass and in double for
  // implicit Euler and the energy sums, the corner CSR and the corner forces. The strain table (uploaded with the
  // single-scene features) is attached to the views of the terms whose law reads one afterwards.
  bool upload_elements(const ConcatenatedScenes& c, DiagnosticList& diagnostics) {
    const std::size_t count = static_cast<std::size_t>(element_count_);
    FMPC_CUDA_CHECK(corner_offset_.upload(c.corner_offset), diagnostics, false);
    FMPC_CUDA_CHECK(corner_index_.upload(c.corner_index), diagnostics, false);
    FMPC_CUDA_CHECK(corner_slot_.upload(c.corner_slot), diagnostics, false);
    FMPC_CUDA_CHECK(rest_inverse_.upload(convert<Real>(c.rest_inverse, *c.pool)), diagnostics, false);
    FMPC_CUDA_CHECK(rest_volume_.upload(convert<Real>(c.rest_volume, *c.pool)), diagnostics, false);
    FMPC_CUDA_CHECK(rest_inverse_d_.upload(c.rest_inverse), diagnostics, false);
    FMPC_CUDA_CHECK(rest_volume_d_.upload(c.rest_volume), diagnostics, false);
    FMPC_CUDA_CHECK(corner_force_.allocate(4 * count), diagnostics, false);
    const bool implicit = scenes_.front().integrator == sim::Integrator::ImplicitEuler;
    model_.term_count = static_cast<int>(c.terms.size());
    model_.element_count = element_count_;
    elements_ = {};
    elements_.count = element_count_;
    elements_.term_count = model_.term_count;
    elements_.corners = corners_.data();
    for (std::size_t t = 0; t < c.terms.size(); ++t) {
      const ConcatenatedScenes::Term& term = c.terms[t];
      DeviceTermArrays& arrays = term_arrays_[t];
      kernels::ElementTermView<Real>& view = model_.terms[t];
      kernels::ElementTermView<double>& view_d = elements_.terms[t];
      view = {};
      view_d = {};
      view.law = view_d.law = term.law;
      view.count = view_d.count = element_count_;
      view.corners = view_d.corners = corners_.data();
      view.corner_slot = view_d.corner_slot = corner_slot_.data();
      view.rest_inverse = rest_inverse_.data();
      view.rest_volume = rest_volume_.data();
      view_d.rest_inverse = rest_inverse_d_.data();
      view_d.rest_volume = rest_volume_d_.data();
      for (int p = 0; p < kernels::kMostLawParameters; ++p) {
        if (term.parameter[p].empty()) continue;
        FMPC_CUDA_CHECK(arrays.parameter[p].upload(convert<Real>(term.parameter[p], *c.pool)), diagnostics, false);
        FMPC_CUDA_CHECK(arrays.parameter_d[p].upload(term.parameter[p]), diagnostics, false);
        view.parameter[p] = arrays.parameter[p].data();
        view_d.parameter[p] = arrays.parameter_d[p].data();
      }
      if (!term.stiffness_damping.empty()) {
        FMPC_CUDA_CHECK(arrays.damping.upload(convert<Real>(term.stiffness_damping, *c.pool)), diagnostics, false);
        FMPC_CUDA_CHECK(arrays.damping_d.upload(term.stiffness_damping), diagnostics, false);
        view.stiffness_damping = arrays.damping.data();
        view_d.stiffness_damping = arrays.damping_d.data();
      }
      view.strain_table = view_d.strain_table = {nullptr, nullptr, 0};
      if (implicit) {
        const std::size_t bytes = kernels::visit_element_law(
            term.law, [](auto element_law) { return sizeof(typename decltype(element_law)::Linearisation); });
        FMPC_CUDA_CHECK(arrays.linearisation.allocate(bytes * count), diagnostics, false);
        elements_.linearisation[t] = arrays.linearisation.data();
      }
    }
    model_.corners = {corner_offset_.data(), corner_index_.data(), corner_force_.data()};
    model_.corner_force = corner_force_.data();
    if (implicit) {
      for (DeviceArray<double>* array : {&element_rhs_part_, &element_diagonal_part_, &element_product_})
        FMPC_CUDA_CHECK(array->allocate(12 * count), diagnostics, false);
      elements_.rhs_part = element_rhs_part_.data();
      elements_.diagonal_part = element_diagonal_part_.data();
      elements_.product = element_product_.data();
    }
    return true;
  }

  // Every scene's probe: its vertices (batch indices), start positions and own external forces, concatenated, and
  // one ProbeScene each. Nothing is allocated when no scene has a probe.
  bool upload_probes(DiagnosticList& diagnostics) {
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
      probes.push_back(ProbeScene{probe.target[0], probe.target[1], probe.target[2], probe.ramp_time,
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

  // The per-step fused kernel's lanes, and whether chunks of forward or semi-implicit Euler run as one persistent
  // launch each, on a cooperative grid (choose_grid_launch) or in thread-block clusters (choose_cluster_launch): no
  // strain table is looked up between steps, each probe vertex is listed once, and the batch fits one or the other.
  // Otherwise one launch per kernel: steps of meshes too large for either are long enough that launches cost little.
  bool choose_launches(const ConcatenatedScenes& c, DiagnosticList& diagnostics) {
    // The per-step kernel's lanes (GpuOptions::gather_lanes; automatic from what an H100 measured, docs/
    // performance.md, sixth run): springs on a 20^3 box (9,261 vertices) step in 7.4 us with 8 lanes, 9.5 with 4 and
    // 17.0 with 1, while the 240^3 box (14M vertices) ran at 166 steps/s with 4 lanes and 207 with 1. Lanes pay
    // while a thread per vertex cannot fill the GPU (about 2^18 resident threads), so the automatic choice is the
    // most of 8, 4, 2, 1 that keeps vertices x lanes within 2^18. Elements alone gather contiguous corner forces,
    // which lanes read coalesced: 4 lanes (the 120^3 FEM box: 812 steps/s against 769 with 1).
    if (valid_lanes(options_.gather_lanes)) {
      gather_lanes_ = options_.gather_lanes;
    } else if (model_.kind == GatherKind::Elements) {
      gather_lanes_ = 4;
    } else {
      gather_lanes_ = 8;
      while (gather_lanes_ > 1 && static_cast<long long>(n_) * gather_lanes_ > (1LL << 18)) gather_lanes_ /= 2;
    }
    while (gather_lanes_ > 1 && static_cast<long long>(n_) * gather_lanes_ > (1LL << 30)) gather_lanes_ /= 2;
    persistent_blocks_ = 0;
    cluster_blocks_ = 0;
    if (!options_.persistent || n_ <= 0 || scenes_.front().strain_stiffness || !probe_vertices_unique_) return true;
    if (!fused_scheme()) return true;
    // GpuOptions::persistent_kind: the preferred launch first, the other where it does not fit.
    const bool clusters_first = options_.persistent_kind == GpuOptions::PersistentKind::Clusters;
    if (clusters_first && !choose_cluster_launch(c, diagnostics)) return false;
    if (cluster_blocks_ == 0 && !choose_grid_launch(c, diagnostics)) return false;
    if (!clusters_first && persistent_blocks_ == 0 && !choose_cluster_launch(c, diagnostics)) return false;
    return !persistent_launch() || allocate_check_results(diagnostics);
  }

  // Whether the persistent chunks run as one cooperative grid (launch_persistent_euler): blocks of `rows` vertices
  // (GpuOptions::persistent_rows; automatically the fewest that keep every block resident, the 20^3 box on an H100:
  // 36 rows, 258 blocks), each with its records, terms, state and waited blocks in its shared memory. A setting that
  // does not fit takes the nearest that does, more rows first. Sets persistent_blocks_ (0: no grid fits) and uploads
  // the blocks' neighbours.
  bool choose_grid_launch(const ConcatenatedScenes& c, DiagnosticList& diagnostics) {
    const bool springs = model_.kind != GatherKind::Elements;
    int resident = 0;  // with the least shared memory: registers and threads bound it
    FMPC_CUDA_CHECK(persistent_euler_block_limit<Real>(model_.kind,
                                                 persistent_euler_shared_bytes<Real>(1, 0, 0), resident),
                    diagnostics, false);
    if (resident <= 0) return true;
    const auto blocks_of = [&](int rows) { return (static_cast<long long>(n_) + rows - 1) / rows; };
    const auto fewest_rows =
        static_cast<int>(std::min<long long>((n_ + resident - 1) / resident, kPersistentThreads + 1));
    const int wanted = std::max(fewest_rows, options_.persistent_rows > 0 ? options_.persistent_rows : fewest_rows);
    std::vector<int> candidates;
    for (int rows = wanted; rows <= kPersistentThreads; ++rows) candidates.push_back(rows);
    for (int rows = std::min(wanted, kPersistentThreads + 1) - 1; rows >= fewest_rows; --rows)
      candidates.push_back(rows);
    std::vector<int> offset, waited, owners;
    for (const int rows : candidates) {
      const long long blocks = blocks_of(rows);
      const auto entry_range = [&](long long b) {
        return std::pair<int, int>{c.offset[static_cast<std::size_t>(b * rows)],
                                   c.offset[static_cast<std::size_t>(std::min<long long>(n_, (b + 1) * rows))]};
      };
      int records = 0;
      for (long long b = 0; springs && b < blocks; ++b) {
        const auto [begin, end] = entry_range(b);
        records = std::max(records, end - begin);
      }
      int limit = 0;
      FMPC_CUDA_CHECK(persistent_euler_block_limit<Real>(model_.kind,
                                                   persistent_euler_shared_bytes<Real>(rows, records, 0), limit),
                      diagnostics, false);
      if (blocks > limit) continue;
      // Springs alone: the other blocks owning a neighbour of each block's vertices.
      int most_waited = 0;
      offset.assign(1, 0);
      waited.clear();
      for (long long b = 0; model_.kind == GatherKind::Springs && b < blocks; ++b) {
        const auto [begin, end] = entry_range(b);
        owners.clear();
        for (int e = begin; e < end; ++e) {
          const int owner = c.neighbour[static_cast<std::size_t>(e)] / rows;
          if (owner != b) owners.push_back(owner);
        }
        std::sort(owners.begin(), owners.end());
        owners.erase(std::unique(owners.begin(), owners.end()), owners.end());
        waited.insert(waited.end(), owners.begin(), owners.end());
        offset.push_back(static_cast<int>(waited.size()));
        most_waited = std::max(most_waited, static_cast<int>(owners.size()));
      }
      FMPC_CUDA_CHECK(
          persistent_euler_block_limit<Real>(model_.kind,
                                       persistent_euler_shared_bytes<Real>(rows, records, most_waited), limit),
          diagnostics, false);
      if (blocks > limit) continue;
      if (model_.kind == GatherKind::Springs) {
        FMPC_CUDA_CHECK(neighbour_block_offset_.upload(offset), diagnostics, false);
        FMPC_CUDA_CHECK(neighbour_block_.upload(waited), diagnostics, false);
        FMPC_CUDA_CHECK(block_steps_done_.allocate(static_cast<std::size_t>(blocks) * kBlockStepsStride), diagnostics,
                        false);
      }
      persistent_blocks_ = static_cast<int>(blocks);
      persistent_rows_ = rows;
      persistent_block_records_ = records;
      persistent_most_waited_ = most_waited;
      return true;
    }
    return true;
  }

  // The persistent checks' results (a slot per check of a launch: the first non-finite vertex, then per scene the
  // inversion count and first) and, on the cooperative grid, a checkpoint slot per check: persistent_checks_ checks per launch, as many checkpoints as fit in kPersistentCheckpointBytes, up to
  // kMostPersistentChecks (clusters, whose checks are their launches' ends: one).
  bool allocate_check_results(DiagnosticList& diagnostics) {
    check_slot_stride_ = 1 + (element_count_ > 0 ? 2 * scenes_.size() : 0);
    persistent_checks_ = 1;
    if (persistent_blocks_ > 0) {
      const std::size_t checkpoint_bytes = 6 * sizeof(Real) * static_cast<std::size_t>(n_);
      persistent_checks_ =
          std::clamp<std::size_t>(kPersistentCheckpointBytes / checkpoint_bytes, 1, kMostPersistentChecks);
    }
    FMPC_CUDA_CHECK(check_results_.allocate(persistent_checks_ * check_slot_stride_), diagnostics, false);
    FMPC_CUDA_CHECK(check_results_host_.allocate(persistent_checks_ * check_slot_stride_), diagnostics, false);
    if (persistent_checks_ > 1)
      for (DeviceArray<Real>* array : checkpoint_.arrays())
        FMPC_CUDA_CHECK(array->allocate(persistent_checks_ * static_cast<std::size_t>(n_)), diagnostics, false);
    return true;
  }

  // Whether the persistent chunks run in thread-block clusters (launch_cluster_euler; GpuOptions::persistent_kind):
  // springs alone, every scene within one cluster of at most kClusterBlocks blocks of kClusterRows rows. A scene alone
  // takes the fewest blocks, up to kClusterBlocks, that give each at most kClusterRows rows and, where the mesh allows,
  // at least 256 (the 20^3 box: 16 blocks of 608); a batch takes the fewest blocks per cluster its largest scene needs,
  // consecutive scenes packed into each cluster (1,000 demo patients: one block of 416 rows each). A block's published
  // state, window and records must fit its shared memory, with one cluster resident. Sets cluster_blocks_ (0: the
  // cooperative kernel decides) and uploads the blocks.
  bool choose_cluster_launch(const ConcatenatedScenes& c, DiagnosticList& diagnostics) {
    if (model_.kind != GatherKind::Springs || c.offset.back() == 0) return true;
    const std::size_t scenes = c.vertex_begin.size() - 1;
    int largest = 0;
    for (std::size_t s = 0; s < scenes; ++s) largest = std::max(largest, c.vertex_begin[s + 1] - c.vertex_begin[s]);
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
        while (end_scene < scenes && c.vertex_begin[end_scene + 1] - c.vertex_begin[s] <= per_cluster * rows)
          ++end_scene;
        const int first = c.vertex_begin[s], end = c.vertex_begin[end_scene];
        const int element_first = c.element_begin[s], elements = c.element_begin[end_scene] - element_first;
        for (int b = 0; b < per_cluster; ++b) {
          ClusterBlock block{};
          block.first_vertex = std::min(first + b * rows, end);
          block.end_vertex = std::min(block.first_vertex + rows, end);
          block.element_first = element_first + static_cast<int>(static_cast<long long>(elements) * b / per_cluster);
          block.element_end =
              element_first + static_cast<int>(static_cast<long long>(elements) * (b + 1) / per_cluster);
          // The window: from the least to the greatest of its vertices and their neighbours.
          int least = block.first_vertex, greatest = block.end_vertex - 1;
          const int entry_first = c.offset[static_cast<std::size_t>(block.first_vertex)];
          const int entry_end = c.offset[static_cast<std::size_t>(block.end_vertex)];
          for (int e = entry_first; e < entry_end; ++e) {
            least = std::min(least, c.neighbour[static_cast<std::size_t>(e)]);
            greatest = std::max(greatest, c.neighbour[static_cast<std::size_t>(e)]);
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
      bool fits = false;
      FMPC_CUDA_CHECK(cluster_euler_fits<Real>(per_cluster, rows, bytes, fits), diagnostics,
                      false);
      if (!fits) continue;
      FMPC_CUDA_CHECK(cluster_blocks_array_.upload(blocks), diagnostics, false);
      cluster_blocks_ = static_cast<int>(blocks.size());
      cluster_size_ = per_cluster;
      cluster_rows_ = rows;
      cluster_window_capacity_ = capacity;
      cluster_shared_bytes_ = static_cast<int>(bytes);
      return true;
    }
    return true;
  }

  PersistentChecks persistent_checks() const {
    PersistentChecks c{};
    unsigned int* results = check_results_.data();
    c.first_non_finite = reinterpret_cast<int*>(results);
    if (element_count_ > 0) {
      c.corners = corners_.data();
      c.element_count = element_count_;
      c.element_scene = scenes_.size() > 1 ? element_scene_.data() : nullptr;
      c.scene_count = static_cast<int>(scenes_.size());
      c.inverted_count = results + 1;
      c.inverted_first = reinterpret_cast<int*>(results + 1 + scenes_.size());
    }
    c.slot_stride = static_cast<int>(check_slot_stride_);
    return c;
  }

  // The strain table and implicit Euler's buffers (a batch of one scene only; create() refuses them in larger
  // batches). Nothing is allocated for what the scene does not use.
  bool upload_single_scene_features(DiagnosticList& diagnostics) {
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
      FMPC_CUDA_CHECK(cg_scalars_.allocate(1), diagnostics, false);
      FMPC_CUDA_CHECK(cg_partial_.allocate(2 * kEnergyBlocks), diagnostics, false);
    }
    return true;
  }

  const char* label() const override { return "GPU "; }
  std::size_t steps_taken() const override { return steps_taken_; }
  // A persistent launch on the cooperative grid takes persistent_checks_; otherwise one check per run.
  std::size_t checks_per_run() const override { return persistent_blocks_ > 0 ? persistent_checks_ : 1; }
  std::size_t most_steps_per_run() const override { return kMostPersistentLaunchSteps; }
  bool non_finite_is_exact() const override { return false; }
  sim::SimulationLaunches launches() const override { return {persistent_launch(), cluster_launch()}; }
  bool reduces_in_place() const override { return true; }

  bool run(const std::vector<std::size_t>& ends, DiagnosticList& diagnostics) override {
    run_ends_ = ends;
    selected_inner_ = false;
    return persistent_launch() ? run_persistent(ends, diagnostics)
                               : run_steps(ends.front() - steps_taken_, options_.use_graphs, diagnostics);
  }

  // A persistent launch's check before its last is only in its checkpoint slot: the checks read that slot, and a
  // checkpoint saved there is that slot (save_checkpoint).
  void select_check(std::size_t check) override {
    if (!persistent_launch()) return;
    steps_taken_ = run_ends_[check];
    checks_slot_ = static_cast<int>(check);
    checks_pending_ = true;
    selected_check_ = check;
    selected_inner_ = check + 1 < run_ends_.size();
  }

  std::vector<sim::Point3> positions(std::size_t scene, DiagnosticList& diagnostics) const override {
    const DeviceState<Real>& s = state_[current_];
    return download(scene, s.x, s.y, s.z, diagnostics);
  }
  std::vector<sim::Point3> velocities(std::size_t scene, DiagnosticList& diagnostics) const override {
    const DeviceState<Real>& s = state_[current_];
    return download(scene, s.vx, s.vy, s.vz, diagnostics);
  }

  bool scene_states(std::vector<std::vector<sim::Point3>>& positions, std::vector<std::vector<sim::Point3>>* velocities,
                    DiagnosticList& diagnostics) const override {
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

  std::vector<double> current_stiffness(std::size_t scene, DiagnosticList& diagnostics) const override {
    if (!scene_exists(scene, diagnostics)) return {};
    const auto begin = static_cast<std::size_t>(spring_begin_[scene]);
    const auto count = static_cast<std::size_t>(spring_begin_[scene + 1]) - begin;
    std::vector<Real> host(count);
    if (count > 0) {
      FMPC_CUDA_CHECK(cudaMemcpyAsync(host.data(), stiffness_.data() + begin, count * sizeof(Real),
                                      cudaMemcpyDeviceToHost, stream_),
                      diagnostics, {});
      if (!synchronize(diagnostics)) return {};
    }
    return std::vector<double>(host.begin(), host.end());
  }

  // Every sample of a probed scene reads it (100 per run): positions and velocities with one synchronisation into
  // buffers kept between readings, and without a strain table the stiffness as uploaded (rounded to Real), made once
  // for the scene instead of downloaded. Fresh buffers and the stiffness made per reading cost about 0.3 ms per
  // sample of the 20^3 box, mostly page faults (H100 machine).
  sim::ProbeReading probe_reading(std::size_t scene, DiagnosticList& diagnostics) const override {
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
    return sim::read_probe(setup, time, probe_state_[0], probe_state_[1], probe_stiffness_);
  }

  int implicit_max_iterations_used() const override { return implicit_iterations_max_; }
  bool persistent_launch() const { return persistent_blocks_ > 0 || cluster_blocks_ > 0; }
  bool cluster_launch() const { return cluster_blocks_ > 0; }

  std::optional<double> kinetic_energy(std::size_t scene, DiagnosticList& diagnostics) const override {
    return energy_sum(EnergyTerm::Kinetic, vertex_begin_.at(scene), vertex_begin_.at(scene + 1), diagnostics);
  }
  std::optional<double> largest_displacement(std::size_t scene, DiagnosticList& diagnostics) const override {
    const StartPositions start{start_x_.data(), start_y_.data(), start_z_.data()};
    FMPC_CUDA_CHECK(launch_largest_displacement(state_[current_].view(), start, vertex_begin_.at(scene),
                                                vertex_begin_.at(scene + 1), energy_partial_.data(),
                                                energy_result_.data(), stream_),
                    diagnostics, std::nullopt);
    return download_result(diagnostics);
  }
  std::optional<double> elastic_energy(std::size_t scene, DiagnosticList& diagnostics) const override {
    const auto springs =
        energy_sum(EnergyTerm::SpringPotential, spring_begin_.at(scene), spring_begin_.at(scene + 1), diagnostics);
    if (!springs) return std::nullopt;
    // The terms' energies in list order, as the host's element_elastic_energy adds them.
    double elements = 0.0;
    for (int term = 0; term < elements_.term_count && elements_.count > 0; ++term) {
      const auto energy = energy_sum(EnergyTerm::ElementPotential, element_begin_.at(scene),
                                     element_begin_.at(scene + 1), diagnostics, term);
      if (!energy) return std::nullopt;
      elements += *energy;
    }
    return *springs + elements;
  }
  std::optional<double> potential_energy(std::size_t scene, DiagnosticList& diagnostics) const override {
    const auto elastic = elastic_energy(scene, diagnostics);
    if (!elastic) return std::nullopt;
    const auto loads =
        energy_sum(EnergyTerm::LoadPotential, vertex_begin_.at(scene), vertex_begin_.at(scene + 1), diagnostics);
    if (!loads) return std::nullopt;
    return *elastic + *loads;
  }

 private:
  bool synchronize(DiagnosticList& diagnostics) const {
    FMPC_CUDA_CHECK(cudaStreamSynchronize(stream_), diagnostics, false);
    return true;
  }

  sim::Integrator scheme() const { return scenes_.front().integrator; }
  // Forward or semi-implicit Euler: one fused kernel per step from state buffer `current_` into the other.
  bool fused_scheme() const {
    return scheme() == sim::Integrator::ForwardEuler || scheme() == sim::Integrator::SemiImplicitEuler;
  }

  // Inverted elements per scene now: counts and each scene's smallest inverted element (local index, -1: none).
  bool count_inverted(std::vector<unsigned int>& counts, std::vector<int>& firsts, DiagnosticList& diagnostics) override {
    const std::size_t scenes = scenes_.size();
    if (checks_pending_) {
      // The persistent kernel counted at the state now held.
      if (!synchronize(diagnostics)) return false;
      checks_pending_ = false;
      const unsigned int* results = check_results_host_.data() + checks_slot_ * check_slot_stride_;
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
    FMPC_CUDA_CHECK(
        launch_count_inverted(corners_.data(), element_count_, scenes > 1 ? element_scene_.data() : nullptr,
                              state_[current_].view(), inverted_count_.data(), inverted_first_.data(), stream_),
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

  // Enqueues `count` steps on the stream (directly or while capturing); `parity` is the Euler state buffer read
  // first and is updated to the one holding the result. Around each step, as the CPU backend: the probe before it,
  // the strain table's lookup, the step, the probe after it.
  bool enqueue_steps(std::size_t count, int& parity, DiagnosticList& diagnostics) {
    // Forward and semi-implicit Euler apply the probe entries from the vertices' own threads (FusedStepArguments::
    // probe_entry) after each step and before the next: one probe launch before the first step instead of two per step.
    const bool fused_probes = fused_scheme() && probe_scenes_.size() > 0 && probe_vertices_unique_;
    for (std::size_t i = 0; i < count; ++i) {
      const int offset = static_cast<int>(i);
      if ((!fused_probes || i == 0) && !enqueue_probe(offset, true, state_[parity], diagnostics)) return false;
      if (!enqueue_strain_lookup(state_[parity], diagnostics)) return false;
      switch (scheme()) {
        case sim::Integrator::ForwardEuler:
        case sim::Integrator::SemiImplicitEuler: {
          FMPC_CUDA_CHECK(launch_element_forces(model_, state_[parity].view(), stream_), diagnostics, false);
          FusedStepArguments<Real> a = fused_arguments();
          a.in = state_[parity].view();
          a.out = state_[1 - parity].mutable_view();
          a.lanes = gather_lanes_;
          if (fused_probes) {
            a.probe = probe_arguments(state_[1 - parity]);
            a.probe_entry = probe_entry_.data();
            a.probe_offset = offset;
            a.probe_next = i + 1 < count;
          }
          FMPC_CUDA_CHECK(launch_fused_step(a, stream_), diagnostics, false);
          parity = 1 - parity;
          break;
        }
        case sim::Integrator::VelocityVerlet:
          // a(x0, v0) once, after the first step's probe and lookup (run_steps keeps that step out of graphs).
          if (!have_acceleration_) {
            FMPC_CUDA_CHECK(launch_element_forces(model_, state_[0].view(), stream_), diagnostics, false);
            FMPC_CUDA_CHECK(launch_acceleration(verlet_arguments(), stream_), diagnostics, false);
            have_acceleration_ = true;
          }
          FMPC_CUDA_CHECK(launch_verlet_drift(verlet_arguments(), stream_), diagnostics, false);
          {
            // The kick gathers at the drifted positions with the velocity predictor.
            const DeviceState<Real>& state = state_[0];
            const kernels::StateView<Real> drifted{state.x.data(),      state.y.data(),      state.z.data(),
                                                   predicted_.x.data(), predicted_.y.data(), predicted_.z.data()};
            FMPC_CUDA_CHECK(launch_element_forces(model_, drifted, stream_), diagnostics, false);
          }
          FMPC_CUDA_CHECK(launch_verlet_kick(verlet_arguments(), stream_), diagnostics, false);
          break;
        case sim::Integrator::RungeKutta4: {
          const RungeKutta4Arguments<Real> a = runge_kutta4_arguments();
          for (int stage = 0; stage < 4; ++stage) {
            const kernels::StateView<Real> at =
                stage == 0 ? state_[0].view()
                           : kernels::StateView<Real>{a.stage_position[stage].x, a.stage_position[stage].y,
                                                      a.stage_position[stage].z, a.stage_velocity[stage].x,
                                                      a.stage_velocity[stage].y, a.stage_velocity[stage].z};
            FMPC_CUDA_CHECK(launch_element_forces(model_, at, stream_), diagnostics, false);
            FMPC_CUDA_CHECK(launch_runge_kutta4_stage(a, stage, stream_), diagnostics, false);
          }
          break;
        }
        case sim::Integrator::ImplicitEuler:
          if (!implicit_solve(diagnostics)) return false;
          break;
      }
      if (!fused_probes && !enqueue_probe(offset, false, state_[parity], diagnostics)) return false;
    }
    return true;
  }

  bool enqueue_probe(int offset, bool before_step, const DeviceState<Real>& state, DiagnosticList& diagnostics) {
    if (probe_scenes_.size() == 0) return true;
    FMPC_CUDA_CHECK(launch_apply_probe(probe_arguments(state), offset, before_step, stream_), diagnostics, false);
    return true;
  }

  ProbeArguments<Real> probe_arguments(const DeviceState<Real>& state) const {
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

  bool enqueue_strain_lookup(const DeviceState<Real>& state, DiagnosticList& diagnostics) {
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

  // The probe kernels' time origin for the chunk about to be enqueued or replayed.
  bool set_step_base(DiagnosticList& diagnostics) {
    if (probe_scenes_.size() == 0) return true;
    step_base_host_ = steps_taken_;
    FMPC_CUDA_CHECK(
        cudaMemcpyAsync(step_base_.data(), &step_base_host_, sizeof step_base_host_, cudaMemcpyHostToDevice, stream_),
        diagnostics, false);
    return true;
  }

  ImplicitArguments<Real> implicit_arguments() {
    ImplicitArguments<Real> a{};
    a.model = model_;
    a.elements = elements_;
    a.loads = loads_;
    a.state = state_[0].mutable_view();
    a.first = first_.data();
    a.second = second_.data();
    a.rest_length = energy_rest_length_.data();
    a.mass = energy_mass_.data();
    a.rest_position = implicit_rest_.data();
    // The CPU backend steps with h rounded to Real and widened again; so does this.
    a.h = static_cast<double>(static_cast<Real>(stability_.front().time_step));
    a.vertex_count = n_;
    a.spring_count = spring_begin_.back();
    a.blocks = implicit_blocks_.data();
    a.diagonal = implicit_diagonal_.data();
    a.inverse_jacobi = implicit_jacobi_.data();
    a.rhs = implicit_rhs_.data();
    a.x = cg_x_.data();
    a.r = cg_r_.data();
    a.z = cg_z_.data();
    a.p = cg_p_.data();
    a.ap = cg_ap_.data();
    a.scalars = cg_scalars_.data();
    a.partial = cg_partial_.data();
    return a;
  }

  bool read_cg_scalars(ConjugateGradientScalars& scalars, DiagnosticList& diagnostics) {
    FMPC_CUDA_CHECK(cudaMemcpyAsync(&scalars, cg_scalars_.data(), sizeof scalars, cudaMemcpyDeviceToHost, stream_),
                    diagnostics, false);
    return synchronize(diagnostics);
  }

  // One implicit Euler step: assemble, then Eigen's preconditioned conjugate gradient (same iteration, same
  // stopping rule, same warning as the CPU backend), then v += dv, x += h v. The host reads |r|^2 once per
  // iteration, so implicit steps are never captured into graphs.
  bool implicit_solve(DiagnosticList& diagnostics) {
    const ImplicitArguments<Real> a = implicit_arguments();
    FMPC_CUDA_CHECK(launch_implicit_assemble(a, stream_), diagnostics, false);
    FMPC_CUDA_CHECK(launch_cg_start(a, stream_), diagnostics, false);
    ConjugateGradientScalars scalars{};
    if (!read_cg_scalars(scalars, diagnostics)) return false;
    // As the CPU backend: a right-hand side this small means the system is at rest to double precision.
    if (std::sqrt(scalars.rhs_norm2) < 1e-150) return true;
    const sim::ImplicitSolverOptions& options = scenes_.front().implicit;
    const double threshold =
        std::max(options.tolerance * options.tolerance * scalars.rhs_norm2, std::numeric_limits<double>::min());
    double residual = scalars.rhs_norm2;
    int iterations = 0;
    if (residual >= threshold) {
      const int limit = sim::implicit_iteration_limit(scenes_.front());
      while (iterations < limit) {
        FMPC_CUDA_CHECK(launch_cg_iteration(a, stream_), diagnostics, false);
        if (!read_cg_scalars(scalars, diagnostics)) return false;
        residual = scalars.rr;
        if (residual < threshold) break;
        FMPC_CUDA_CHECK(launch_cg_direction(a, stream_), diagnostics, false);
        ++iterations;
      }
    }
    implicit_iterations_max_ = std::max(implicit_iterations_max_, iterations);
    const double error = std::sqrt(residual / scalars.rhs_norm2);
    if (!(error <= options.tolerance) && !cg_warning_given_) {
      cg_warning_given_ = true;
      diagnostics.warning(scenes_.front().source_range, "cg-not-converged",
                          sim::cg_stopped_message(steps_taken_ + 1, iterations, error, options.tolerance));
    }
    FMPC_CUDA_CHECK(launch_implicit_finish(a, stream_), diagnostics, false);
    return true;
  }

  VerletArguments<Real> verlet_arguments() const {
    return {model_, loads_, state_[0].mutable_view(), acceleration_.view(), predicted_.view(), n_, step_};
  }

  RungeKutta4Arguments<Real> runge_kutta4_arguments() const {
    RungeKutta4Arguments<Real> a{};
    a.model = model_;
    a.loads = loads_;
    a.state = state_[0].mutable_view();
    a.stage_position[1] = stage_position_a_.view();
    a.stage_position[2] = stage_position_b_.view();
    a.stage_position[3] = stage_position_a_.view();
    for (std::size_t s = 1; s < 4; ++s) a.stage_velocity[s] = stage_velocity_[s - 1].view();
    for (std::size_t s = 0; s < 3; ++s) a.stage_acceleration[s] = stage_acceleration_[s].view();
    a.vertex_count = n_;
    a.step = step_;
    return a;
  }

  bool run_steps(std::size_t count, bool allow_graph, DiagnosticList& diagnostics) {
    checks_pending_ = false;
    if (count == 0 || n_ == 0) {
      steps_taken_ += count;
      return true;
    }
    if (persistent_launch()) return run_persistent({steps_taken_ + count}, diagnostics);
    // Velocity Verlet's first step computes a(x0, v0) and implicit Euler reads the residual every CG iteration:
    // those steps are enqueued directly, never captured.
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

  // Forward or semi-implicit Euler's arguments but the state buffers and the lanes.
  FusedStepArguments<Real> fused_arguments() const {
    FusedStepArguments<Real> a{};
    a.model = model_;
    a.loads = loads_;
    a.vertex_count = n_;
    a.scheme = scheme() == sim::Integrator::ForwardEuler ? FusedScheme::ForwardEuler : FusedScheme::SemiImplicitEuler;
    a.step = step_;
    return a;
  }

  // Persistent launches from the state held through the checks after `ends` (steps_taken_ after each, increasing;
  // at most persistent_checks_ of them, one in clusters): one launch, or where a single check is more than
  // kMostPersistentLaunchSteps away, launches without checks up to the last. Where the state held is the checkpoint
  // it goes to slot 0, the state of each check but the last to the slot after it (advance); the checks' results are
  // downloaded.
  bool run_persistent(const std::vector<std::size_t>& ends, DiagnosticList& diagnostics) {
    while (ends.back() - steps_taken_ > kMostPersistentLaunchSteps) {
      if (!launch_persistent(kMostPersistentLaunchSteps, {}, diagnostics)) return false;
    }
    std::vector<std::size_t> counts(ends.size());
    for (std::size_t check = 0; check < ends.size(); ++check) counts[check] = ends[check] - steps_taken_;
    if (!launch_persistent(counts.back(), counts, diagnostics)) return false;
    FMPC_CUDA_CHECK(cudaMemcpyAsync(check_results_host_.data(), check_results_.data(),
                                    ends.size() * check_slot_stride_ * sizeof(unsigned int), cudaMemcpyDeviceToHost,
                                    stream_),
                    diagnostics, false);
    checks_slot_ = static_cast<int>(ends.size()) - 1;
    checks_pending_ = true;
    return true;
  }

  // One persistent launch of `count` steps with checks after checks[j] of them (the last `count`; none: no checks).
  bool launch_persistent(std::size_t count, const std::vector<std::size_t>& checks, DiagnosticList& diagnostics) {
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
    a.blocks = persistent_blocks_;
    a.rows = persistent_rows_;
    if (!checks.empty()) a.checks = persistent_checks();
    a.check_count = std::max(1, static_cast<int>(checks.size()));
    a.first_check = checks.empty() ? static_cast<int>(count) : static_cast<int>(checks.front());
    a.check_every = checks.size() > 2 ? static_cast<int>(checks[1] - checks[0]) : 0;
    a.checkpoints = checkpoint_.mutable_view();
    a.checkpoint_stride = static_cast<long long>(n_);
    a.store_start = checkpoint_in_state_;
    a.block_records = persistent_block_records_;
    a.most_neighbour_blocks = persistent_most_waited_;
    a.neighbours = {neighbour_block_offset_.data(), neighbour_block_.data(), block_steps_done_.data()};
    if (cluster_blocks_ > 0) {
      const ClusterEulerArguments<Real> cluster{a,
                                                cluster_blocks_array_.data(),
                                                cluster_blocks_,
                                                cluster_size_,
                                                cluster_rows_,
                                                cluster_window_capacity_,
                                                cluster_shared_bytes_};
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

  // Replays `count` steps from a graph captured on first use (one per length and starting Euler buffer).
  bool launch_graph(std::size_t count, DiagnosticList& diagnostics) {
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

  bool capture(std::size_t count, cudaGraphExec_t& executable, DiagnosticList& diagnostics) {
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

  bool save_checkpoint(DiagnosticList& diagnostics) override {
    checkpoint_step_ = steps_taken_;
    checkpoint_has_acceleration_ = have_acceleration_;
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
    if (scheme() == sim::Integrator::VelocityVerlet) {
      FMPC_CUDA_CHECK(copy_async(checkpoint_acceleration_.x, acceleration_.x, stream_), diagnostics, false);
      FMPC_CUDA_CHECK(copy_async(checkpoint_acceleration_.y, acceleration_.y, stream_), diagnostics, false);
      FMPC_CUDA_CHECK(copy_async(checkpoint_acceleration_.z, acceleration_.z, stream_), diagnostics, false);
    }
    return true;
  }

  bool restore_checkpoint(DiagnosticList& diagnostics) override {
    checks_pending_ = false;
    selected_inner_ = false;
    if (checkpoint_in_state_) {
      steps_taken_ = checkpoint_step_;
      have_acceleration_ = checkpoint_has_acceleration_;
      return true;
    }
    if (!copy_state(state_[current_].mutable_view(), read_only(checkpoint_slot(checkpoint_slot_)), diagnostics))
      return false;
    if (scheme() == sim::Integrator::VelocityVerlet) {
      FMPC_CUDA_CHECK(copy_async(acceleration_.x, checkpoint_acceleration_.x, stream_), diagnostics, false);
      FMPC_CUDA_CHECK(copy_async(acceleration_.y, checkpoint_acceleration_.y, stream_), diagnostics, false);
      FMPC_CUDA_CHECK(copy_async(acceleration_.z, checkpoint_acceleration_.z, stream_), diagnostics, false);
    }
    steps_taken_ = checkpoint_step_;
    have_acceleration_ = checkpoint_has_acceleration_;
    return true;
  }

  // Checkpoint slot `slot` (several on the cooperative grid: allocate_check_results).
  MutableStateView<Real> checkpoint_slot(int slot) const {
    return offset_state(checkpoint_.mutable_view(), static_cast<long long>(slot) * n_);
  }

  // The n_ vertices' state copied from `from` to `to` on the stream.
  bool copy_state(const MutableStateView<Real>& to, const kernels::StateView<Real>& from, DiagnosticList& diagnostics) {
    Real* const targets[6] = {to.x, to.y, to.z, to.vx, to.vy, to.vz};
    const Real* const sources[6] = {from.x, from.y, from.z, from.vx, from.vy, from.vz};
    if (n_ == 0) return true;
    for (int i = 0; i < 6; ++i)
      FMPC_CUDA_CHECK(cudaMemcpyAsync(targets[i], sources[i], static_cast<std::size_t>(n_) * sizeof(Real),
                                      cudaMemcpyDeviceToDevice, stream_),
                      diagnostics, false);
    return true;
  }

  // The smallest vertex index with a non-finite position or velocity, n_ when there is none.
  std::optional<int> first_non_finite_vertex(DiagnosticList& diagnostics) override {
    if (checks_pending_) {
      if (!synchronize(diagnostics)) return std::nullopt;
      return static_cast<int>(check_results_host_.data()[checks_slot_ * check_slot_stride_]);
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

  bool scene_exists(std::size_t scene, DiagnosticList& diagnostics) const {
    if (scene < scenes_.size()) return true;
    diagnostics.error(SourceRange{}, "scene " + std::to_string(scene) + " does not exist; the batch has " +
                                         std::to_string(scenes_.size()));
    return false;
  }

  std::vector<sim::Point3> download(std::size_t scene, const DeviceArray<Real>& x, const DeviceArray<Real>& y,
                                    const DeviceArray<Real>& z, DiagnosticList& diagnostics) const {
    if (!scene_exists(scene, diagnostics)) return {};
    const auto begin = static_cast<std::size_t>(vertex_begin_[scene]);
    return download_range(begin, static_cast<std::size_t>(vertex_begin_[scene + 1]) - begin, x, y, z, diagnostics);
  }

  std::vector<sim::Point3> download_range(std::size_t begin, std::size_t count, const DeviceArray<Real>& x,
                                          const DeviceArray<Real>& y, const DeviceArray<Real>& z,
                                          DiagnosticList& diagnostics) const {
    std::vector<std::vector<sim::Point3>> out;
    if (!download_ranges(begin, count, {{&x, &y, &z}}, out, diagnostics)) return {};
    return std::move(out.front());
  }

  // Entries [begin, begin + count) of each triple of arrays (x, y, z) as points into out[t] (resized, so a buffer
  // kept between calls is not allocated again); false after a device error (reported). Through page-locked staging
  // of kDownloadStagingEntries Reals, one synchronisation per piece that fills it (a sample of the 20^3 box's
  // positions and velocities is one), where copies into pageable memory each wait for the stream.
  bool download_ranges(std::size_t begin, std::size_t count,
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

  // energy_result_ (a reduction's), through page-locked memory: every sample reads three (largest displacement,
  // kinetic and elastic energy), and a copy into pageable memory waits on its own.
  std::optional<double> download_result(DiagnosticList& diagnostics) const {
    if (result_host_.size() == 0) FMPC_CUDA_CHECK(result_host_.allocate(1), diagnostics, std::nullopt);
    FMPC_CUDA_CHECK(cudaMemcpyAsync(result_host_.data(), energy_result_.data(), sizeof(double), cudaMemcpyDeviceToHost,
                                    stream_),
                    diagnostics, std::nullopt);
    if (!synchronize(diagnostics)) return std::nullopt;
    return *result_host_.data();
  }

  // The sum of `term` over [begin, end); ElementPotential's of element term `element_term`.
  std::optional<double> energy_sum(EnergyTerm term, int begin, int end, DiagnosticList& diagnostics,
                                   int element_term = 0) const {
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
      a.element_corners = corners_.data();
    }
    if (common.strain_stiffness) {
      a.table = {table_strain_.data(), table_modulus_.data(), static_cast<int>(table_strain_.size())};
      a.stiffness_per_modulus = stiffness_per_modulus_.data();
    }
    FMPC_CUDA_CHECK(launch_energy_sum(a, term, begin, end, energy_partial_.data(), energy_result_.data(), stream_),
                    diagnostics, std::nullopt);
    return download_result(diagnostics);
  }

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
  int persistent_blocks_ = 0;  // > 0: run_steps uses launch_persistent_euler with this many blocks
  int persistent_rows_ = 0;
  int persistent_block_records_ = 0;  // the most CSR entries of a persistent block
  int persistent_most_waited_ = 0;    // the most blocks a persistent block waits for (springs alone)
  DeviceArray<int> neighbour_block_offset_, neighbour_block_;  // BlockNeighbours
  DeviceArray<unsigned> block_steps_done_;
  // > 0: the persistent chunks run in clusters (choose_cluster_launch), this many blocks in all.
  int cluster_blocks_ = 0;
  int cluster_size_ = 0;  // blocks per cluster
  int cluster_rows_ = 0;
  int cluster_window_capacity_ = 0;
  int cluster_shared_bytes_ = 0;
  DeviceArray<ClusterBlock> cluster_blocks_array_;
  int gather_lanes_ = 1;                     // the per-step fused kernel's threads per vertex
  // PersistentChecks' results (persistent runs): a slot of check_slot_stride_ per check of a launch.
  DeviceArray<unsigned int> check_results_;
  PinnedArray<unsigned int> check_results_host_;
  std::size_t check_slot_stride_ = 1;  // PersistentChecks::slot_stride
  std::size_t persistent_checks_ = 1;  // the most checks of one persistent launch (allocate_check_results)
  int checks_slot_ = 0;                // the check whose results are pending
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
  DeviceArray<ConjugateGradientScalars> cg_scalars_;
  unsigned long long step_base_host_ = 0;
  int implicit_iterations_max_ = 0;
  bool cg_warning_given_ = false;
  DeviceState<Real> state_[2];
  // The state at the last check (checkpoint_step_): slot checkpoint_slot_ of checkpoint_ (checkpoint_slot), which
  // has persistent_checks_ slots on the cooperative grid.
  DeviceState<Real> checkpoint_;
  int checkpoint_slot_ = 0;
  DeviceVector3<Real> acceleration_, predicted_, checkpoint_acceleration_;
  DeviceVector3<Real> stage_position_a_, stage_position_b_, stage_velocity_[3], stage_acceleration_[3];
  ForceModelView<Real> model_{};
  ImplicitElements elements_{};
  std::vector<int> element_begin_;
  int element_count_ = 0;
  DeviceArray<int> corners_, element_scene_, corner_offset_, corner_index_, corner_slot_, inverted_first_;
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
    DeviceArray<unsigned char> linearisation;
  };
  DeviceArray<Real> rest_inverse_, rest_volume_;
  DeviceArray<double> rest_inverse_d_, rest_volume_d_;
  DeviceTermArrays term_arrays_[kMostElementTerms];
  DeviceArray<kernels::CornerForce<Real>> corner_force_;
  DeviceArray<double> element_rhs_part_, element_diagonal_part_, element_product_;
  kernels::VertexLoads<Real> loads_{};
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

// What a batch of several scenes cannot share is refused before the device is touched, never silently ignored.
const char* single_scene_feature(const sim::SimulationSetup& setup) {
  if (setup.integrator == sim::Integrator::ImplicitEuler) {
    return "implicit Euler runs one scene at a time on the GPU (its conjugate gradient solves one system); run the "
           "scene as a simulation of its own";
  }
  if (setup.strain_stiffness) {
    return "a scene with table-driven stiffness k(strain) runs on its own on the GPU; run it as a simulation of its "
           "own";
  }
  return nullptr;
}

}  // namespace

bool cuda_device_available(std::string& description) {
  int count = 0;
  const cudaError_t status = cudaGetDeviceCount(&count);
  if (status != cudaSuccess) {
    description = std::string("no usable CUDA device: ") + cudaGetErrorString(status);
    return false;
  }
  if (count == 0) {
    description = "no CUDA device";
    return false;
  }
  cudaDeviceProp properties{};
  if (cudaGetDeviceProperties(&properties, 0) != cudaSuccess) {
    description = "CUDA device 0 cannot be queried";
    return false;
  }
  description = properties.name;
  return true;
}

bool batch_accepts(const std::vector<sim::SimulationSetup>& scenes, std::size_t s, DiagnosticList& diagnostics) {
  const char* feature = scenes.size() > 1 ? single_scene_feature(scenes[s]) : nullptr;
  if (feature != nullptr) {
    diagnostics.error(SourceRange{}, "scene " + std::to_string(s) + ": " + feature);
    return false;
  }
  if (const char* field = shared_field_mismatch(scenes[s], scenes.front())) {
    diagnostics.error(SourceRange{}, "scene " + std::to_string(s) + " differs from scene 0 in its " + field +
                                         "; the scenes of one GPU batch share it: run it in another batch");
    return false;
  }
  return true;
}

std::unique_ptr<sim::SteppingEngine> create_engine(const std::vector<sim::SimulationSetup>& scenes,
                                                   const std::vector<sim::StabilityReport>& stability,
                                                   const GpuOptions& options, DiagnosticList& diagnostics) {
  std::size_t vertices = 0, entries = 0;
  for (const sim::SimulationSetup& setup : scenes) {
    vertices += setup.rest_positions.size();
    entries += setup.springs.adjacency_spring.size();
  }
  const auto limit = static_cast<std::size_t>(std::numeric_limits<int>::max() - 1);
  if (vertices > limit || entries > limit) {
    diagnostics.error(SourceRange{}, "the GPU backend indexes vertices and springs with int; " +
                                         std::to_string(vertices) + " vertices and " + std::to_string(entries) +
                                         " spring ends are too many: split the batch");
    return nullptr;
  }
  if (scenes.front().precision == sim::Precision::Float) {
    auto engine = std::make_unique<GpuEngine<float>>(scenes, stability, options);
    if (!engine->upload(diagnostics)) return nullptr;
    return engine;
  }
  auto engine = std::make_unique<GpuEngine<double>>(scenes, stability, options);
  if (!engine->upload(diagnostics)) return nullptr;
  return engine;
}

}  // namespace fmpc::gpu
