#include "runtime/gpu/gpu_simulation.h"

#include <cuda_runtime_api.h>

#include <cmath>
#include <limits>
#include <sstream>

#include "runtime/gpu/gpu_launch.h"

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

// Device memory owned by one object; freed on destruction.
template <typename T>
class DeviceArray {
 public:
  DeviceArray() = default;
  DeviceArray(const DeviceArray&) = delete;
  DeviceArray& operator=(const DeviceArray&) = delete;
  ~DeviceArray() {
    if (data_ != nullptr) cudaFree(data_);
  }
  cudaError_t upload(const std::vector<T>& host) {
    if (data_ != nullptr) cudaFree(data_);
    data_ = nullptr;
    size_ = host.size();
    if (size_ == 0) return cudaSuccess;
    void* raw = nullptr;
    const cudaError_t status = cudaMalloc(&raw, size_ * sizeof(T));
    if (status != cudaSuccess) return status;
    data_ = static_cast<T*>(raw);
    return cudaMemcpy(data_, host.data(), size_ * sizeof(T), cudaMemcpyHostToDevice);
  }
  cudaError_t download(std::vector<T>& host) const {
    host.resize(size_);
    if (size_ == 0) return cudaSuccess;
    return cudaMemcpy(host.data(), data_, size_ * sizeof(T), cudaMemcpyDeviceToHost);
  }
  T* data() const { return data_; }

 private:
  T* data_ = nullptr;
  std::size_t size_ = 0;
};

template <typename Real>
struct DeviceState {
  DeviceArray<Real> x, y, z, vx, vy, vz;
  kernels::StateView<Real> view() const { return {x.data(), y.data(), z.data(), vx.data(), vy.data(), vz.data()}; }
  MutableStateView<Real> mutable_view() const {
    return {x.data(), y.data(), z.data(), vx.data(), vy.data(), vz.data()};
  }
};

template <typename Real>
std::vector<Real> convert(const std::vector<double>& values) {
  std::vector<Real> out(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) out[i] = static_cast<Real>(values[i]);
  return out;
}

template <typename Real>
std::vector<Real> component(const std::vector<sim::Point3>& points, std::size_t axis) {
  std::vector<Real> out(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) out[i] = static_cast<Real>(points[i][axis]);
  return out;
}

template <typename Real>
class GpuSimulationImpl final : public GpuSimulation {
 public:
  GpuSimulationImpl(const sim::SimulationSetup& setup, const sim::StabilityReport& stability)
      : setup_(setup), stability_(stability), n_(static_cast<int>(setup.rest_positions.size())) {}

  ~GpuSimulationImpl() override {
    if (stream_ != nullptr) cudaStreamDestroy(stream_);
  }

  bool upload(DiagnosticList& diagnostics) {
    const sim::SpringNetwork& net = setup_.springs;
    FMPC_CUDA_CHECK(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking), diagnostics, false);
    FMPC_CUDA_CHECK(offset_.upload(net.adjacency_offset), diagnostics, false);
    FMPC_CUDA_CHECK(spring_.upload(net.adjacency_spring), diagnostics, false);
    FMPC_CUDA_CHECK(neighbour_.upload(net.adjacency_neighbour), diagnostics, false);
    FMPC_CUDA_CHECK(rest_length_.upload(convert<Real>(net.rest_length)), diagnostics, false);
    FMPC_CUDA_CHECK(stiffness_.upload(convert<Real>(net.stiffness)), diagnostics, false);
    FMPC_CUDA_CHECK(damping_.upload(convert<Real>(net.damping)), diagnostics, false);
    FMPC_CUDA_CHECK(mass_.upload(convert<Real>(setup_.mass)), diagnostics, false);
    std::vector<unsigned char> fixed(setup_.rest_positions.size(), 0);
    for (const auto v : setup_.fixed_vertices) fixed[static_cast<std::size_t>(v)] = 1;
    FMPC_CUDA_CHECK(fixed_.upload(fixed), diagnostics, false);
    FMPC_CUDA_CHECK(rest_x_.upload(component<Real>(setup_.rest_positions, 0)), diagnostics, false);
    FMPC_CUDA_CHECK(rest_y_.upload(component<Real>(setup_.rest_positions, 1)), diagnostics, false);
    FMPC_CUDA_CHECK(rest_z_.upload(component<Real>(setup_.rest_positions, 2)), diagnostics, false);
    if (!setup_.external_forces.empty()) {
      FMPC_CUDA_CHECK(force_x_.upload(component<Real>(setup_.external_forces, 0)), diagnostics, false);
      FMPC_CUDA_CHECK(force_y_.upload(component<Real>(setup_.external_forces, 1)), diagnostics, false);
      FMPC_CUDA_CHECK(force_z_.upload(component<Real>(setup_.external_forces, 2)), diagnostics, false);
    }
    const std::vector<sim::Point3>& start =
        setup_.initial_positions.empty() ? setup_.rest_positions : setup_.initial_positions;
    std::vector<sim::Point3> velocity = setup_.initial_velocities.empty()
                                            ? std::vector<sim::Point3>(start.size(), sim::Point3{0.0, 0.0, 0.0})
                                            : setup_.initial_velocities;
    for (const auto v : setup_.fixed_vertices) velocity[static_cast<std::size_t>(v)] = {0.0, 0.0, 0.0};
    for (DeviceState<Real>* state : {&state_[0], &state_[1]}) {
      FMPC_CUDA_CHECK(state->x.upload(component<Real>(start, 0)), diagnostics, false);
      FMPC_CUDA_CHECK(state->y.upload(component<Real>(start, 1)), diagnostics, false);
      FMPC_CUDA_CHECK(state->z.upload(component<Real>(start, 2)), diagnostics, false);
      FMPC_CUDA_CHECK(state->vx.upload(component<Real>(velocity, 0)), diagnostics, false);
      FMPC_CUDA_CHECK(state->vy.upload(component<Real>(velocity, 1)), diagnostics, false);
      FMPC_CUDA_CHECK(state->vz.upload(component<Real>(velocity, 2)), diagnostics, false);
    }
    FMPC_CUDA_CHECK(first_non_finite_.upload(std::vector<int>{n_}), diagnostics, false);

    arguments_.network = {
        offset_.data(),
        spring_.data(),
        neighbour_.data(),
        rest_length_.data(),
        stiffness_.data(),
        damping_.data(),
        {setup_.law, static_cast<Real>(setup_.basafa_k2_over_k1), static_cast<Real>(setup_.basafa_xc)}};
    arguments_.loads = {mass_.data(),
                        fixed_.data(),
                        rest_x_.data(),
                        rest_y_.data(),
                        rest_z_.data(),
                        force_x_.data(),
                        force_y_.data(),
                        force_z_.data(),
                        static_cast<Real>(setup_.gravity[0]),
                        static_cast<Real>(setup_.gravity[1]),
                        static_cast<Real>(setup_.gravity[2]),
                        static_cast<Real>(setup_.nodal_damping_gamma0),
                        static_cast<Real>(setup_.nodal_damping_gamma1)};
    arguments_.vertex_count = n_;
    arguments_.scheme =
        setup_.integrator == sim::Integrator::ForwardEuler ? FusedScheme::ForwardEuler : FusedScheme::SemiImplicitEuler;
    arguments_.h = static_cast<Real>(stability_.time_step);
    return true;
  }

  bool advance(std::size_t steps, DiagnosticList& diagnostics, std::size_t check_every) override {
    if (failed_) return false;
    const std::size_t interval = check_every == 0 ? steps : check_every;
    for (std::size_t i = 0; i < steps; ++i) {
      arguments_.in = state_[current_].view();
      arguments_.out = state_[1 - current_].mutable_view();
      FMPC_CUDA_CHECK(launch_fused_step(arguments_, stream_), diagnostics, false);
      current_ = 1 - current_;
      ++steps_taken_;
      if ((i + 1) % interval == 0 || i + 1 == steps) {
        if (!check_finite(diagnostics)) return false;
      }
    }
    return true;
  }

  std::size_t steps_taken() const override { return steps_taken_; }
  const sim::StabilityReport& stability() const override { return stability_; }

  std::vector<sim::Point3> positions(DiagnosticList& diagnostics) const override {
    return download(state_[current_].x, state_[current_].y, state_[current_].z, diagnostics);
  }
  std::vector<sim::Point3> velocities(DiagnosticList& diagnostics) const override {
    return download(state_[current_].vx, state_[current_].vy, state_[current_].vz, diagnostics);
  }

 private:
  std::vector<sim::Point3> download(const DeviceArray<Real>& x, const DeviceArray<Real>& y, const DeviceArray<Real>& z,
                                    DiagnosticList& diagnostics) const {
    std::vector<Real> hx, hy, hz;
    FMPC_CUDA_CHECK(cudaStreamSynchronize(stream_), diagnostics, {});
    FMPC_CUDA_CHECK(x.download(hx), diagnostics, {});
    FMPC_CUDA_CHECK(y.download(hy), diagnostics, {});
    FMPC_CUDA_CHECK(z.download(hz), diagnostics, {});
    std::vector<sim::Point3> out(hx.size());
    for (std::size_t i = 0; i < out.size(); ++i) {
      out[i] = {static_cast<double>(hx[i]), static_cast<double>(hy[i]), static_cast<double>(hz[i])};
    }
    return out;
  }

  bool check_finite(DiagnosticList& diagnostics) {
    FMPC_CUDA_CHECK(launch_find_non_finite(state_[current_].view(), n_, first_non_finite_.data(), stream_), diagnostics,
                    false);
    std::vector<int> first;
    FMPC_CUDA_CHECK(cudaStreamSynchronize(stream_), diagnostics, false);
    FMPC_CUDA_CHECK(first_non_finite_.download(first), diagnostics, false);
    if (first.empty() || first[0] >= n_) return true;
    failed_ = true;
    const auto vertex = static_cast<std::size_t>(first[0]);
    const std::vector<sim::Point3> points = positions(diagnostics);
    // The most strained spring at the vertex, as the CPU backend reports it.
    const sim::SpringNetwork& net = setup_.springs;
    int culprit = -1;
    double worst = -1.0;
    for (auto e = net.adjacency_offset[vertex]; e < net.adjacency_offset[vertex + 1]; ++e) {
      const auto s = static_cast<std::size_t>(net.adjacency_spring[static_cast<std::size_t>(e)]);
      const double length = sim::distance(points[static_cast<std::size_t>(net.first[s])],
                                          points[static_cast<std::size_t>(net.second[s])]);
      const double strain = std::isfinite(length) ? std::abs(length - net.rest_length[s]) / net.rest_length[s]
                                                  : std::numeric_limits<double>::infinity();
      if (strain > worst) {
        worst = strain;
        culprit = static_cast<int>(s);
      }
    }
    std::ostringstream message;
    message << "the GPU simulation became non-finite by step " << steps_taken_ << ": vertex " << vertex
            << " has a NaN or infinite position or velocity";
    if (culprit >= 0) message << "; its most strained spring is " << culprit;
    message << "; lower dt, raise damping, or check the loads";
    diagnostics.error(SourceRange{}, message.str());
    return false;
  }

  const sim::SimulationSetup setup_;
  sim::StabilityReport stability_;
  int n_;
  cudaStream_t stream_ = nullptr;
  DeviceArray<int> offset_, spring_, neighbour_, first_non_finite_;
  DeviceArray<Real> rest_length_, stiffness_, damping_, mass_, rest_x_, rest_y_, rest_z_, force_x_, force_y_, force_z_;
  DeviceArray<unsigned char> fixed_;
  DeviceState<Real> state_[2];
  int current_ = 0;
  FusedStepArguments<Real> arguments_{};
  std::size_t steps_taken_ = 0;
  bool failed_ = false;
};

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

std::unique_ptr<GpuSimulation> GpuSimulation::create(const sim::SimulationSetup& setup, DiagnosticList& diagnostics) {
  if (setup.integrator != sim::Integrator::SemiImplicitEuler && setup.integrator != sim::Integrator::ForwardEuler) {
    diagnostics.error(SourceRange{}, std::string(sim::to_string(setup.integrator)) +
                                         " is not available on the GPU yet (forward and semi-implicit Euler are); "
                                         "use the CPU backend");
    return nullptr;
  }
  if (setup.rest_positions.size() > static_cast<std::size_t>(std::numeric_limits<int>::max() - 1)) {
    diagnostics.error(SourceRange{}, "the GPU backend indexes vertices with int; the mesh is too large");
    return nullptr;
  }
  const auto stability = sim::check_stability(setup, diagnostics);  // validates the setup first
  if (!stability) return nullptr;
  if (setup.precision == sim::Precision::Float) {
    auto simulation = std::make_unique<GpuSimulationImpl<float>>(setup, *stability);
    if (!simulation->upload(diagnostics)) return nullptr;
    return simulation;
  }
  auto simulation = std::make_unique<GpuSimulationImpl<double>>(setup, *stability);
  if (!simulation->upload(diagnostics)) return nullptr;
  return simulation;
}

}  // namespace fmpc::gpu
