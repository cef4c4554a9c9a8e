#pragma once
// Device and page-locked host memory owned by objects (freed on destruction), the state and 3-vector bundles the
// engine's kernels read and write, and CUDA graphs destroyed with their owner. CUDA errors are returned, never thrown.
#include <cuda_runtime_api.h>

#include <cstddef>
#include <vector>

#include "runtime/gpu/gpu_launch.h"

namespace fmpc::gpu {

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
  // Copies `host` into the allocation as it is, on `stream` (its pointer, which launches and graphs hold, stays);
  // cudaErrorInvalidValue where the sizes differ.
  template <typename Allocator>
  cudaError_t overwrite(const std::vector<T, Allocator>& host, cudaStream_t stream) {
    if (host.size() != size_) return cudaErrorInvalidValue;
    if (size_ == 0) return cudaSuccess;
    return cudaMemcpyAsync(data_, host.data(), size_ * sizeof(T), cudaMemcpyHostToDevice, stream);
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

}  // namespace fmpc::gpu
